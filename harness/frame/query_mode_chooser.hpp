#pragma once
// Which of the tracer's query modes a batch uses (issue 18, item 2; used by the reference's waves,
// reference_wavefront.cpp). Every QueryMode returns the same hits bit for bit (ray_tracer.hpp), so the
// choice changes the caller's speed, never its results: it may follow timings. Which mode is fastest
// depends on the scene and on the rays' coherence, which falls with every bounce (the reference's
// photons start Z-ordered and close together; after a refraction through a mesh they scatter), and on
// `bunny` it changed from run to run (bench/bench_reference.cpp). So each thread times its own
// batches, per kind of batch (the closest-hit queries of a wave's first, second, third and later
// segments, and the visibility queries), and uses the mode with the lowest recent time per ray, trying
// every mode at first and the others now and then (one batch in kExploreEvery), so that a change of
// the machine's or the rays' behaviour is seen. One chooser per thread: it is not thread-safe.
#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>

#include <caustics/frame/ray_tracer.hpp>

namespace caustics {

class QueryModeChooser {
public:
    static constexpr int kKinds = 5;               // closest hits of segments 0, 1, 2, 3+; visibility
    static constexpr int kVisibility = kKinds - 1;
    static constexpr std::size_t kMinRays = 64;    // smaller batches are neither timed nor explored
    static constexpr int kWarmUp = 2;              // timed batches per mode before the choice starts
    static constexpr unsigned kExploreEvery = 32;  // one batch in this many tries another mode
    static constexpr double kKeep = 0.75;          // the mode in use: weight of its previous average

    static int hit_kind(int segment) { return segment < kVisibility - 1 ? segment : kVisibility - 1; }

    QueryMode pick(int kind, std::size_t rays) {
        Kind& k = kinds_[static_cast<std::size_t>(kind)];
        if (rays < kMinRays) return best(k);
        for (int m = 0; m < kQueryModes; ++m)
            if (k.samples[static_cast<std::size_t>(m)] < kWarmUp) return static_cast<QueryMode>(m);
        const QueryMode fastest = best(k);
        if (++k.decisions % kExploreEvery != 0) return fastest;
        // The other modes in turn.
        const unsigned other = 1 + (k.decisions / kExploreEvery) % (kQueryModes - 1);
        return static_cast<QueryMode>((static_cast<unsigned>(fastest) + other) % kQueryModes);
    }

    // A batch of `rays` queries took `seconds` in `mode`. The mode in use keeps a running average; a
    // mode tried now and then is judged by its latest batch (its older ones may be long out of date),
    // and if that batch was slow only by chance, it becomes the mode in use and its average shows it.
    void record(int kind, QueryMode mode, std::size_t rays, double seconds) {
        if (rays < kMinRays) return;
        Kind& k = kinds_[static_cast<std::size_t>(kind)];
        const std::size_t m = static_cast<std::size_t>(mode);
        const double per_ray = seconds / static_cast<double>(rays);
        const bool in_use = k.samples[m] > 0 && best(k) == mode;
        k.per_ray[m] = in_use ? kKeep * k.per_ray[m] + (1.0 - kKeep) * per_ray : per_ray;
        if (k.samples[m] < kWarmUp) ++k.samples[m];
    }

    // Runs query(mode) for a batch of `rays` of `kind` in the chosen mode, timed.
    template <class Query>
    void run(int kind, std::size_t rays, Query&& query) {
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
    };
    // Before any timing, 16-ray packets: the fastest mode on most scenes' first segments.
    static QueryMode best(const Kind& k) {
        int fastest = static_cast<int>(QueryMode::Packet16);
        for (int m = 0; m < kQueryModes; ++m) {
            const std::size_t i = static_cast<std::size_t>(m), f = static_cast<std::size_t>(fastest);
            if (k.samples[i] > 0 && (k.samples[f] == 0 || k.per_ray[i] < k.per_ray[f])) fastest = m;
        }
        return static_cast<QueryMode>(fastest);
    }
    std::array<Kind, kKinds> kinds_{};
};

}  // namespace caustics
