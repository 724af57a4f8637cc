#include <caustics/reference/photon_sampler.hpp>

#include <caustics/util/target_clones.hpp>

namespace caustics {
namespace {

constexpr std::uint32_t reverse_bits(std::uint32_t x) {
    // Bytes by one byte swap, then the bits within each byte.
    x = __builtin_bswap32(x);
    x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
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

// The centre of the 2^-32 cell of a 32-bit point: in (0, 1), never exactly 0 or 1 (exact in double).
constexpr double cell_centre(std::uint32_t x) { return (static_cast<double>(x) + 0.5) * 0x1.0p-32; }

constexpr std::uint32_t sobol_dim1_loop(std::uint32_t index) {
    // Direction numbers v_k = v_{k-1} ^ (v_{k-1} >> 1), v_0 = 2^31 (Sobol' 1967; Joe and Kuo's second
    // dimension).
    std::uint32_t x = 0, v = 0x80000000u;
    for (; index; index >>= 1, v ^= v >> 1)
        if (index & 1u) x ^= v;
    return x;
}

// x -> reverse_bits(sobol_dim1(reverse_bits(x))) is linear over GF(2) (a composition of linear maps),
// so it is the XOR of one table entry per byte of x: four look-ups instead of a 32-step loop and two
// bit reversals, the same bits.
struct Dim1Tables {
    std::uint32_t t[4][256];
};

constexpr Dim1Tables make_dim1_tables() {
    Dim1Tables tables{};
    for (int byte = 0; byte < 4; ++byte)
        for (std::uint32_t v = 0; v < 256; ++v) {
            std::uint32_t x = 0;
            for (int bit = 0; bit < 8; ++bit)
                if (v & (1u << bit)) x ^= reverse_bits(sobol_dim1_loop(reverse_bits(1u << (8 * byte + bit))));
            tables.t[byte][v] = x;
        }
    return tables;
}

constexpr Dim1Tables kDim1 = make_dim1_tables();

std::uint32_t reversed_dim1_of_reversed(std::uint32_t x) {
    return kDim1.t[0][x & 0xFFu] ^ kDim1.t[1][(x >> 8) & 0xFFu] ^ kDim1.t[2][(x >> 16) & 0xFFu] ^ kDim1.t[3][x >> 24];
}

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

std::uint32_t sobol_dim1(std::uint32_t index) { return sobol_dim1_loop(index); }

// With owen_scramble(x, s) = R(H(R(x), s)) (R: reverse_bits, H: lk_hash) and the shuffled index
// R(h), h = H(R(index), s1): the even dimension's point R(R(h)) = h scrambles to R(H(R(h), s2)), the odd
// one's sobol_dim1(R(h)) to R(H(R(sobol_dim1(R(h))), s2')). Both come from the same h: one hash of
// the index per pair, the same bits as scrambling each dimension on its own (tests/test_reference_bits.cpp).
namespace {

void scrambled_pair(std::uint32_t index, std::uint64_t pair_seed, std::uint32_t& even, std::uint32_t& odd) {
    const std::uint32_t h = lk_hash(reverse_bits(index), static_cast<std::uint32_t>(pair_seed));
    const std::uint32_t seed2 = static_cast<std::uint32_t>(pair_seed >> 32);
    even = reverse_bits(lk_hash(reverse_bits(h), seed2));
    odd = reverse_bits(lk_hash(reversed_dim1_of_reversed(h), seed2 ^ 0x68bc21ebu));
}

// The emission samples (the first pair) of a Sobol' index below 2^32.
inline void sobol_emission(std::uint32_t index, std::uint64_t pair0_seed, double& u1, double& u2) {
    std::uint32_t even, odd;
    scrambled_pair(index, pair0_seed, even, odd);
    u1 = cell_centre(even);
    u2 = cell_centre(odd);
}

}  // namespace

void PhotonSampler::quasi_pair(int pair, std::uint32_t& even, std::uint32_t& odd) const {
    scrambled_pair(static_cast<std::uint32_t>(index_), pair_seed(replica_seed_, pair), even, odd);
}

SamplerSeeds PhotonSampler::seeds(SamplerKind kind, std::uint64_t seed, std::uint32_t replica) {
    const PhotonSampler s(kind, seed, replica, 0);
    return {kind, s.replica_seed_, pair_seed(s.replica_seed_, 0)};
}

void PhotonSampler::emission(const SamplerSeeds& seeds, std::uint64_t index, double& u1, double& u2) {
    if (seeds.kind == SamplerKind::Independent || index > 0xFFFFFFFFull) {
        PhotonSampler(seeds, index).get2(0, u1, u2);
        return;
    }
    sobol_emission(static_cast<std::uint32_t>(index), seeds.pair0_seed, u1, u2);
}

namespace {

// emissions() of scrambled Sobol' indices below 2^32: integer hashes, byte-table look-ups and exact
// conversions only, which AVX2 runs over eight indices at a time (gathers for the tables).
CAUSTICS_AVX2_CLONES void sobol_emissions(std::uint32_t first, std::size_t n, std::uint64_t pair_seed, double* out) {
    for (std::size_t k = 0; k < n; ++k)
        sobol_emission(first + static_cast<std::uint32_t>(k), pair_seed, out[2 * k], out[2 * k + 1]);
}

}  // namespace

void PhotonSampler::emissions(const SamplerSeeds& seeds, std::uint64_t first, std::size_t n, double* out) {
    if (seeds.kind == SamplerKind::Sobol && n > 0 && first + n - 1 <= 0xFFFFFFFFull) {
        sobol_emissions(static_cast<std::uint32_t>(first), n, seeds.pair0_seed, out);
        return;
    }
    for (std::size_t k = 0; k < n; ++k) emission(seeds, first + k, out[2 * k], out[2 * k + 1]);
}

double PhotonSampler::get(int dim) const {
    if (kind_ == SamplerKind::Independent || dim >= kQuasiDimensions || index_ > 0xFFFFFFFFull) return random(dim);
    // Dimensions are taken in pairs, each pair reading its own shuffled (Owen-scrambled) index (Burley's
    // "padding"); the pair is the (0,2)-sequence (van der Corput, sobol_dim1), Owen-scrambled.
    std::uint32_t even, odd;
    quasi_pair(dim >> 1, even, odd);
    return cell_centre(dim & 1 ? odd : even);
}

void PhotonSampler::get2(int dim, double& first, double& second) const {
    if (kind_ == SamplerKind::Independent || dim + 1 >= kQuasiDimensions || index_ > 0xFFFFFFFFull || (dim & 1)) {
        first = get(dim), second = get(dim + 1);
        return;
    }
    std::uint32_t even, odd;
    quasi_pair(dim >> 1, even, odd);
    first = cell_centre(even);
    second = cell_centre(odd);
}

}  // namespace caustics
