// Embree 3 ray tracer of one frame (docs/design.md section 10: Embree 3.13, rtcIntersect1 with an
// RTCIntersectContext). Batches go to Embree in the caller's QueryMode: single rays, or 8- or 16-ray
// packets with a coherent context; every mode completes its hits in the same code, so all give the
// same bits.
//
// Conventions we own rather than borrow from Embree:
// - The outward geometric normal is normalize((v1 - v0) x (v2 - v0)), counter-clockwise seen from
//   outside (mesh.hpp). Embree's Ng is documented as (v0 - v1) x (v2 - v0), the opposite sign; the
//   sign is measured once on a probe triangle (embree_ng_sign) and applied to Embree's Ng per hit, which
//   costs no memory traffic beyond what Embree already touched (fetching our own vertices per hit
//   made photon tracing ~2x slower on the pool scene: cache misses).
// - Sphere hits are recomputed in double precision from Embree's float distance (exact quadric), so
//   refraction through the ball lens starts from an accurate point.
// - Embree errors are reported once, at the edge: the device's error callback records the message and
//   the constructor turns it into an exception after each build step.
#include <caustics/frame/ray_tracer.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include <caustics/frame/ray_offset.hpp>
#include <caustics/frame/sphere_hits.hpp>
#include <caustics/util/huge_pages.hpp>

#include "detail/deferred_hits.hpp"

namespace caustics {
namespace {

struct DeviceErrors {
    std::mutex mutex;
    std::string last;   // first error message not yet reported
};

DeviceErrors& device_errors() {
    static DeviceErrors errors;
    return errors;
}

void on_embree_error(void* /*user*/, RTCError code, const char* message) {
    if (code == RTC_ERROR_NONE) return;
    DeviceErrors& errors = device_errors();
    std::lock_guard<std::mutex> lock(errors.mutex);
    if (errors.last.empty())
        errors.last = "Embree error " + std::to_string(static_cast<int>(code)) + ": " + (message ? message : "");
}

// One process-wide device: creating a device spins up Embree's thread pool and is expensive.
// CAUSTICS_EMBREE_CONFIG, when set, is passed to rtcNewDevice as its configuration string (Embree 3's
// "isa=avx2", "threads=N", "verbose=1", ...): with "isa=avx2" a CPU with AVX-512 runs the AVX2 kernels,
// as a machine without AVX-512 would (its sums' last bits need not be that machine's on every CPU:
// tests/test_reference_bits.cpp).
RTCDevice shared_device() {
    static RTCDevice device = [] {
        const char* config = std::getenv("CAUSTICS_EMBREE_CONFIG");
        RTCDevice d = rtcNewDevice(config && *config ? config : nullptr);
        if (!d) throw std::runtime_error("Embree: rtcNewDevice failed (error " +
                                         std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
        rtcSetDeviceErrorFunction(d, on_embree_error, nullptr);
        return d;
    }();
    return device;
}

// Throws if Embree reported an error since the last check.
void check_embree(const char* what) {
    DeviceErrors& errors = device_errors();
    std::string message;
    {
        std::lock_guard<std::mutex> lock(errors.mutex);
        message.swap(errors.last);
    }
    if (!message.empty()) throw std::runtime_error(std::string("RayTracer: ") + what + ": " + message);
}

glm::dvec3 to_d(const glm::vec3& v) { return {v.x, v.y, v.z}; }

// Embree asserts (aborts the process) on a ray whose origin or direction is not finite or beyond
// ~1.8e18, or whose tnear/tfar is NaN. The scene bounds (limits.hpp: |x| <= 1e5 m) keep every ray the
// harness casts far inside that, so such a ray is a bug upstream: it becomes an internal failure that
// names the ray (exit 1), not an abort.
bool valid_ray(const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax) {
    constexpr double kLarge = 1e18;
    return std::abs(o.x) <= kLarge && std::abs(o.y) <= kLarge && std::abs(o.z) <= kLarge && std::abs(d.x) <= kLarge &&
           std::abs(d.y) <= kLarge && std::abs(d.z) <= kLarge && tmin >= 0.0 && !std::isnan(tmax);
}

[[noreturn]] void invalid_ray(const char* what, const glm::dvec3& o, const glm::dvec3& d, double tmin, double tmax) {
    char text[256];
    std::snprintf(text, sizeof text, "RayTracer::%s: invalid ray origin (%g, %g, %g) direction (%g, %g, %g) t in (%g, %g)",
                  what, o.x, o.y, o.z, d.x, d.y, d.z, tmin, tmax);
    throw std::runtime_error(text);
}

// +1 if Embree's triangle Ng points along (v1 - v0) x (v2 - v0) (our outward normal), -1 if opposite.
// Measured once on a one-triangle scene rather than assumed (Embree documents (v0 - v1) x (v2 - v0)).
double embree_ng_sign() {
    static const double sign = [] {
        RTCDevice device = shared_device();
        RTCScene scene = rtcNewScene(device);
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                              3 * sizeof(float), 3));
        const float vertices[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};   // counter-clockwise seen from +z
        std::copy(vertices, vertices + 9, v);
        auto* index = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                     RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 1));
        index[0] = 0, index[1] = 1, index[2] = 2;
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(scene, geometry);
        rtcReleaseGeometry(geometry);
        rtcCommitScene(scene);
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rh{};
        rh.ray = {0.25f, 0.25f, 1.0f, 0.0f, 0.0f, 0.0f, -1.0f, 0.0f, 10.0f, 0xFFFFFFFFu, 0u, 0u};
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        rtcReleaseScene(scene);
        check_embree("normal convention probe");
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID || rh.hit.Ng_z == 0.0f)
            throw std::runtime_error("RayTracer: Embree normal convention probe missed its triangle");
        return rh.hit.Ng_z > 0.0f ? 1.0 : -1.0;
    }();
    return sign;
}

