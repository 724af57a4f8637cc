#pragma once
// The viewer's reference of the current frame: served from the cache (load_or_compute_reference) when
// it is there, otherwise traced in a background thread in growing rounds, so that the reference view and
// the error sharpen while the method is explored. Each round extends the previous round's sums
// (compute_reference's `start`), which gives the same bits as tracing all the photons at once.
//
// Rounds: the first traces photons / 64 (at least kMinPhotons); each next one doubles the total, but adds
// no more photons than the measured rate traces in `round_seconds`, so that a frame change (which
// abandons the reference) waits for at most one short round. With a cache folder, every round goes through
// load_or_compute_reference, so the rounds are stored as they finish and a later viewer (or `caustics
// render` with the same photons) resumes from the largest one; the search for that entry mirrors the
// cache's file names (reference_cache.cpp: <key>-<photons>.ref).
//
// A noise target (ReferenceSettings::noise_target) ends the rounds once noise_nrmse meets it; the final
// count is then the photon cap.
//
// Low priority: the thread traces in its own one-thread TBB arena (no worker of the method's pool) and
// lowers its own scheduling priority to nice 10 (kNice), so the method's renders keep the cores: under
// Linux's fair scheduler a nice-10 thread beside busy nice-0 ones gets about a tenth of a core (weights
// 110 against 1024), where nice 19 (weight 15) would starve it while the viewer renders continuously;
// when the viewer idles (rendering only on a change) it gets a whole core.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <caustics/reference/reference.hpp>
#include <caustics/run/scene_frame.hpp>

namespace caustics::view {

inline constexpr int kNice = 10;

struct ProgressiveSettings {
    ReferenceSettings reference{.photons = 4'000'000, .progress = false};   // photons: the final count
    std::uint64_t first_round = 0;     // photons of the first round; 0: photons / 64
    double round_seconds = 1.5;        // a round after the first adds at most this long's photons
    std::string cache_dir;             // empty (or a scene built in code): nothing is cached
    bool low_priority = true;
};

struct ProgressiveStatus {
    std::uint64_t photons = 0;         // of the latest result (all replicas)
    std::uint64_t target = 0;          // the final count
    int rounds = 0;                    // results published so far
    bool done = false;                 // the final count is reached (or it failed)
    bool from_cache = false;           // the first result came from the cache
    double photons_per_second = 0.0;   // of the last traced round (0: none traced)
    std::string error;                 // what went wrong, when it stopped early
};

class ProgressiveReference {
public:
    // `sf` must outlive this object. Starts the thread at once.
    ProgressiveReference(const SceneFrame& sf, ProgressiveSettings settings);
    ~ProgressiveReference();   // cancels after the current round and joins
    ProgressiveReference(const ProgressiveReference&) = delete;
    ProgressiveReference& operator=(const ProgressiveReference&) = delete;

    // The latest round's result (null before the first).
    std::shared_ptr<const ReferenceResult> latest() const;
    ProgressiveStatus status() const;
    // Photon totals of every published round, in order.
    std::vector<std::uint64_t> round_photons() const;
    void wait();     // until done (tests, --screenshot with a reference)
    void cancel();   // stop after the current round, without waiting (status().done then)

private:
    void run();
    ReferenceResult trace_round(std::uint64_t photons, const ReferenceResult* previous);
    const SceneFrame& sf_;
    ProgressiveSettings settings_;
    double noise_target_ = 0.0;
    std::atomic<bool> cancel_{false};
    mutable std::mutex mutex_;
    std::shared_ptr<const ReferenceResult> latest_;
    ProgressiveStatus status_;
    std::vector<std::uint64_t> rounds_;
    std::thread thread_;
};

// The photon count of the largest cached entry for this scene frame and settings at most `photons`
// (0: none). Its validity is checked only when it is loaded.
std::uint64_t largest_cached_photons(const SceneFrame& sf, const ReferenceSettings& settings,
                                     const std::string& cache_dir, std::uint64_t photons);

}  // namespace caustics::view
