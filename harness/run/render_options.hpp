#pragma once
// What one timed render is asked to do: `caustics render`'s options, also filled by the sweep runner.
#include <map>
#include <string>

#include <caustics/reference/reference.hpp>

namespace caustics {

struct RenderOptions {
    std::string scene_path;
    std::string method;
    std::map<std::string, std::string> overrides;   // --set KEY=VALUE
    int frame = 0;
    std::string out_dir;                            // empty: write no files
    int warmup = 3;
    int repeats = 10;                               // timed frames at least (then until precise or capped)
    double timing_precision = 0.05;                 // relative half-width of the median's 95 % interval
    double timing_max_s = 3.0;                      // time cap of the timed frames [s]
    // The reference asked for (photons, seed, sampler, replicas, noise target, cap); its threads and
    // progress come from the fields below (reference_settings).
    ReferenceSettings reference{.photons = 4'000'000};
    std::string truth = "auto";                     // receiver truth: auto | analytic | reference
    bool no_reference = false;                      // skip the reference: error values are null
    std::string cache_dir;                          // reference cache; empty: default_cache_dir()
    int threads = 0;                                // 0: every core
    bool beauty = true;                             // render beauty.png when writing files
    bool progress = true;                           // reference progress bar on stderr
};

}  // namespace caustics