// Embree's answer for one ray, whichever query produced it.
struct RawHit {
    unsigned geom_id, prim_id;
    float u, v, ng_x, ng_y, ng_z, tfar;
};
constexpr RawHit kMiss{RTC_INVALID_GEOMETRY_ID, 0u, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};

// One query as Embree's single ray, t in [tmin, tmax] in single precision. tmin already includes the
// tracer's minimum.
RTCRay single_ray(const glm::dvec3& origin, const glm::dvec3& dir, double tmin, double tmax) {
    RTCRay ray;
    ray.org_x = static_cast<float>(origin.x);
    ray.org_y = static_cast<float>(origin.y);
    ray.org_z = static_cast<float>(origin.z);
    ray.dir_x = static_cast<float>(dir.x);
    ray.dir_y = static_cast<float>(dir.y);
    ray.dir_z = static_cast<float>(dir.z);
    ray.tnear = static_cast<float>(tmin);
    ray.tfar = embree_tfar(tmax);
    ray.time = 0.0f;
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    return ray;
}

// Embree's closest hit of one ray; geom_id is RTC_INVALID_GEOMETRY_ID where it hits nothing.
RawHit closest_single(RTCScene scene, RTCIntersectContext* context, const glm::dvec3& origin, const glm::dvec3& dir,
                      double tmin, double tmax) {
    RTCRayHit rh;
    rh.ray = single_ray(origin, dir, tmin, tmax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return kMiss;   // the hit's other fields are not set
    return {rh.hit.geomID, rh.hit.primID, rh.hit.u, rh.hit.v, rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z, rh.ray.tfar};
}

// True if Embree finds anything on the ray's segment (it sets tfar to -inf then).
bool occluded_single(RTCScene scene, RTCIntersectContext* context, const glm::dvec3& origin, const glm::dvec3& dir,
                     double tmin, double tmax) {
    RTCRay ray = single_ray(origin, dir, tmin, tmax);
    rtcOccluded1(scene, context, &ray);
    return ray.tfar < 0.0f;
}

// Lane k of a packet (RTCRay8 or RTCRay16): the query's segment [tmin, tmax] in single precision.
template <class RayW>
void set_lane(RayW& p, int k, const RayQuery& q, double tmin) {
    p.org_x[k] = static_cast<float>(q.origin.x);
    p.org_y[k] = static_cast<float>(q.origin.y);
    p.org_z[k] = static_cast<float>(q.origin.z);
    p.dir_x[k] = static_cast<float>(q.dir.x);
    p.dir_y[k] = static_cast<float>(q.dir.y);
    p.dir_z[k] = static_cast<float>(q.dir.z);
    p.tnear[k] = static_cast<float>(tmin);
    p.tfar[k] = embree_tfar(q.tmax);
    p.time[k] = 0.0f;
    p.mask[k] = 0xFFFFFFFFu;
    p.id[k] = 0;
    p.flags[k] = 0;
}

// Embree's packet types and queries by width.
template <int W>
struct Packet;
template <>
struct Packet<8> {
    using Ray = RTCRay8;
    using RayHit = RTCRayHit8;
    static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* p) { rtcIntersect8(valid, s, c, p); }
    static void occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* p) { rtcOccluded8(valid, s, c, p); }
};
template <>
struct Packet<16> {
    using Ray = RTCRay16;
    using RayHit = RTCRayHit16;
    static void intersect(const int* valid, RTCScene s, RTCIntersectContext* c, RayHit* p) { rtcIntersect16(valid, s, c, p); }
    static void occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Ray* p) { rtcOccluded16(valid, s, c, p); }
};

