#pragma once
// An idealised light tracer for `sphere` and `pool`: a bound on what a structure-of-arrays transport could
// cost (docs/reference_throughput.md). bench_reference.cpp times it against the same anchor as the
// reference (counters ideal_over_anchor, ceiling_ideal).
//
// It traces the same photons as the reference: its Sobol' batches, their Z order and the light's
// emission. It uses the same scene in Embree (16-ray packets, coherent) and the physics the reference
// applies on these scenes:
// - the dielectric's hit: the exact ray-sphere distance, or the height field's bilinear normal
//   (HeightField::sample_normals, four lanes at a time, as the reference's);
// - Snell's law and total internal reflection;
// - Fresnel by Russian roulette where the scene asks (Scene::fresnel; neither scene does);
// - the deposit on the receiver's bins after a specular event; any other diffuse hit ends the photon;
// - with the camera view (with_camera), the reference's camera deposit of every diffuse hit after a
//   specular event: the pixel, the G-buffer's object, the sides and the cosine, then a visibility ray
//   towards the pinhole (16-ray packets), into pixel sums private to each thread.
//
// What it leaves out, each in its favour:
// - the flux ledger, media and dispersion;
// - the camera pixels' footprint table, built once outside the timed runs (the reference builds it per
//   run);
// - the generality of materials and objects (one dielectric, diffuse objects otherwise);
// - a 32-bit LCG per photon in place of the Sobol' draw of each Fresnel choice;
// - bins private to each thread (no atomic adds), never cleared;
// - every check the reference makes.
//
// Each wave's dielectric hits are stepped four lanes at a time, by hand with AVX2 and FMA.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

#include <embree3/rtcore.h>
#include <immintrin.h>
#include <glm/glm.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_reduce.h>

#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_offset.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/photon_source.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/scene/scene.hpp>

