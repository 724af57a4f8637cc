#pragma once
// The reference's sample values (docs/design.md section 5, issue 11): for photon `index` of replica `replica`,
// the value in [0, 1) of each sample dimension (0-1: emission position or direction, 2: dispersion,
// 3 and up: the Fresnel choice of each specular event).
//
// Sobol (the default): randomized quasi-Monte Carlo. Dimensions are taken in pairs; each pair is the
// two-dimensional Sobol' (0,2)-sequence (van der Corput and its companion, polynomial x + 1), Owen-
// scrambled with the hash-based nested uniform scramble of Burley 2020 ("Practical Hash-based Owen
// Scrambling", JCGT 9(4)), and each pair reads its own Owen-scrambled (shuffled) index so that pairs are
// decorrelated ("padding"). A shuffle maps every aligned block of 2^k indices onto another aligned
// block, which for the (0,2)-sequence is again a (0,k,2)-net, so every power-of-two prefix stays
// stratified. Each replica draws its scramble seeds from (seed, replica): replicas are independent
// randomizations, and the spread between them is the only valid standard error (the points within
// one replica are dependent).
// Independent: counter-based uniform random numbers keyed by (seed, replica, index, dimension).
//
// Both are pure functions of their arguments, so results do not depend on the thread count.
#include <cstddef>
#include <cstdint>
#include <string>

#include <caustics/util/hash.hpp>

namespace caustics {

enum class SamplerKind { Sobol, Independent };

// "sobol" / "independent"; parse returns false for anything else.
const char* sampler_name(SamplerKind kind);
bool parse_sampler(const std::string& text, SamplerKind& kind);

// Dimensions past this use independent random numbers in either sampler (deep Fresnel chains).
constexpr int kQuasiDimensions = 16;

// What the samplers of every photon of one (seed, replica) share, hashed once rather than per photon.
struct SamplerSeeds {
    SamplerKind kind = SamplerKind::Sobol;
    std::uint64_t replica_seed = 0;
    std::uint64_t pair0_seed = 0;   // the first pair's scramble seeds (dimensions 0 and 1)
};

class PhotonSampler {
public:
    PhotonSampler() = default;
    PhotonSampler(SamplerKind kind, std::uint64_t seed, std::uint32_t replica, std::uint64_t index)
        : kind_(kind), replica_seed_(mix64(seed * 0x9E3779B97F4A7C15ull + replica + 1)), index_(index) {}
    // The same sampler as PhotonSampler(kind, seed, replica, index) with seeds(kind, seed, replica).
    PhotonSampler(const SamplerSeeds& seeds, std::uint64_t index)
        : kind_(seeds.kind), replica_seed_(seeds.replica_seed), index_(index) {}
    static SamplerSeeds seeds(SamplerKind kind, std::uint64_t seed, std::uint32_t replica);
    // get2(0, u1, u2) of PhotonSampler(seeds, index): the emission sample values.
    static void emission(const SamplerSeeds& seeds, std::uint64_t index, double& u1, double& u2);
    // emission() of indices first, first + 1, ..., first + n - 1: out[2 k] and out[2 k + 1] are u1 and u2
    // of index first + k (the same values; a loop that vectorises where the indices allow).
    static void emissions(const SamplerSeeds& seeds, std::uint64_t first, std::size_t n, double* out);
    // The value of dimension `dim` (each dimension may be read any number of times).
    double get(int dim) const;
    // Dimensions dim and dim + 1 at once (the same values as two get calls; one index hash when they
    // form a pair).
    void get2(int dim, double& first, double& second) const;

private:
    // The scrambled 32-bit points of both dimensions of a pair.
    void quasi_pair(int pair, std::uint32_t& even, std::uint32_t& odd) const;
    static std::uint64_t pair_seed(std::uint64_t replica_seed, int pair) {
        return mix64(replica_seed + static_cast<std::uint64_t>(pair) * 0xA24BAED4963EE407ull);
    }
    double random(int dim) const {
        const std::uint64_t h = mix64(mix64(replica_seed_ + index_ * 0xD1B54A32D192ED03ull) + (dim + 1) * 0x9E3779B97F4A7C15ull);
        return static_cast<double>(h >> 11) * 0x1.0p-53;
    }
    SamplerKind kind_ = SamplerKind::Sobol;
    std::uint64_t replica_seed_ = 0;
    std::uint64_t index_ = 0;
};

// Owen scrambling of a 32-bit base-2 fraction (bit 31 is the first digit), seeded; a bijection that
// keeps every aligned dyadic interval whole (nested uniform scramble).
std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed);
// The second dimension of the Sobol' sequence (generator matrix of the polynomial x + 1), 32 digits.
std::uint32_t sobol_dim1(std::uint32_t index);

}  // namespace caustics
