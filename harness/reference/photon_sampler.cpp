#include <caustics/reference/photon_sampler.hpp>

namespace caustics {
namespace {

std::uint32_t reverse_bits(std::uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
    x = ((x >> 8) & 0x00FF00FFu) | ((x & 0x00FF00FFu) << 8);
    return (x >> 16) | (x << 16);
}

// A Laine-Karras style hash: each step only propagates lower bits into higher ones (x ^= x * even,
// x *= odd, x += c), so output bit b depends on input bits <= b only. Applied to the reversed digits it
// is a nested uniform scramble (Burley 2020, section 3, with the improved constants of its follow-up
// discussion; any mixing of this shape is valid, these mix well).
std::uint32_t lk_hash(std::uint32_t x, std::uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

constexpr double kTo01 = 0x1.0p-32;

}  // namespace

const char* sampler_name(SamplerKind kind) { return kind == SamplerKind::Sobol ? "sobol" : "independent"; }

bool parse_sampler(const std::string& text, SamplerKind& kind) {
    if (text == "sobol") return kind = SamplerKind::Sobol, true;
    if (text == "independent") return kind = SamplerKind::Independent, true;
    return false;
}

std::uint32_t owen_scramble(std::uint32_t x, std::uint32_t seed) {
    return reverse_bits(lk_hash(reverse_bits(x), seed));
}

std::uint32_t sobol_dim1(std::uint32_t index) {
    // Direction numbers v_k = v_{k-1} ^ (v_{k-1} >> 1), v_0 = 2^31 (Sobol' 1967; Joe and Kuo's second
    // dimension).
    std::uint32_t x = 0, v = 0x80000000u;
    for (; index; index >>= 1, v ^= v >> 1)
        if (index & 1u) x ^= v;
    return x;
}

double PhotonSampler::get(int dim) const {
    if (kind_ == SamplerKind::Independent || dim >= kQuasiDimensions || index_ > 0xFFFFFFFFull) return random(dim);
    const int pair = dim >> 1;
    const std::uint64_t pair_seed = mix64(replica_seed_ + static_cast<std::uint64_t>(pair) * 0xA24BAED4963EE407ull);
    // Shuffled index (Burley's "padding"): a nested scramble of the index's digits.
    const std::uint32_t index = owen_scramble(static_cast<std::uint32_t>(index_), static_cast<std::uint32_t>(pair_seed));
    const std::uint32_t raw = (dim & 1) ? sobol_dim1(index) : reverse_bits(index);
    const std::uint32_t scrambled = owen_scramble(raw, static_cast<std::uint32_t>(pair_seed >> 32) ^ (dim & 1 ? 0x68bc21ebu : 0u));
    // Centre of the 2^-32 cell: never exactly 0 or 1.
    return (static_cast<double>(scrambled) + 0.5) * kTo01;
}

}  // namespace caustics
