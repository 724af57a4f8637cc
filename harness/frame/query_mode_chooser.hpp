#pragma once
// Which of the tracer's query modes a batch uses (issue 18, item 2; used by the reference's waves,
// reference_wavefront.cpp). The modes gave the same hits bit for bit on every ray checked
// (tests/test_reference_bits.cpp: the reference's own rays on four scenes, and its sums with each mode
// pinned), so the choice changes the caller's speed, not its results, and may follow timings. Which
// mode is fastest depends on the scene and on the rays' coherence, which falls with every bounce (the
// reference's photons start Z-ordered and close together; after a refraction through a mesh they
// scatter), and on `bunny` it changed from run to run (bench/bench_reference.cpp). So each thread
// times its own batches, per kind of batch (the closest-hit queries of a wave's first, second, third
// and later segments, and the visibility queries), and uses the mode with the lowest recent time per
// ray. It tries every mode at first and each other mode in turn now and then (one batch in
// kExploreEvery), so that a change of the machine's or the rays' behaviour is seen. One chooser per
// thread: it is not thread-safe.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>

#include <caustics/frame/ray_tracer.hpp>

namespace caustics {

class QueryModeChooser {
public:
    static constexpr int kLastHitKind = 3;                 // closest hits of segments 0, 1, 2 and 3+
    static constexpr int kVisibility = kLastHitKind + 1;   // visibility queries
    static constexpr int kKinds = kVisibility + 1;
    static constexpr std::size_t kMinRays = 64;    // smaller batches are neither timed nor explored
    static constexpr int kWarmUp = 2;              // timed batches per mode before the choice starts
    static constexpr unsigned kExploreEvery = 32;  // one batch in this many tries another mode
    static constexpr double kKeep = 0.75;          // the mode in use: weight of its previous average

    static int hit_kind(int segment) { return std::clamp(segment, 0, kLastHitKind); }

    // The mode of the next batch of `rays` queries of `kind`.
    QueryMode pick(int kind, std::size_t rays) {
        Kind& k = kinds_[static_cast<std::size_t>(kind)];
        if (rays < kMinRays) return fastest(k);
        for (int m = 0; m < kQueryModes; ++m)
            if (k.samples[static_cast<std::size_t>(m)] < kWarmUp) return static_cast<QueryMode>(m);
        const QueryMode best = fastest(k);
        if (++k.decisions % kExploreEvery != 0) return best;
        // The other modes in turn (by their own number, so that none is skipped when the best changes).
        do k.explore = (k.explore + 1) % kQueryModes;
        while (static_cast<QueryMode>(k.explore) == best);
        return static_cast<QueryMode>(k.explore);
    }

    // The mode a batch of `kind` would use now, outside the turns of trying the others.
    QueryMode current(int kind) const { return fastest(kinds_[static_cast<std::size_t>(kind)]); }

    // A batch of `rays` queries took `seconds` in `mode`. The mode in use keeps a running average; a
    // mode tried now and then is judged by its latest batch (its older ones may be long out of date):
    // if that batch was fast only by chance, the mode becomes the one in use and its average shows it.
    void record(int kind, QueryMode mode, std::size_t rays, double seconds) {
        if (rays < kMinRays) return;
        Kind& k = kinds_[static_cast<std::size_t>(kind)];
        const std::size_t m = static_cast<std::size_t>(mode);
        const double per_ray = seconds / static_cast<double>(rays);
        const bool in_use = k.samples[m] >= kWarmUp && fastest(k) == mode;
        k.per_ray[m] = in_use ? kKeep * k.per_ray[m] + (1.0 - kKeep) * per_ray : per_ray;
        if (k.samples[m] < kWarmUp) ++k.samples[m];
    }

    // Runs query(mode) for a batch of `rays` of `kind`: in `pinned` where that is set, else in the
    // chosen mode, timed.
    template <class Query>
    void run(int kind, std::size_t rays, const std::optional<QueryMode>& pinned, Query&& query) {
        if (pinned) return query(*pinned);
        const QueryMode mode = pick(kind, rays);
        if (rays < kMinRays) return query(mode);
        const auto start = std::chrono::steady_clock::now();
        query(mode);
        record(kind, mode, rays, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }

private:
    struct Kind {
        std::array<double, kQueryModes> per_ray{};   // recent seconds per ray
        std::array<int, kQueryModes> samples{};      // timed batches, up to kWarmUp
        unsigned decisions = 0;
        int explore = 0;                             // the mode tried last
    };
    // The mode with the lowest time per ray; before any timing, 16-ray packets (the tracer's default).
    static QueryMode fastest(const Kind& k) {
        int best = static_cast<int>(QueryMode::Packet16);
        for (int m = 0; m < kQueryModes; ++m) {
            const std::size_t i = static_cast<std::size_t>(m), b = static_cast<std::size_t>(best);
            if (k.samples[i] > 0 && (k.samples[b] == 0 || k.per_ray[i] < k.per_ray[b])) best = m;
        }
        return static_cast<QueryMode>(best);
    }
    std::array<Kind, kKinds> kinds_{};
};

}  // namespace caustics