namespace ideal {

// The camera view: the pinhole, the G-buffer and each pixel's footprint (reference.cpp's pixel table).
struct IdealCamera {
    const caustics::CameraModel* model = nullptr;
    const caustics::CameraGBuffer* gbuffer = nullptr;
    std::vector<double> scale;   // max(d^2, 1e-12) / clamp(cos, 0.05, 1) per covered pixel
    double shadow_tmin = 0.0;    // the tracer's minimum tnear (scene_ray_offset)
};

// One dielectric (an exact sphere or a height field's triangles) and diffuse objects, one of them the
// receiver: what `sphere` and `pool` are.
struct IdealScene {
    RTCScene scene = nullptr;
    unsigned dielectric_geom = RTC_INVALID_GEOMETRY_ID;     // the dielectric's geometry id
    unsigned receiver_geom = RTC_INVALID_GEOMETRY_ID;
    const caustics::HeightField* heightfield = nullptr;   // null: the dielectric is the sphere below
    glm::dvec3 center{0.0};
    double radius = 1.0;
    double ior = 1.5;
    bool fresnel = false;   // Scene::fresnel: Russian roulette on Fresnel's reflectance, else TIR only
    std::uint32_t max_depth = 8;   // Scene::max_specular_depth
    const caustics::ReceiverChart* chart = nullptr;
    IdealCamera camera;   // model null: no camera view
};

// The idealised path is hand-vectorised for AVX2 and FMA only.
inline bool supported() {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    return false;
#endif
}

// The idealised path's scene where the scene is one dielectric (an exact sphere or
// a height field, without absorption, scattering or dispersion) among diffuse objects, lit by one light,
// without a medium: `sphere` and `pool`. Otherwise scene == nullptr.
inline IdealScene scene_of(const caustics::Scene& sc, const caustics::FrameGeometry& frame,
                           const caustics::RayTracer& tracer, const caustics::ReceiverChart& chart) {
    using namespace caustics;
    IdealScene s;
    if (!supported() || sc.lights.size() != 1 || sc.medium.present) return s;
    int dielectric = -1;
    for (std::size_t i = 0; i < sc.objects.size(); ++i) {
        const Material& m = sc.objects[i].material;
        if (m.type == MaterialType::Dielectric) {
            if (dielectric >= 0 || m.absorption != 0.0 || m.scattering != 0.0 || m.dispersion != 0.0) return s;
            dielectric = static_cast<int>(i);
        } else if (m.type != MaterialType::Diffuse) {
            return s;
        }
        const ObjectInstance& inst = frame.objects[i];
        if (!inst.analytic_sphere && inst.mesh.empty()) return s;   // geometry ids would not be object indices
    }
    if (dielectric < 0) return s;
    const ObjectInstance& inst = frame.objects[static_cast<std::size_t>(dielectric)];
    if (!inst.analytic_sphere && !inst.heightfield) return s;
    // RayTracer attaches one geometry per object, in order: check it with a ray down onto the dielectric.
    auto* embree = static_cast<RTCScene>(tracer.embree_scene());
    const glm::dvec3 top = 0.5 * (inst.bounds.lo + inst.bounds.hi) +
                           glm::dvec3(0.0, 0.0, inst.bounds.hi.z - inst.bounds.lo.z + 1.0);
    const Hit probe = tracer.intersect(top, {0.0, 0.0, -1.0}, 0.0, 1e30);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray = {static_cast<float>(top.x), static_cast<float>(top.y), static_cast<float>(top.z), 0.0f,
              0.0f, 0.0f, -1.0f, 0.0f, 1e30f, 0xFFFFFFFFu, 0u, 0u};
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(embree, &context, &rh);
    if (!probe.valid || probe.object != dielectric || rh.hit.geomID != static_cast<unsigned>(dielectric)) return s;
    s.scene = embree;
    s.dielectric_geom = static_cast<unsigned>(dielectric);
    s.receiver_geom = static_cast<unsigned>(sc.receiver.object_index);
    s.heightfield = inst.heightfield.get();
    s.center = inst.object->center;
    s.radius = inst.object->radius;
    s.ior = inst.object->material.ior;
    s.fresnel = sc.fresnel;
    s.max_depth = static_cast<std::uint32_t>(sc.max_specular_depth);
    s.chart = &chart;
    return s;
}

// Adds the camera view to an idealised scene: the pixel table as compute_reference makes it.
inline void with_camera(IdealScene& s, const caustics::CameraModel& model, const caustics::CameraGBuffer& gbuffer,
                        const caustics::FrameGeometry& frame) {
    IdealCamera& c = s.camera;
    c.model = &model;
    c.gbuffer = &gbuffer;
    c.shadow_tmin = caustics::scene_ray_offset(frame);
    c.scale.assign(gbuffer.covered.size(), 0.0);
    for (std::size_t i = 0; i < gbuffer.covered.size(); ++i) {
        if (!gbuffer.covered[i]) continue;
        const glm::dvec3 to_cam = model.position - glm::dvec3(gbuffer.position[i]);
        const double d2 = glm::dot(to_cam, to_cam);
        const double cos_c = d2 > 0.0 ? glm::dot(glm::dvec3(gbuffer.normal[i]), to_cam) / std::sqrt(d2) : 1.0;
        c.scale[i] = std::max(d2, 1e-12) / std::clamp(cos_c, 0.05, 1.0);
    }
}

struct Result {
    double seconds = 0.0;
    std::uint64_t rays = 0;
    std::uint64_t deposited = 0;
    std::uint64_t shadow_rays = 0;
};

// A wave's photons, one array per coordinate.
struct Wave {
    std::vector<double> ox, oy, oz, dx, dy, dz, nx, ny, nz;   // n: a height-field hit's normal
    std::vector<double> hx, hy, px, py, pz;                  // the height field's hits packed: x, y, normal
    std::vector<std::uint32_t> rng, depth, lane;             // lane: a packed hit's lane
    std::vector<float> tfar, ngx, ngy, ngz;   // ng: Embree's geometric normal (unnormalised)
    std::vector<unsigned> geom;
    void resize(std::size_t n) {
        for (auto* v : {&ngx, &ngy, &ngz}) v->resize(n);
        for (auto* v : {&ox, &oy, &oz, &dx, &dy, &dz, &nx, &ny, &nz, &hx, &hy, &px, &py, &pz}) v->resize(n);
        rng.resize(n), depth.resize(n), lane.resize(n), tfar.resize(n), geom.resize(n);
    }
};

// Lane k of a 16-ray packet: the ray origin + t dir, t in [tnear, tfar].
inline void put_lane(RTCRay16& r, int k, const glm::dvec3& o, const glm::dvec3& d, float tnear, float tfar) {
    r.org_x[k] = static_cast<float>(o.x), r.org_y[k] = static_cast<float>(o.y), r.org_z[k] = static_cast<float>(o.z);
    r.dir_x[k] = static_cast<float>(d.x), r.dir_y[k] = static_cast<float>(d.y), r.dir_z[k] = static_cast<float>(d.z);
    r.tnear[k] = tnear, r.tfar[k] = tfar, r.time[k] = 0.0f;
    r.mask[k] = 0xFFFFFFFFu, r.id[k] = 0u, r.flags[k] = 0u;
}

// n queries in 16-ray packets: lane(k, i) fills lane k from query i (lanes past n repeat the packet's
// first query, inactive), then query(k0, valid) sends the packet of queries k0 .. k0 + 15.
template <class Lane, class Query>
inline void in_packets16(std::size_t n, Lane lane, Query query) {
    for (std::size_t k0 = 0; k0 < n; k0 += 16) {
        alignas(64) int valid[16];
        for (int k = 0; k < 16; ++k) {
            valid[k] = k0 + k < n ? -1 : 0;
            lane(k, k0 + k < n ? k0 + k : k0);
        }
        query(k0, valid);
    }
}

inline RTCIntersectContext coherent_context() {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    return context;
}

// Embree's closest hits for the wave's first n rays, 16 at a time.
inline void trace(RTCScene scene, Wave& w, std::size_t n) {
    RTCIntersectContext context = coherent_context();
    alignas(64) RTCRayHit16 p;
    in_packets16(
        n,
        [&](int k, std::size_t i) {
            put_lane(p.ray, k, {w.ox[i], w.oy[i], w.oz[i]}, {w.dx[i], w.dy[i], w.dz[i]}, 1e-4f, 1e30f);
            p.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID, p.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        },
        [&](std::size_t k0, int* valid) {
            rtcIntersect16(valid, scene, &context, &p);
            for (std::size_t k = 0; k < 16 && k0 + k < n; ++k) {
                w.tfar[k0 + k] = p.ray.tfar[k];
                w.geom[k0 + k] = p.hit.geomID[k];
                w.ngx[k0 + k] = p.hit.Ng_x[k], w.ngy[k0 + k] = p.hit.Ng_y[k], w.ngz[k0 + k] = p.hit.Ng_z[k];
            }
        });
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
// The dielectric's hits, four lanes per AVX2 vector with FMA, by hand: the bound should not depend on
// what the compiler's vectoriser makes of the branches. Lanes n .. n rounded up to 4 are stepped too
// (the arrays hold a whole wave): harmless garbage, dropped with the other lanes that did not hit the
// dielectric.
__attribute__((target("avx2,fma"))) inline __m256d dot(__m256d ax, __m256d ay, __m256d az, __m256d bx, __m256d by,
                                                        __m256d bz) {
    return _mm256_fmadd_pd(ax, bx, _mm256_fmadd_pd(ay, by, _mm256_mul_pd(az, bz)));
}

// Snell's law, total internal reflection and Fresnel by Russian roulette for lanes k .. k + 3 at p with
// the outward normal n, moving along d: the new ray goes to the wave's arrays.
template <bool Fresnel>
__attribute__((target("avx2,fma"))) inline void refract4(const IdealScene& s, Wave& w, std::size_t k, __m256d px,
                                                         __m256d py, __m256d pz, __m256d nx, __m256d ny, __m256d nz,
                                                         __m256d dx, __m256d dy, __m256d dz) {
    const __m256d ior = _mm256_set1_pd(s.ior), one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd();
    const __m256d two = _mm256_set1_pd(2.0), half = _mm256_set1_pd(0.5), minus_one = _mm256_set1_pd(-1.0);
    const __m256d dn = dot(dx, dy, dz, nx, ny, nz);
    const __m256d outside = _mm256_cmp_pd(dn, zero, _CMP_LT_OQ);
    const __m256d sign = _mm256_blendv_pd(minus_one, one, outside);
    nx = _mm256_mul_pd(nx, sign), ny = _mm256_mul_pd(ny, sign), nz = _mm256_mul_pd(nz, sign);
    const __m256d cos_i = _mm256_sub_pd(zero, _mm256_mul_pd(dn, sign));
    const __m256d n_i = _mm256_blendv_pd(ior, one, outside), n_t = _mm256_blendv_pd(one, ior, outside);
    const __m256d eta = _mm256_div_pd(n_i, n_t);
    const __m256d sin2_t = _mm256_mul_pd(_mm256_mul_pd(eta, eta), _mm256_fnmadd_pd(cos_i, cos_i, one));
    const __m256d cos_t = _mm256_sqrt_pd(_mm256_max_pd(_mm256_sub_pd(one, sin2_t), zero));
    __m256d reflect = _mm256_cmp_pd(sin2_t, one, _CMP_GE_OQ);
    if constexpr (Fresnel) {
        const __m256d ici = _mm256_mul_pd(n_i, cos_i), tct = _mm256_mul_pd(n_t, cos_t);
        const __m256d tci = _mm256_mul_pd(n_t, cos_i), ict = _mm256_mul_pd(n_i, cos_t);
        const __m256d rs = _mm256_div_pd(_mm256_sub_pd(ici, tct), _mm256_add_pd(ici, tct));
        const __m256d rp = _mm256_div_pd(_mm256_sub_pd(tci, ict), _mm256_add_pd(tci, ict));
        const __m256d fresnel = _mm256_mul_pd(half, _mm256_fmadd_pd(rs, rs, _mm256_mul_pd(rp, rp)));
        __m128i state = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&w.rng[k]));
        state = _mm_add_epi32(_mm_mullo_epi32(state, _mm_set1_epi32(1664525)), _mm_set1_epi32(1013904223));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(&w.rng[k]), state);
        const __m256d u = _mm256_mul_pd(_mm256_cvtepi32_pd(_mm_srli_epi32(state, 8)), _mm256_set1_pd(0x1.0p-24));
        reflect = _mm256_or_pd(reflect, _mm256_cmp_pd(u, fresnel, _CMP_LT_OQ));
    }
    const __m256d f = _mm256_blendv_pd(eta, one, reflect);
    const __m256d g = _mm256_blendv_pd(_mm256_fmsub_pd(eta, cos_i, cos_t), _mm256_mul_pd(two, cos_i), reflect);
    const __m256d ex = _mm256_fmadd_pd(f, dx, _mm256_mul_pd(g, nx)), ey = _mm256_fmadd_pd(f, dy, _mm256_mul_pd(g, ny));
    const __m256d ez = _mm256_fmadd_pd(f, dz, _mm256_mul_pd(g, nz));
    const __m256d inv = _mm256_div_pd(one, _mm256_sqrt_pd(dot(ex, ey, ez, ex, ey, ez)));
    _mm256_storeu_pd(&w.dx[k], _mm256_mul_pd(ex, inv)), _mm256_storeu_pd(&w.dy[k], _mm256_mul_pd(ey, inv));
    _mm256_storeu_pd(&w.dz[k], _mm256_mul_pd(ez, inv));
    _mm256_storeu_pd(&w.ox[k], px), _mm256_storeu_pd(&w.oy[k], py), _mm256_storeu_pd(&w.oz[k], pz);
}