// Queries a batch completes together, whatever the mode (their shading-normal records are prefetched as
// Embree answers each, raw_hits).
constexpr int kGroup = 16;


}  // namespace

struct RayTracer::Impl {
    RTCScene scene = nullptr;
    // A triangle's three vertex normals side by side: a hit's shading normal reads one 36-byte record
    // instead of the triangle's indices and three normals scattered over the mesh (on a 69k-triangle
    // mesh, hits are incoherent and each of those reads tends to miss the cache).
    struct CornerNormals {
        glm::vec3 n[3];
    };
    struct GeometryInfo {
        int object = -1;
        const ObjectInstance* instance = nullptr;
        // Per triangle; empty: no vertex normals (or not a mesh). On huge pages where large: hits read
        // it at random, and with 4 KiB pages most of those reads also missed the TLB.
        std::vector<CornerNormals, HugePageAllocator<CornerNormals>> corner_normals;
    };
    std::vector<GeometryInfo> geometries;   // by Embree geomID
    double min_tmin = 0.0;                  // self-intersection guard scaled to the scene size
    double ng_sign = 1.0;                   // embree_ng_sign(), cached

    // The Hit of one ray from Embree's raw answer, for single and packet queries. Written into `out`
    // field by field: a returned Hit was copied in 16-byte pieces from a temporary just written in
    // 8-byte ones, a store-forwarding stall per hit. With `deferred` set (batches), a sphere's exact hit
    // and a height field's shading normal are left to deferred->finish(), which computes a group's
    // together with exact_sphere_hits and HeightField::sample_normals; single rays call
    // exact_sphere_hit and sample_normal. The two forms give the same bits (tests/test_sphere_hits.cpp,
    // tests/test_heightfield_normals.cpp, and RayTracerBatches in tests/test_reference_bits.cpp).
    void complete(const glm::dvec3& origin, const glm::dvec3& dir, const RawHit& raw, Hit& out,
                  DeferredHits<kGroup>* deferred = nullptr) const;
    // Throws on a ray Embree would abort on; tmin is the query's as Embree gets it (at least min_tmin).
    void check(const RayQuery& q, double tmin, const char* what) const {
        if (!valid_ray(q.origin, q.dir, tmin, q.tmax)) [[unlikely]]
            invalid_ray(what, q.origin, q.dir, tmin, q.tmax);
    }
    // Embree's answers for queries[0, count), count <= kGroup, in `mode`. Each answer's shading-normal
    // record is prefetched as soon as Embree gives it, so that the queries after it hide the miss.
    void raw_hits(const RayQuery* queries, int count, QueryMode mode, RawHit* raw) const;
    void prefetch_normals(const RawHit& raw) const {
        if (raw.geom_id == RTC_INVALID_GEOMETRY_ID) return;
        const auto& normals = geometries[raw.geom_id].corner_normals;
        if (normals.empty()) return;
        const char* record = reinterpret_cast<const char*>(&normals[raw.prim_id]);
        __builtin_prefetch(record);
        __builtin_prefetch(record + sizeof(CornerNormals) - 1);
    }
    template <int W>
    void raw_hits_packet(const RayQuery* queries, int count, RawHit* raw) const;
    void visibility(const RayQuery* queries, int count, QueryMode mode, std::uint8_t* occluded) const;
    template <int W>
    void visibility_packet(const RayQuery* queries, int count, std::uint8_t* occluded) const;

