#pragma once
// Where the reference's photons come from (docs/design.md section 5): the emitters of directional and point
// lights, and the order in which each batch of photons is traced (the sample values themselves come
// from photon_sampler.hpp). Split from reference.cpp; everything here is deterministic.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>
#include <caustics/util/hash.hpp>
#include <caustics/scene/scene.hpp>

namespace caustics {

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited": a and b complete the unit vector n.
void orthonormal_basis(const glm::dvec3& n, glm::dvec3& a, glm::dvec3& b);

// Where photons of one light start and how much flux each carries.
struct Emitter {
    LightType type = LightType::Directional;
    glm::dvec3 direction{0, 0, -1}, axis_a{1, 0, 0}, axis_b{0, 1, 0};
    glm::dvec3 corner{0.0};            // directional: rectangle origin
    double extent_a = 0, extent_b = 0; // directional: rectangle sides
    glm::dvec3 position{0.0};          // point light
    double cos_max = -1.0;             // point light: cone half-angle cosine (-1 = full sphere)
    double power = 0.0;                // total flux this light sends through the sampled domain [W]
    double flux_per_photon = 0.0;

    // Photon k of n leaves from origins[k] along dirs[k] for its emission sample values u[k] (dimensions
    // 0 and 1): a directional light's rectangle; a point light's cone, uniform in solid angle. A point
    // light's cos and sin of phi come from vector_sincos (util/vector_sincos.hpp: libmvec's kernels
    // where the CPU has AVX2), the rest from a loop that runs four photons per AVX2 vector; every photon
    // gets the bits it would get alone.
    void sample_many(const glm::dvec2* u, std::size_t n, glm::dvec3* origins, glm::dvec3* dirs) const;
    void sample(double u1, double u2, glm::dvec3& origin, glm::dvec3& dir) const {
        const glm::dvec2 u(u1, u2);
        sample_many(&u, 1, &origin, &dir);
    }
};

// The emitter of one light, aimed at the frame's specular objects (or its receiver, or the whole scene):
// a directional light covers the bounds' projection with a margin; a point light the cone around them.
Emitter make_emitter(const Light& light, const FrameGeometry& frame);

// The order in which the photons [first, first + values.size()) of one batch are traced: grouped by
// light and then along a Z-order curve over a 256 x 256 grid of their two emission sample values
// (values[k]: photon first + k's), so that consecutive photons start close together and take similar
// paths (coherent BVH traversal, height-field and accumulator accesses). Every photon's sample values
// depend only on its index, and deposits are integer sums, so the order changes nothing but the
// round-off of the batch's flux ledger; it is a fixed function of the batch (stable sorts), so results
// stay independent of the thread count. `lights` is the number of emitters (photon k belongs to light
// k mod lights). `order` receives photon offsets k.
// `scratch` holds the sort's keys: 32-bit (key, offset) pairs for batches of up to 65,536 photons (the
// reference's), 64-bit ones for larger batches.
struct SortScratch {
    std::vector<std::uint32_t> narrow;
    std::vector<std::uint64_t> wide;
};
void photon_batch_order(std::uint64_t lights, std::uint64_t first, const std::vector<glm::dvec2>& values,
                        std::vector<std::uint32_t>& order, SortScratch& scratch);

}  // namespace caustics