// The sphere's lanes: the exact distance nearest Embree's, the position and the outward normal, then
// refract4.
template <bool Fresnel>
__attribute__((target("avx2,fma"))) inline void step_sphere_avx2(const IdealScene& s, Wave& w, std::size_t n) {
    const __m256d cx = _mm256_set1_pd(s.center.x), cy = _mm256_set1_pd(s.center.y), cz = _mm256_set1_pd(s.center.z);
    const __m256d r2 = _mm256_set1_pd(s.radius * s.radius), inv_r = _mm256_set1_pd(1.0 / s.radius);
    const __m256d zero = _mm256_setzero_pd();
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7FFFFFFFFFFFFFFFll));
    for (std::size_t k = 0; k < n; k += 4) {
        const __m256d ox = _mm256_loadu_pd(&w.ox[k]), oy = _mm256_loadu_pd(&w.oy[k]), oz = _mm256_loadu_pd(&w.oz[k]);
        const __m256d dx = _mm256_loadu_pd(&w.dx[k]), dy = _mm256_loadu_pd(&w.dy[k]), dz = _mm256_loadu_pd(&w.dz[k]);
        const __m256d ax = _mm256_sub_pd(ox, cx), ay = _mm256_sub_pd(oy, cy), az = _mm256_sub_pd(oz, cz);
        const __m256d a = dot(dx, dy, dz, dx, dy, dz), b = dot(ax, ay, az, dx, dy, dz);
        const __m256d c = _mm256_sub_pd(dot(ax, ay, az, ax, ay, az), r2);
        const __m256d sq = _mm256_sqrt_pd(_mm256_max_pd(_mm256_fmsub_pd(b, b, _mm256_mul_pd(a, c)), zero));
        const __m256d b_pos = _mm256_cmp_pd(b, zero, _CMP_GT_OQ);
        const __m256d q = _mm256_sub_pd(zero, _mm256_add_pd(b, _mm256_blendv_pd(_mm256_sub_pd(zero, sq), sq, b_pos)));
        const __m256d t0 = _mm256_div_pd(q, a), t1 = _mm256_div_pd(c, q);
        const __m256d tf = _mm256_cvtps_pd(_mm_loadu_ps(&w.tfar[k]));
        const __m256d pick0 = _mm256_cmp_pd(_mm256_and_pd(_mm256_sub_pd(t0, tf), abs_mask),
                                            _mm256_and_pd(_mm256_sub_pd(t1, tf), abs_mask), _CMP_LT_OQ);
        const __m256d t = _mm256_blendv_pd(t1, t0, pick0);
        const __m256d px = _mm256_fmadd_pd(t, dx, ox), py = _mm256_fmadd_pd(t, dy, oy), pz = _mm256_fmadd_pd(t, dz, oz);
        const __m256d nx = _mm256_mul_pd(_mm256_sub_pd(px, cx), inv_r), ny = _mm256_mul_pd(_mm256_sub_pd(py, cy), inv_r);
        const __m256d nz = _mm256_mul_pd(_mm256_sub_pd(pz, cz), inv_r);
        refract4<Fresnel>(s, w, k, px, py, pz, nx, ny, nz, dx, dy, dz);
    }
}