    ~Impl() {
        if (scene) rtcReleaseScene(scene);
    }
};

RayTracer::RayTracer(const FrameGeometry& frame) : frame_(&frame), impl_(std::make_unique<Impl>()) {
    RTCDevice device = shared_device();
    impl_->ng_sign = embree_ng_sign();
    check_embree("device");
    impl_->scene = rtcNewScene(device);
    // Robust mode makes shared edges watertight (tests/test_reference.cpp measures the miss rate).
    rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);

    for (std::size_t index = 0; index < frame.objects.size(); ++index) {
        const ObjectInstance& inst = frame.objects[index];
        RTCGeometry geometry = nullptr;
        if (inst.analytic_sphere) {
            geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
            auto* point = static_cast<float*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
            const Object& obj = *inst.object;
            point[0] = static_cast<float>(obj.center.x);
            point[1] = static_cast<float>(obj.center.y);
            point[2] = static_cast<float>(obj.center.z);
            point[3] = static_cast<float>(obj.radius);
        } else {
            if (inst.mesh.empty()) continue;
            geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
            const auto& mesh = inst.mesh;
            // rtcSetNewGeometryBuffer pads the vertex buffer for Embree's 16-byte loads.
            auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                mesh.positions.size()));
            for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
                vertices[3 * v + 0] = mesh.positions[v].x;
                vertices[3 * v + 1] = mesh.positions[v].y;
                vertices[3 * v + 2] = mesh.positions[v].z;
            }
            auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
                geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                mesh.triangles.size()));
            for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
                indices[3 * t + 0] = mesh.triangles[t].x;
                indices[3 * t + 1] = mesh.triangles[t].y;
                indices[3 * t + 2] = mesh.triangles[t].z;
            }
        }
        rtcCommitGeometry(geometry);
        const unsigned id = rtcAttachGeometry(impl_->scene, geometry);
        rtcReleaseGeometry(geometry);
        if (impl_->geometries.size() <= id) impl_->geometries.resize(id + 1);
        Impl::GeometryInfo& info = impl_->geometries[id];
        info.object = static_cast<int>(index);
        info.instance = &inst;
        if (!inst.analytic_sphere && !inst.heightfield && !inst.mesh.normals.empty()) {
            const TriangleMesh& mesh = inst.mesh;
            info.corner_normals.resize(mesh.triangles.size());
            for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
                const glm::uvec3 tri = mesh.triangles[t];
                info.corner_normals[t] = {{mesh.normals[tri.x], mesh.normals[tri.y], mesh.normals[tri.z]}};
            }
        }
        check_embree("geometry");
    }
    rtcCommitScene(impl_->scene);
    check_embree("scene build");

    impl_->min_tmin = scene_ray_offset(frame);
}

RayTracer::~RayTracer() = default;

void* RayTracer::embree_scene() const { return impl_->scene; }

// The single-ray forms are batches of one in QueryMode::Single: one place for the segment's rules
// (the tracer's minimum tmin, empty segments, rays Embree would abort on).
Hit RayTracer::intersect(const glm::dvec3& origin, const glm::dvec3& dir, double tmin, double tmax) const {
    const RayQuery query{origin, dir, tmin, tmax};
    RawHit raw;
    impl_->raw_hits(&query, 1, QueryMode::Single, &raw);
    Hit hit;
    if (raw.geom_id != RTC_INVALID_GEOMETRY_ID) impl_->complete(origin, dir, raw, hit);
    return hit;
}

