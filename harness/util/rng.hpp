#pragma once
// The project's one pseudo-random stream: splitmix64 (Steele, Lea and Flood 2014), whose output is the
// mix64 finaliser of a Weyl sequence. Used where a seeded, platform-independent stream of numbers is
// needed (synthesised height fields, drop positions); the reference's sampler hashes its indices
// through the same mix64 instead of keeping a stream (photon_sampler.hpp).
#include <cstdint>

#include <caustics/util/hash.hpp>

namespace caustics {

struct SplitMix64 {
    std::uint64_t state = 0;

    std::uint64_t next() {
        const std::uint64_t s = state;
        state += 0x9E3779B97F4A7C15ull;
        return mix64(s);
    }
    // Uniform in [0, 1): 53 random bits.
    double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
    // Uniform in (0, 1]: never 0, so log() of it is finite (Box-Muller).
    double uniform_nonzero() { return (static_cast<double>(next() >> 11) + 1.0) * (1.0 / 9007199254740992.0); }
};

}  // namespace caustics