// The height field's lanes: the position at Embree's distance, the normal from the wave's arrays
// (step_heightfield fills them), then refract4.
template <bool Fresnel>
__attribute__((target("avx2,fma"))) inline void refract_heightfield_avx2(const IdealScene& s, Wave& w, std::size_t n) {
    for (std::size_t k = 0; k < n; k += 4) {
        const __m256d ox = _mm256_loadu_pd(&w.ox[k]), oy = _mm256_loadu_pd(&w.oy[k]), oz = _mm256_loadu_pd(&w.oz[k]);
        const __m256d dx = _mm256_loadu_pd(&w.dx[k]), dy = _mm256_loadu_pd(&w.dy[k]), dz = _mm256_loadu_pd(&w.dz[k]);
        const __m256d t = _mm256_cvtps_pd(_mm_loadu_ps(&w.tfar[k]));
        const __m256d px = _mm256_fmadd_pd(t, dx, ox), py = _mm256_fmadd_pd(t, dy, oy), pz = _mm256_fmadd_pd(t, dz, oz);
        refract4<Fresnel>(s, w, k, px, py, pz, _mm256_loadu_pd(&w.nx[k]), _mm256_loadu_pd(&w.ny[k]),
                          _mm256_loadu_pd(&w.nz[k]), dx, dy, dz);
    }
}
#endif

