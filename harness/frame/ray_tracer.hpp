#pragma once
// Embree 3 scene of one frame (docs/design.md section 10: rtcIntersect1 with an RTCIntersectContext).
// Triangles for planes, boxes, meshes and height fields; Embree sphere points for analytic spheres.
// Shading normals are interpolated (height fields: from the field's gradients) and face the same
// side as the geometric normal's outward orientation.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>

namespace caustics {

// A query's far end as Embree takes it: single precision, and +inf for "unbounded" (tmax >= 3e38, where
// the float conversion would overflow). The reference's ray log records it the same way.
inline float embree_tfar(double tmax) {
    return tmax >= 3e38 ? std::numeric_limits<float>::infinity() : static_cast<float>(tmax);
}

struct Hit {
    bool valid = false;
    int object = -1;               // index into scene.objects / frame.objects
    double t = 0.0;
    glm::dvec3 position{0.0};
    glm::dvec3 geometric_normal{0.0};  // unit, outward (height fields: up)
    glm::dvec3 shading_normal{0.0};    // unit, outward, interpolated
};

// One query of a batch: origin + t dir, t in (tmin, tmax).
struct RayQuery {
    glm::dvec3 origin{0.0};
    glm::dvec3 dir{0.0, 0.0, 1.0};
    double tmin = 1e-6;
    double tmax = 1e30;
};

// How a batch of queries goes to Embree: one ray at a time (rtcIntersect1 / rtcOccluded1) or as
// packets of 8 or 16 rays with a coherent context. Which is fastest depends on the rays' coherence and
// the scene, and changes from run to run where they are close (bench/bench_reference.cpp, one run: on
// `sphere` 16-ray packets replayed the reference's rays 1.4x faster than single rays; on `bunny`, whose
// refracted rays scatter over a 69k-triangle mesh, single rays 1.5x faster than 16-ray packets).
enum class QueryMode : std::uint8_t { Single, Packet8, Packet16 };
constexpr int kQueryModes = static_cast<int>(QueryMode::Packet16) + 1;

class RayTracer {
public:
    explicit RayTracer(const FrameGeometry& frame);
    ~RayTracer();
    RayTracer(const RayTracer&) = delete;
    RayTracer& operator=(const RayTracer&) = delete;

    // Closest hit along origin + t dir, t in (tmin, tmax). Thread-safe.
    Hit intersect(const glm::dvec3& origin, const glm::dvec3& dir, double tmin = 1e-6,
                  double tmax = 1e30) const;
    // True if anything lies on the open segment. Thread-safe.
    bool occluded(const glm::dvec3& origin, const glm::dvec3& dir, double tmin, double tmax) const;

    // Batches of n queries. hits[k] / occluded[k] are meant to be what the single-ray forms return for
    // queries[k], bit for bit, in every QueryMode, so that the mode only sets the speed. Every mode
    // completes its hits in one code path; Embree does not promise that its 1-, 8- and 16-wide kernels
    // agree, and they did on every ray checked (tests/test_reference_bits.cpp). Thread-safe.
    void intersect(const RayQuery* queries, std::size_t n, Hit* hits, QueryMode mode = QueryMode::Packet16) const;
    void occluded(const RayQuery* queries, std::size_t n, std::uint8_t* occluded,
                  QueryMode mode = QueryMode::Packet16) const;

    const FrameGeometry& frame() const { return *frame_; }

    // Raw Embree access for throughput measurements (bench/): the committed RTCScene.
    void* embree_scene() const;

private:
    struct Impl;
    const FrameGeometry* frame_;
    std::unique_ptr<Impl> impl_;
};

}  // namespace caustics
