#include "estimator_lanes.hpp"
#include "simd.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

// The vector types never cross this file's boundary (every function taking one is internal and inlined
// into estimate_four), so the ABI note GCC gives for them under the baseline target does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace caustics::caustic_mapping {
namespace {

#define LANES_INLINE [[gnu::always_inline]] inline

constexpr int kLanes = 4;
typedef double Lanes __attribute__((vector_size(8 * kLanes)));
using Mask = decltype(Lanes{} < Lanes{});   // -1 (true) or 0 per lane

struct Lanes3 {
    Lanes x, y, z;
};

// The scalar estimator's glm operations, lane by lane, in glm's order (dot: (x + y) + z).
LANES_INLINE Lanes3 along(const Lanes3& v, const Lanes& d, const Lanes3& r) { return {v.x + d * r.x, v.y + d * r.y, v.z + d * r.z}; }
LANES_INLINE Lanes3 minus(const Lanes3& a, const Lanes3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
LANES_INLINE Lanes dot(const Lanes3& a, const Lanes3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
LANES_INLINE Lanes sqrt_lanes(Lanes a) {
    for (int l = 0; l < kLanes; ++l) a[l] = std::sqrt(a[l]);
    return a;
}
LANES_INLINE Lanes length(const Lanes3& a) { return sqrt_lanes(dot(a, a)); }
LANES_INLINE Mask finite(const Lanes& a) { return (a - a) == 0.0; }   // false for inf and NaN
LANES_INLINE Lanes abs_lanes(const Lanes& a) { return a < 0.0 ? -a : a; }   // only compared: -0 stays -0
LANES_INLINE Lanes sign(const Lanes& a) { return a < 0.0 ? Lanes{} - 1.0 : Lanes{} + 1.0; }
LANES_INLINE bool any(const Mask& m) {
    for (int l = 0; l < kLanes; ++l)
        if (m[l]) return true;
    return false;
}

// The face's constants as PositionsTexture::locate uses them.
struct Face {
    glm::dvec3 eye, forward, right, up;
    double x0, y1, sx, sy, near_depth;
    bool perspective;
    const GBuffer* g;
    explicit Face(const PositionsTexture& tex) {
        const LightProjection& f = tex.faces[0];
        eye = f.eye, forward = f.forward, right = f.right, up = f.up;
        x0 = f.x0, y1 = f.y1, near_depth = f.near_depth;
        sx = f.pixels_per_x();
        sy = f.pixels_per_y();
        perspective = f.type == ProjectionType::Perspective;
        g = &tex.maps[0];
    }
    LANES_INLINE Lanes dot_with(const Lanes3& d, const glm::dvec3& a) const { return d.x * a.x + d.y * a.y + d.z * a.z; }
    LANES_INLINE Lanes3 from_eye(const Lanes3& p) const { return {p.x - eye.x, p.y - eye.y, p.z - eye.z}; }
};

struct Lookup {
    Lanes3 q, n;   // the stored point (and normal), bilinear
    Lanes side;    // PositionsTexture::side(p, q)
    Mask ok;       // looked up, with four covered texels (else the lane goes to the scalar estimator)
};

// PositionsTexture::locate, fetch (bilinear branch) and side for the lanes in `active`.
LANES_INLINE Lookup fetch(const Face& f, const Lanes3& p, Mask active, bool want_normal) {
    Lookup out;
    const Lanes3 d = f.from_eye(p);
    const Lanes depth = f.dot_with(d, f.forward);
    Lanes x = f.dot_with(d, f.right), y = f.dot_with(d, f.up);
    Mask ok = active;
    if (f.perspective) {
        ok &= depth > f.near_depth;
        const Lanes inv_depth = 1.0 / depth;
        x *= inv_depth;
        y *= inv_depth;
    }
    const GBuffer& g = *f.g;
    const Lanes px = (x - f.x0) * f.sx, py = (f.y1 - y) * f.sy;
    ok &= (px >= 0.0) & (py >= 0.0) & (px <= static_cast<double>(g.width)) & (py <= static_cast<double>(g.height));
    const Lanes fx = px - 0.5, fy = py - 0.5;
    // Per lane: the texel (x0, y0) below and left of the point, its four texels covered; then the
    // texels' values gathered into vectors from scalars held in registers (writing them into a vector's
    // lanes one at a time went through memory and stalled on the wide reload). Lanes that are not ok
    // read texel 0 and are ignored.
    static_assert(kLanes == 4, "the gathers below list four lanes");
    std::size_t base[kLanes] = {};
    double x0s[kLanes] = {}, y0s[kLanes] = {};
    const std::size_t w = static_cast<std::size_t>(g.width);
    for (int l = 0; l < kLanes; ++l) {
        if (!ok[l]) continue;
        const int x0 = static_cast<int>(std::floor(fx[l])), y0 = static_cast<int>(std::floor(fy[l]));
        if (!(x0 >= 0 && y0 >= 0 && x0 + 1 < g.width && y0 + 1 < g.height)) {
            ok[l] = 0;
            continue;
        }
        const std::size_t i = g.index(x0, y0);
        if (g.id[i] == -1 || g.id[i + 1] == -1 || g.id[i + w] == -1 || g.id[i + w + 1] == -1) {
            ok[l] = 0;
            continue;
        }
        base[l] = i;
        x0s[l] = x0;
        y0s[l] = y0;
    }
    const Lanes ax = fx - Lanes{x0s[0], x0s[1], x0s[2], x0s[3]}, ay = fy - Lanes{y0s[0], y0s[1], y0s[2], y0s[3]};
    const std::size_t offset[4] = {0, 1, w, w + 1};   // the texels (x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)
    auto gather = [&](const std::vector<glm::vec3>& plane, int c) {
        const glm::vec3* a = plane.data() + offset[c];
        return Lanes3{Lanes{a[base[0]].x, a[base[1]].x, a[base[2]].x, a[base[3]].x},
                      Lanes{a[base[0]].y, a[base[1]].y, a[base[2]].y, a[base[3]].y},
                      Lanes{a[base[0]].z, a[base[1]].z, a[base[2]].z, a[base[3]].z}};
    };
    Lanes3 P[4], N[4];
    for (int c = 0; c < 4; ++c) P[c] = gather(g.position, c);
    if (want_normal)
        for (int c = 0; c < 4; ++c) N[c] = gather(g.normal, c);
    const Lanes w00 = (1.0 - ax) * (1.0 - ay), w10 = ax * (1.0 - ay), w01 = (1.0 - ax) * ay, w11 = ax * ay;
    auto blend = [&](const Lanes3* v) {
        return Lanes3{w00 * v[0].x + w10 * v[1].x + w01 * v[2].x + w11 * v[3].x,
                      w00 * v[0].y + w10 * v[1].y + w01 * v[2].y + w11 * v[3].y,
                      w00 * v[0].z + w10 * v[1].z + w01 * v[2].z + w11 * v[3].z};
    };
    out.q = blend(P);
    if (want_normal) {
        const Lanes3 n = blend(N);
        const Lanes len = length(n);
        const Mask positive = len > 0.0;
        out.n = {positive ? n.x / len : N[0].x, positive ? n.y / len : N[0].y, positive ? n.z / len : N[0].z};
    }
    if (f.perspective) {
        const Lanes3 dq = f.from_eye(out.q);
        out.side = dot(d, d) - dot(dq, dq);
    } else {
        out.side = depth - f.dot_with(f.from_eye(out.q), f.forward);
    }
    out.ok = ok;
    return out;
}

// Up to four rays (count); done[l]: out[l] (and normals[l]) were set.
CAUSTICS_AVX2_CLONES void estimate_four(const Face& f, const EstimatorSettings& s, const EstimateRay* rays, int count,
                                        EstimateResult* out, glm::dvec3* normals, bool* done) {
    Lanes3 v{}, r{};
    Lanes d{};
    Mask live{};
    for (int l = 0; l < kLanes; ++l) {
        const EstimateRay& ray = rays[std::min(l, count - 1)];
        v.x[l] = ray.v.x, v.y[l] = ray.v.y, v.z[l] = ray.v.z;
        r.x[l] = ray.r.x, r.y[l] = ray.r.y, r.z[l] = ray.r.z;
        d[l] = ray.d_start;
        live[l] = l < count ? -1 : 0;
    }
    const bool newton = s.kind == EstimatorKind::Newton;
    Mask scalar{};                 // lanes left to the scalar estimator
    Mask active = live;            // lanes still iterating
    Mask converged{}, have_prev{};
    Lanes prev_step{}, lookups{}, iterations{};
    for (int k = 0; k < s.iterations && any(active); ++k) {
        const Mask fin = finite(d);
        scalar |= active & ~fin;
        active &= fin;
        const Lanes3 p = along(v, d, r);
        lookups = active ? lookups + 1.0 : lookups;
        const Lookup a = fetch(f, p, active, false);
        scalar |= active & ~a.ok;
        active &= a.ok;
        Lanes next = length(minus(a.q, v));   // the approximate step
        if (newton) {
            const Lanes g = sign(a.side) * length(minus(a.q, p));
            lookups = active ? lookups + 1.0 : lookups;
            const Lookup b = fetch(f, along(v, d + s.eps, r), active, false);
            const Lanes3 pe = along(p, Lanes{} + s.eps, r);
            const Lanes deriv = (sign(b.side) * length(minus(b.q, pe)) - g) / s.eps;
            const Lanes newton_next = d - g / deriv;
            // A bad derivative (the scalar estimator then takes the approximate step and counts it).
            const Mask good = b.ok & finite(deriv) & (deriv > 1e-12) & (newton_next > 0.0) & finite(newton_next);
            scalar |= active & ~good;
            active &= good;
            next = newton_next;
        }
        const Lanes step = next - d;
        iterations = active ? iterations + 1.0 : iterations;
        const Mask oscillating = have_prev & (step * prev_step < 0.0) & (abs_lanes(step) > 0.5 * abs_lanes(prev_step)) &
                                 (abs_lanes(step) > s.tolerance);
        scalar |= active & oscillating;
        active &= ~oscillating;
        d = active ? next : d;
        prev_step = active ? step : prev_step;
        have_prev |= active;
        const Mask now = active & (abs_lanes(step) <= s.tolerance);
        converged |= now;
        active &= ~now;
    }
    Mask last = live & ~scalar;
    const Mask fin = finite(d);
    scalar |= last & ~fin;
    last &= fin;
    lookups = last ? lookups + 1.0 : lookups;
    const Lookup e = fetch(f, along(v, d, r), last, normals != nullptr);
    last &= e.ok;
    for (int l = 0; l < count; ++l) {
        done[l] = last[l] != 0;
        if (!done[l]) continue;
        EstimateResult& o = out[l];
        o = EstimateResult{};
        o.hit = true;
        o.point = {e.q.x[l], e.q.y[l], e.q.z[l]};
        o.d = d[l];
        o.lookups = static_cast<int>(lookups[l]);
        o.iterations = static_cast<int>(iterations[l]);
        o.converged = converged[l] != 0;
        if (normals) normals[l] = {e.n.x[l], e.n.y[l], e.n.z[l]};
    }
}

#undef LANES_INLINE

}  // namespace

std::size_t estimate_rays(const PositionsTexture& tex, const EstimatorSettings& s, const EstimateRay* rays,
                          std::size_t n, EstimateResult* out, glm::dvec3* normals) {
    auto scalar = [&](std::size_t k) {
        out[k] = estimate_intersection(tex, rays[k].v, rays[k].r, s, rays[k].d_start, normals ? &normals[k] : nullptr);
    };
    if (!lanes_apply(tex)) {
        for (std::size_t k = 0; k < n; ++k) scalar(k);
        return 0;
    }
    const Face f(tex);
    std::size_t finished = 0;
    for (std::size_t k = 0; k < n; k += kLanes) {
        const int count = static_cast<int>(std::min<std::size_t>(kLanes, n - k));
        bool done[kLanes] = {};
        estimate_four(f, s, rays + k, count, out + k, normals ? normals + k : nullptr, done);
        for (int l = 0; l < count; ++l) {
            if (done[l]) ++finished;
            else scalar(k + static_cast<std::size_t>(l));
        }
    }
    return finished;
}

}  // namespace caustics::caustic_mapping