// Every lane stepped as a hit on the dielectric (the caller drops the others). A height field's normal is
// its bilinear gradient's (HeightField::sample_normals, four lanes at a time, as the reference's). Only
// where supported().
inline void step_dielectric(const IdealScene& s, Wave& w, std::size_t n) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    if (!s.heightfield) return s.fresnel ? step_sphere_avx2<true>(s, w, n) : step_sphere_avx2<false>(s, w, n);
    // The dielectric's hits only, packed, then their normals back to their lanes.
    std::size_t m = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const double t = w.tfar[k];
        w.lane[m] = static_cast<std::uint32_t>(k);
        w.hx[m] = w.ox[k] + t * w.dx[k], w.hy[m] = w.oy[k] + t * w.dy[k];
        m += w.geom[k] == s.dielectric_geom;
    }
    s.heightfield->sample_normals(w.hx.data(), w.hy.data(), m, w.px.data(), w.py.data(), w.pz.data());
    for (std::size_t j = 0; j < m; ++j) {
        const std::uint32_t k = w.lane[j];
        w.nx[k] = w.px[j], w.ny[k] = w.py[j], w.nz[k] = w.pz[j];
    }
    s.fresnel ? refract_heightfield_avx2<true>(s, w, n) : refract_heightfield_avx2<false>(s, w, n);