void RayTracer::Impl::complete(const glm::dvec3& origin, const glm::dvec3& dir, const RawHit& raw, Hit& out,
                               DeferredHits<kGroup>* deferred) const {
    const GeometryInfo& info = geometries[raw.geom_id];
    const ObjectInstance& inst = *info.instance;
    double t = raw.tfar;
    glm::dvec3 position, geometric_normal, shading_normal;

    if (inst.analytic_sphere) {
        // Exact ray-sphere distance in double, the root nearest Embree's float answer.
        if (deferred) {
            out.valid = true;
            out.object = info.object;
            out.t = t;
            deferred->add_sphere(inst.object, origin, dir, out);
            return;
        }
        const SphereHit h = exact_sphere_hit(inst.object->center, inst.object->radius, origin, dir, t);
        t = h.t;
        position = h.position;
        geometric_normal = h.normal;
        shading_normal = geometric_normal;
    } else {
        // Embree's Ng is computed from the triangle it just tested (no extra memory traffic); its sign
        // relative to our counter-clockwise-outward convention is measured once (embree_ng_sign).
        const glm::dvec3 ng(raw.ng_x, raw.ng_y, raw.ng_z);
        const double len = glm::length(ng);
        geometric_normal = len > 0.0 ? (ng_sign / len) * ng : glm::dvec3(0.0, 0.0, 1.0);
        position = origin + t * dir;

        if (inst.heightfield && deferred) {
            out.valid = true;
            out.object = info.object;
            out.t = t;
            out.position = position;
            out.geometric_normal = geometric_normal;
            deferred->add_field(inst.heightfield.get(), out);
            return;
        }
        if (inst.heightfield) {
            shading_normal = inst.heightfield->sample_normal(position.x, position.y);
        } else if (!info.corner_normals.empty()) {
            const CornerNormals& c = info.corner_normals[raw.prim_id];
            const double u = raw.u, v = raw.v;
            const glm::dvec3 ns = (1.0 - u - v) * to_d(c.n[0]) + u * to_d(c.n[1]) + v * to_d(c.n[2]);
            const double ls = glm::length(ns);
            shading_normal = ls > 0.0 ? ns / ls : geometric_normal;
        } else {
            shading_normal = geometric_normal;
        }
        // Shading normals face the geometric normal's (outward) side.
        if (glm::dot(shading_normal, geometric_normal) < 0.0) shading_normal = -shading_normal;
    }
    out.valid = true;
    out.object = info.object;
    out.t = t;
    out.position = position;
    out.geometric_normal = geometric_normal;
    out.shading_normal = shading_normal;
}

bool RayTracer::occluded(const glm::dvec3& origin, const glm::dvec3& dir, double tmin, double tmax) const {
    const RayQuery query{origin, dir, tmin, tmax};
    std::uint8_t result = 0;
    impl_->visibility(&query, 1, QueryMode::Single, &result);
    return result != 0;
}

namespace {

// Runs packet.template operator()<W>(offset, n) over a group of `count` <= kGroup queries in `mode`'s
// packets (W = 8 or 16); false for single rays, which the caller runs itself.
template <class PerWidth>
bool in_packets(QueryMode mode, int count, PerWidth&& packet) {
    if (mode == QueryMode::Packet16) {
        packet.template operator()<16>(0, count);
    } else if (mode == QueryMode::Packet8) {
        packet.template operator()<8>(0, std::min(count, 8));
        if (count > 8) packet.template operator()<8>(8, count - 8);
    } else {
        return false;
    }
    return true;
}

}  // namespace

void RayTracer::Impl::raw_hits(const RayQuery* queries, int count, QueryMode mode, RawHit* raw) const {
    const bool done = in_packets(mode, count, [&]<int W>(int offset, int n) {
        raw_hits_packet<W>(queries + offset, n, raw + offset);
    });
    if (done) return;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int k = 0; k < count; ++k) {
        const RayQuery& q = queries[k];
        const double tmin = std::max(q.tmin, min_tmin);
        check(q, tmin, "intersect");
        raw[k] = closest_single(scene, &context, q.origin, q.dir, tmin, q.tmax);
        prefetch_normals(raw[k]);
    }
}

