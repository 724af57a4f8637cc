#include <caustics/reference/photon_source.hpp>

#include <algorithm>
#include <numbers>

#include <caustics/util/target_clones.hpp>
#include <caustics/util/vector_sincos.hpp>

namespace caustics {
namespace {

// Interleaves the bits of two 8-bit integers (Morton / Z order).
std::uint32_t morton2(std::uint32_t x, std::uint32_t y) {
    auto spread = [](std::uint32_t v) {
        v &= 0xFFu;
        v = (v | (v << 4)) & 0x0F0Fu;
        v = (v | (v << 2)) & 0x3333u;
        v = (v | (v << 1)) & 0x5555u;
        return v;
    };
    return spread(x) | (spread(y) << 1);
}

// A point light's directions of photons [0, n) from their sample values u and the cos and sin of their
// angle phi: element-wise double arithmetic in the order of the one-photon formula (glm's: the cone's
// axis term plus the rim term, each component (c a + s b) scaled by sin_t; normalize is v * (1 / sqrt(
// (x x + y y) + z z))), so AVX2 runs four photons per vector with the same bits (no FMA on that target).
CAUSTICS_AVX2_CLONES void point_directions(const Emitter& e, const glm::dvec2* u, const double* cos_phi,
                                            const double* sin_phi, std::size_t n, glm::dvec3* dirs) {
    const double one_minus_cos_max = 1.0 - e.cos_max;
    const glm::dvec3 d = e.direction, a = e.axis_a, b = e.axis_b;
    for (std::size_t k = 0; k < n; ++k) {
        const double cos_t = 1.0 - u[k].x * one_minus_cos_max;
        const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
        const double c = cos_phi[k], s = sin_phi[k];
        const double x = cos_t * d.x + sin_t * (c * a.x + s * b.x);
        const double y = cos_t * d.y + sin_t * (c * a.y + s * b.y);
        const double z = cos_t * d.z + sin_t * (c * a.z + s * b.z);
        const double inv = 1.0 / std::sqrt(x * x + y * y + z * z);
        dirs[k] = {x * inv, y * inv, z * inv};
    }
}

}  // namespace

void orthonormal_basis(const glm::dvec3& n, glm::dvec3& a, glm::dvec3& b) {
    const double sign = std::copysign(1.0, n.z);
    const double s = -1.0 / (sign + n.z);
    const double t = n.x * n.y * s;
    a = {1.0 + sign * n.x * n.x * s, sign * t, -sign * n.x};
    b = {t, sign + n.y * n.y * s, -n.y};
}

Emitter make_emitter(const Light& light, const FrameGeometry& frame) {
    Emitter e;
    e.type = light.type;
    Bounds3 target = frame.specular_bounds.valid() ? frame.specular_bounds : frame.receiver().bounds;
    if (!target.valid()) target = frame.scene_bounds;
    const glm::dvec3 lo = target.lo, hi = target.hi;
    const double size = std::max(1e-6, glm::length(hi - lo));
    if (light.type == LightType::Directional) {
        e.direction = glm::normalize(light.direction);
        orthonormal_basis(e.direction, e.axis_a, e.axis_b);
        double amin = 1e300, amax = -1e300, bmin = 1e300, bmax = -1e300;
        for (int k = 0; k < 8; ++k) {
            const glm::dvec3 c((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
            amin = std::min(amin, glm::dot(c, e.axis_a));
            amax = std::max(amax, glm::dot(c, e.axis_a));
            bmin = std::min(bmin, glm::dot(c, e.axis_b));
            bmax = std::max(bmax, glm::dot(c, e.axis_b));
        }
        // A small margin so that silhouettes are not clipped by round-off.
        const double margin = 1e-4 * size;
        amin -= margin, amax += margin, bmin -= margin, bmax += margin;
        // Start behind every object of the scene along the light direction.
        const Bounds3& all = frame.scene_bounds.valid() ? frame.scene_bounds : target;
        double dmin = 1e300;
        for (int k = 0; k < 8; ++k) {
            const glm::dvec3 c((k & 1) ? all.hi.x : all.lo.x, (k & 2) ? all.hi.y : all.lo.y,
                               (k & 4) ? all.hi.z : all.lo.z);
            dmin = std::min(dmin, glm::dot(c, e.direction));
        }
        dmin -= 0.01 * size + 1e-3;
        e.corner = dmin * e.direction + amin * e.axis_a + bmin * e.axis_b;
        e.extent_a = amax - amin;
        e.extent_b = bmax - bmin;
        e.power = light.irradiance * e.extent_a * e.extent_b;
    } else {
        e.position = light.position;
        const glm::dvec3 center = 0.5 * (lo + hi);
        const double radius = 0.5 * glm::length(hi - lo) * (1.0 + 1e-4) + 1e-6;
        const double dist = glm::length(center - light.position);
        if (dist > radius) {
            e.direction = (center - light.position) / dist;
            const double sin_max = radius / dist;
            e.cos_max = std::sqrt(std::max(0.0, 1.0 - sin_max * sin_max));
        } else {
            e.direction = {0.0, 0.0, -1.0};
            e.cos_max = -1.0;
        }
        orthonormal_basis(e.direction, e.axis_a, e.axis_b);
        e.power = light.intensity * 2.0 * std::numbers::pi * (1.0 - e.cos_max);
    }
    return e;
}

namespace {

// photon_batch_order with each key and photon offset packed into one Element: (key << kShift) | offset,
// offsets below 2^kShift. 32-bit elements where the batch allows (the reference's batches of 65,536)
// halve the passes' memory traffic; the order is the same, since both sorts are stable by the same key.
template <class Element, int kShift>
void sort_by_cell(std::uint64_t lights, std::uint64_t first, const std::vector<glm::dvec2>& values,
                  std::vector<std::uint32_t>& order, Element* keyed, Element* by_low) {
    const std::size_t n = values.size();
    constexpr Element kOffset = (Element{1} << kShift) - 1;
    std::uint32_t low[257] = {}, high[257] = {};
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t key = morton2(static_cast<std::uint32_t>(values[i].x * 256.0),
                                          static_cast<std::uint32_t>(values[i].y * 256.0));
        keyed[i] = static_cast<Element>(key) << kShift | static_cast<Element>(i);
        ++low[(key & 0xFFu) + 1];
        ++high[(key >> 8) + 1];
    }
    for (std::size_t c = 1; c <= 256; ++c) low[c] += low[c - 1], high[c] += high[c - 1];
    for (std::size_t i = 0; i < n; ++i) by_low[low[(keyed[i] >> kShift) & 0xFFu]++] = keyed[i];
    order.resize(n);
    if (lights <= 1) {
        for (std::size_t j = 0; j < n; ++j)
            order[high[by_low[j] >> (kShift + 8)]++] = static_cast<std::uint32_t>(by_low[j] & kOffset);
        return;
    }
    Element* by_cell = keyed;   // reused: every key is in by_low now
    for (std::size_t j = 0; j < n; ++j) by_cell[high[by_low[j] >> (kShift + 8)]++] = by_low[j];
    // A stable second pass by light (photon k belongs to light k mod L).
    std::vector<std::uint32_t> light_start(lights + 1, 0u);
    for (std::size_t i = 0; i < n; ++i) ++light_start[(first + i) % lights + 1];
    for (std::size_t l = 1; l <= lights; ++l) light_start[l] += light_start[l - 1];
    for (std::size_t j = 0; j < n; ++j) {
        const auto i = static_cast<std::uint32_t>(by_cell[j] & kOffset);
        order[light_start[(first + i) % lights]++] = i;
    }
}

// A batch of one light whose photons lie in distinct cells of the 256 x 256 grid is sorted by one
// scatter, slots[key] = offset, and a pass that keeps the filled slots in key order. That is the
// reference's usual batch: an aligned block of 2^16 indices of the scrambled (0,2)-sequence is a
// (0,16,2)-net, one point in every 2^-8 x 2^-8 cell (the index shuffle maps aligned blocks onto aligned
// blocks, and Owen scrambling keeps nets), and a batch that starts at such a block's start is part of
// one. With distinct keys the stable sort is the key order. False where two photons share a cell (order
// unspecified): the caller sorts. A full batch scatters into `order` itself.
bool order_by_distinct_cells(const std::vector<glm::dvec2>& values, std::vector<std::uint32_t>& order,
                             std::vector<std::uint32_t>& slots_scratch) {
    constexpr std::size_t kCells = std::size_t{1} << 16;
    constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
    const std::size_t n = values.size();
    std::vector<std::uint32_t>& slots = n == kCells ? order : slots_scratch;
    slots.assign(kCells, kEmpty);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t key = morton2(static_cast<std::uint32_t>(values[i].x * 256.0),
                                          static_cast<std::uint32_t>(values[i].y * 256.0));
        if (slots[key] != kEmpty) return false;   // independent samples: after a few hundred photons
        slots[key] = static_cast<std::uint32_t>(i);
    }
    if (n == kCells) return true;
    order.resize(n + 1);   // one spare element: the compaction below writes each slot before it counts
    std::size_t j = 0;
    for (std::size_t c = 0; c < kCells; ++c) {
        order[j] = slots[c];
        j += slots[c] != kEmpty ? 1 : 0;
    }
    order.resize(n);
    return true;
}

}  // namespace

void photon_batch_order(std::uint64_t lights, std::uint64_t first, const std::vector<glm::dvec2>& values,
                        std::vector<std::uint32_t>& order, SortScratch& scratch) {
    // A stable sort by the 16-bit cell key as two stable passes of 8 bits (least significant first):
    // the same order as one counting sort over all 65,536 cells, with counts that stay in L1 (the
    // counting sort's random increments of a 256 KB table cost more than both passes).
    const std::size_t n = values.size();
    constexpr std::size_t kCells = std::size_t{1} << 16;
    if (lights <= 1 && n <= kCells && order_by_distinct_cells(values, order, scratch.narrow)) return;
    if (n <= kCells) {
        scratch.narrow.resize(2 * n);
        sort_by_cell<std::uint32_t, 16>(lights, first, values, order, scratch.narrow.data(), scratch.narrow.data() + n);
    } else {
        scratch.wide.resize(2 * n);
        sort_by_cell<std::uint64_t, 32>(lights, first, values, order, scratch.wide.data(), scratch.wide.data() + n);
    }
}

void Emitter::sample_many(const glm::dvec2* u, std::size_t n, glm::dvec3* origins, glm::dvec3* dirs) const {
    if (type == LightType::Directional) {
        for (std::size_t k = 0; k < n; ++k) {
            origins[k] = corner + (u[k].x * extent_a) * axis_a + (u[k].y * extent_b) * axis_b;
            dirs[k] = direction;
        }
        return;
    }
    // In chunks that stay in L1: the azimuths' cos and sin first, four per call of libmvec's kernels
    // (util/vector_sincos.hpp; with libm's scalar sincos the emission took about 60 % of a point
    // light's photon generation), then the directions.
    constexpr std::size_t kChunk = 64;
    double phi[kChunk], cos_phi[kChunk], sin_phi[kChunk];
    for (std::size_t k0 = 0; k0 < n; k0 += kChunk) {
        const std::size_t m = std::min(kChunk, n - k0);
        for (std::size_t k = 0; k < m; ++k) phi[k] = 2.0 * std::numbers::pi * u[k0 + k].y;
        vector_sincos(phi, m, cos_phi, sin_phi);
        point_directions(*this, u + k0, cos_phi, sin_phi, m, dirs + k0);
        for (std::size_t k = 0; k < m; ++k) origins[k0 + k] = position;
    }
}

}  // namespace caustics