#endif
}

// A wave's camera deposits waiting for their visibility rays.
struct Shadows {
    std::vector<glm::dvec3> origin, dir;
    std::vector<double> tmax;
    std::vector<std::size_t> pixel;
    std::vector<std::int64_t> increment;
    void clear() {
        origin.clear(), dir.clear(), tmax.clear(), pixel.clear(), increment.clear();
    }
};

// The reference's deposit_camera for lane k, a diffuse hit after a specular event (weight 1: one light,
// no absorption). The diffuse objects are planes: the shading normal is the geometric one.
inline void camera_deposit(const IdealScene& s, const Wave& w, std::size_t k, Shadows& out) {
    const IdealCamera& c = s.camera;
    const double t = w.tfar[k];
    const glm::dvec3 p(w.ox[k] + t * w.dx[k], w.oy[k] + t * w.dy[k], w.oz[k] + t * w.dz[k]);
    double px, py;
    if (!c.model->project(p, px, py)) return;
    if (!(px >= 0.0 && py >= 0.0 && px < c.gbuffer->width && py < c.gbuffer->height)) return;
    const std::size_t pixel = c.gbuffer->index(static_cast<int>(px), static_cast<int>(py));
    if (c.gbuffer->object[pixel] != static_cast<int>(w.geom[k])) return;   // geometry ids are object indices
    glm::dvec3 to_camera = c.model->position - p;
    const double dist = glm::length(to_camera);
    if (!(dist > 0.0)) return;
    to_camera /= dist;
    const glm::dvec3 n = glm::normalize(glm::dvec3(w.ngx[k], w.ngy[k], w.ngz[k]));
    const double side = w.dx[k] * n.x + w.dy[k] * n.y + w.dz[k] * n.z < 0.0 ? 1.0 : -1.0;
    const double cos_c = side * glm::dot(n, to_camera);
    if (cos_c <= 0.0) return;
    const double x = c.scale[pixel] * cos_c / (dist * dist);
    out.origin.push_back(p), out.dir.push_back(to_camera), out.tmax.push_back(dist * (1.0 - 1e-6));
    out.pixel.push_back(pixel), out.increment.push_back(static_cast<std::int64_t>(x * 1073741824.0 + 0.5));
}