template <int W>
void RayTracer::Impl::raw_hits_packet(const RayQuery* queries, int count, RawHit* raw) const {
    assert(count >= 1 && count <= W);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) int valid[W];
    alignas(64) typename Packet<W>::RayHit p;
    if (count < W) std::memset(&p, 0, sizeof p);   // inactive lanes hold zeros, never stale values
    for (int k = 0; k < W; ++k) {
        valid[k] = k < count ? -1 : 0;
        if (k >= count) continue;
        const double tmin = std::max(queries[k].tmin, min_tmin);
        check(queries[k], tmin, "intersect");
        set_lane(p.ray, k, queries[k], tmin);
        p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        p.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    Packet<W>::intersect(valid, scene, &context, &p);
    // A missed lane's other hit fields are not set.
    for (int k = 0; k < count; ++k) {
        raw[k] = p.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID
                     ? kMiss
                     : RawHit{p.hit.geomID[k], p.hit.primID[k], p.hit.u[k], p.hit.v[k], p.hit.Ng_x[k], p.hit.Ng_y[k],
                              p.hit.Ng_z[k], p.ray.tfar[k]};
        prefetch_normals(raw[k]);
    }
}

void RayTracer::Impl::visibility(const RayQuery* queries, int count, QueryMode mode, std::uint8_t* occluded) const {
    const bool done = in_packets(mode, count, [&]<int W>(int offset, int n) {
        visibility_packet<W>(queries + offset, n, occluded + offset);
    });
    if (done) return;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int k = 0; k < count; ++k) {
        const RayQuery& q = queries[k];
        const double tmin = std::max(q.tmin, min_tmin);
        occluded[k] = 0;
        if (!(q.tmax > tmin)) continue;   // an empty segment is not occluded
        check(q, tmin, "occluded");
        occluded[k] = occluded_single(scene, &context, q.origin, q.dir, tmin, q.tmax) ? 1 : 0;
    }
}

template <int W>
void RayTracer::Impl::visibility_packet(const RayQuery* queries, int count, std::uint8_t* occluded) const {
    assert(count >= 1 && count <= W);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    alignas(64) int valid[W];
    alignas(64) typename Packet<W>::Ray p;
    std::memset(&p, 0, sizeof p);   // lanes left out (inactive or empty) hold zeros
    for (int k = 0; k < W; ++k) {
        valid[k] = 0;
        if (k >= count) continue;
        const RayQuery& q = queries[k];
        const double tmin = std::max(q.tmin, min_tmin);
        if (!(q.tmax > tmin)) continue;   // an empty segment is not occluded
        check(q, tmin, "occluded");
        valid[k] = -1;
        set_lane(p, k, q, tmin);
    }
    Packet<W>::occluded(valid, scene, &context, &p);
    // Embree sets tfar to -inf where a ray is occluded.
    for (int k = 0; k < count; ++k) occluded[k] = valid[k] != 0 && p.tfar[k] < 0.0f ? 1 : 0;
}

void RayTracer::intersect(const RayQuery* queries, std::size_t n, Hit* hits, QueryMode mode) const {
    RawHit raw[kGroup];
    DeferredHits<kGroup> deferred;
    for (std::size_t first = 0; first < n; first += kGroup) {
        const int count = static_cast<int>(std::min<std::size_t>(kGroup, n - first));
        impl_->raw_hits(queries + first, count, mode, raw);   // prefetches the shading-normal records
        for (int k = 0; k < count; ++k) {
            const RayQuery& q = queries[first + k];
            if (raw[k].geom_id == RTC_INVALID_GEOMETRY_ID) hits[first + k] = Hit{};
            else impl_->complete(q.origin, q.dir, raw[k], hits[first + k], &deferred);
        }
        deferred.finish();
    }
}

void RayTracer::occluded(const RayQuery* queries, std::size_t n, std::uint8_t* occluded, QueryMode mode) const {
    for (std::size_t first = 0; first < n; first += kGroup)
        impl_->visibility(queries + first, static_cast<int>(std::min<std::size_t>(kGroup, n - first)), mode,
                          occluded + first);
}

}  // namespace caustics