// The visibility rays, 16 at a time; a visible deposit adds to the thread's pixel sums.
inline void resolve_shadows(const IdealScene& s, const Shadows& q, std::vector<std::int64_t>& pixel_sums) {
    RTCIntersectContext context = coherent_context();
    const std::size_t n = q.origin.size();
    const float tmin = static_cast<float>(s.camera.shadow_tmin);
    alignas(64) RTCRay16 r;
    in_packets16(
        n, [&](int k, std::size_t i) { put_lane(r, k, q.origin[i], q.dir[i], tmin, static_cast<float>(q.tmax[i])); },
        [&](std::size_t k0, int* valid) {
            rtcOccluded16(valid, s.scene, &context, &r);
            for (std::size_t k = 0; k < 16 && k0 + k < n; ++k)   // Embree sets tfar to -inf where occluded
                if (!(r.tfar[k] < 0.0f)) pixel_sums[q.pixel[k0 + k]] += q.increment[k0 + k];
        });
}

// Batch b of a reference's photons: batches of kPhotonBatch per replica, replica after replica, as
// compute_reference makes them.
constexpr std::uint64_t kPhotonBatch = 65536;
struct PhotonBatch {
    std::uint32_t replica;
    std::uint64_t first;   // the batch's first photon index within its replica
    std::size_t n;
    caustics::SamplerSeeds seeds;
    PhotonBatch(std::uint64_t b, std::uint64_t batches_per_replica, std::uint64_t per_replica,
                const caustics::ReferenceSettings& settings)
        : replica(static_cast<std::uint32_t>(b / batches_per_replica)),
          first((b % batches_per_replica) * kPhotonBatch),
          n(static_cast<std::size_t>(std::min(per_replica, first + kPhotonBatch) - first)),
          seeds(caustics::PhotonSampler::seeds(settings.sampler, settings.seed, replica)) {}
};

// A thread's buffers, kept from one run to the next (as the reference keeps its own, util/huge_pages.hpp):
// fresh pages would cost a run a page fault each.
struct ThreadBuffers {
    std::vector<glm::dvec2> by_index, emission;
    std::vector<std::uint32_t> order;
    caustics::SortScratch scratch;
    std::vector<glm::dvec3> origins, dirs;
    std::vector<std::int64_t> bin_sums, pixel_sums;
    Shadows shadows;
    Wave w;
};
using Buffers = tbb::enumerable_thread_specific<ThreadBuffers>;

// The reference's photons (settings.photons over settings.replicas, batches of 65,536) through the
// idealised path; returns its time, rays and deposits. Only where supported().
inline Result run(const IdealScene& s, const caustics::Emitter& emitter, const caustics::ReferenceSettings& settings,
                  Buffers& buffers) {
    using namespace caustics;
    constexpr std::size_t kWave = 512;
    const auto replicas = static_cast<std::uint64_t>(settings.replicas);
    const std::uint64_t per_replica = (settings.photons + replicas - 1) / replicas;
    const std::uint64_t batches = (per_replica + kPhotonBatch - 1) / kPhotonBatch;
    const std::size_t bins = static_cast<std::size_t>(s.chart->width()) * s.chart->height();
    struct Counts {
        std::uint64_t rays = 0, deposited = 0, shadow_rays = 0;
    };
    const bool camera = s.camera.model != nullptr;
    const std::size_t pixels = camera ? s.camera.gbuffer->covered.size() : 0;
    const auto start = std::chrono::steady_clock::now();
    const Counts total = tbb::parallel_reduce(
        tbb::blocked_range<std::uint64_t>(0, batches * replicas, 1), Counts{},
        [&](const tbb::blocked_range<std::uint64_t>& range, Counts acc) {
            ThreadBuffers& t = buffers.local();
            auto& [by_index, emission, order, scratch, origins, dirs, bin_sums, pixel_sums, shadows, w] = t;
            origins.resize(kWave), dirs.resize(kWave), bin_sums.resize(bins), pixel_sums.resize(pixels), w.resize(kWave);
            for (std::uint64_t b = range.begin(); b < range.end(); ++b) {
                const PhotonBatch batch(b, batches, per_replica, settings);
                const auto [replica, first, n, seeds] = batch;
                by_index.resize(n);
                PhotonSampler::emissions(seeds, first, n, reinterpret_cast<double*>(by_index.data()));
                photon_batch_order(1, first, by_index, order, scratch);
                emission.resize(n);
                for (std::size_t j = 0; j < n; ++j) emission[j] = by_index[order[j]];
                for (std::size_t w0 = 0; w0 < n; w0 += kWave) {
                    std::size_t live = std::min(kWave, n - w0);
                    emitter.sample_many(emission.data() + w0, live, origins.data(), dirs.data());
                    for (std::size_t k = 0; k < live; ++k) {
                        w.ox[k] = origins[k].x, w.oy[k] = origins[k].y, w.oz[k] = origins[k].z;
                        w.dx[k] = dirs[k].x, w.dy[k] = dirs[k].y, w.dz[k] = dirs[k].z;
                        w.rng[k] = static_cast<std::uint32_t>((first + w0 + k) * 2654435761u) ^ replica;
                        w.depth[k] = 0;
                    }
                    while (live > 0) {
                        trace(s.scene, w, live);
                        acc.rays += live;
                        // Receiver hits deposit (after a specular event) before the step moves origins.
                        shadows.clear();
                        for (std::size_t k = 0; k < live; ++k) {
                            if (w.depth[k] == 0 || w.geom[k] == s.dielectric_geom || w.geom[k] == RTC_INVALID_GEOMETRY_ID)
                                continue;
                            if (camera) camera_deposit(s, w, k, shadows);
                            if (w.geom[k] != s.receiver_geom) continue;
                            const double tf = w.tfar[k];
                            const int bin = s.chart->bin_of({w.ox[k] + tf * w.dx[k], w.oy[k] + tf * w.dy[k], w.oz[k] + tf * w.dz[k]});
                            if (bin >= 0) ++bin_sums[static_cast<std::size_t>(bin)], ++acc.deposited;
                        }
                        if (!shadows.origin.empty()) {
                            resolve_shadows(s, shadows, pixel_sums);
                            acc.shadow_rays += shadows.origin.size();
                        }
                        step_dielectric(s, w, live);
                        // The dielectric's hits go on; the rest end.
                        std::size_t next = 0;
                        for (std::size_t k = 0; k < live; ++k) {
                            if (w.geom[k] != s.dielectric_geom || w.depth[k] + 1 > s.max_depth) continue;
                            w.ox[next] = w.ox[k], w.oy[next] = w.oy[k], w.oz[next] = w.oz[k];
                            w.dx[next] = w.dx[k], w.dy[next] = w.dy[k], w.dz[next] = w.dz[k];
                            w.rng[next] = w.rng[k], w.depth[next] = w.depth[k] + 1;
                            ++next;
                        }
                        live = next;
                    }
                }
            }
            return acc;
        },
        [](Counts a, const Counts& b) {
            a.rays += b.rays, a.deposited += b.deposited, a.shadow_rays += b.shadow_rays;
            return a;
        });
    return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), total.rays,
            total.deposited, total.shadow_rays};
}

}  // namespace ideal
