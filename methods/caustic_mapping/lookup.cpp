#include "lookup.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "lookup_lanes.hpp"

namespace caustics::caustic_mapping {
namespace {

// One light-view face with its per-point constants hoisted: the projection as multiplications, the
// texel side for the depth bias, and the face's G-buffer and caustic map.
struct Face : ViewProjection {
    const GBuffer* g = nullptr;
    const float* map = nullptr;
    double near_depth = 0;
    double bias_unit = 0;       // depth_bias * two texel sides (perspective: at unit depth)
    double inv_texel_area = 0;  // 1 / LightProjection::texel_area()
    int width = 1, height = 1;
    const std::uint64_t* mask = nullptr;   // LookupMask::face
    int mask_words = 0;
};

struct Faces {
    std::array<Face, 6> face;
    bool cube = false;
    bool perspective = false;
};

Faces hoist(const PositionsTexture& receivers, const std::vector<Image>& caustic, const LookupMask& mask,
            double depth_bias) {
    Faces fs;
    fs.cube = receivers.cube;
    fs.perspective = receivers.faces[0].type == ProjectionType::Perspective;
    for (std::size_t f = 0; f < receivers.faces.size() && f < fs.face.size(); ++f) {
        const LightProjection& v = receivers.faces[f];
        Face& o = fs.face[f];
        o.g = &receivers.maps[f];
        o.map = caustic[f].pixels.data();
        o.eye = v.eye, o.right = v.right, o.up = v.up, o.forward = v.forward;
        o.x0 = v.x0, o.y1 = v.y1;
        o.sx = v.pixels_per_x(), o.sy = v.pixels_per_y();
        o.near_depth = v.near_depth;
        o.bias_unit = depth_bias * 2.0 * std::sqrt(v.texel_area());
        o.inv_texel_area = 1.0 / v.texel_area();
        o.width = v.width, o.height = v.height;
        o.mask = mask.face(f), o.mask_words = mask.words();
    }
    return fs;
}

// The dot products of a receiver point's unit normal (world space) with the face's right, up and forward
// axes, which are all the depth bias and the texel area use of it.
template <class NormalFn>
inline auto normal_dots(const Face& f, NormalFn&& normal) {
    return [&f, &normal] {
        const glm::dvec3 n = normal();
        return glm::dvec3(glm::dot(n, f.right), glm::dot(n, f.up), glm::dot(n, f.forward));
    };
}

// The lookup's end where the caustic map holds flux (bilinear value `flux` != 0) at a receiver texel
// (`texel`, id not -1): the depth test, then flux / receiver area of the texel. `dots()` gives
// normal_dots' three products.
template <bool kPerspective, class DotsFn>
inline double irradiance_with_flux(const Face& f, const glm::dvec3& v, double inv_depth, std::size_t texel, float flux,
                                   DotsFn&& dots, LookupCounts& counts) {
    const double depth = v.z;
    // Shadow-map depth test with a slope-scaled bias of about two texels: bias = k (1 + tan(angle of
    // incidence)), k >= 0 two texels (at this depth, in perspective). The slope term is evaluated only
    // when the smallest bias (tan = 0) does not already pass the test.
    const glm::dvec3 nd3 = dots();
    double nd, k = f.bias_unit, r2 = 0.0;
    if constexpr (kPerspective) {
        nd = std::abs(nd3.x * v.x + nd3.y * v.y + nd3.z * v.z);
        r2 = glm::dot(v, v);
        k *= depth;
    } else {
        nd = std::abs(nd3.z);
    }
    const float stored = f.g->depth[texel];
    if (static_cast<float>(depth - k) > stored) {
        const double c = std::max(kPerspective ? nd / std::sqrt(r2) : nd, 0.05);
        if (static_cast<float>(depth - k * (1.0 + std::sqrt(1.0 - c * c) / c)) > stored) {
            ++counts.shadowed;
            return 0.0;
        }
    }
    // 1 / receiver area of one texel (LightProjection::surface_texel_area, cosine clamped at 1e-3):
    // orthographic A / cos; perspective (solid angle A z^3 / r^3) * r^2 / cos = A z^3 / |n . d|.
    double inv_area;
    if constexpr (kPerspective) {
        const double cosine_r = nd * nd >= 1e-6 * r2 ? nd : 1e-3 * std::sqrt(r2);
        inv_area = cosine_r * f.inv_texel_area * (inv_depth * inv_depth * inv_depth);
    } else {
        inv_area = std::max(nd, 1e-3) * f.inv_texel_area;
    }
    return static_cast<double>(flux) * static_cast<float>(inv_area);
}

// Irradiance at a receiver point given by its coordinates v = (x, y, depth) in face f's view space, in
// front of the eye in perspective (depth > near_depth), and by its texel coordinates (px, py) and 1 / depth
// (1 when orthographic) from project(); `dots()` gives the dot products of its unit normal with the face's
// axes (normal_dots) and is called only where the caustic map holds flux (the depth bias and the texel
// area need it).
template <bool kPerspective, class DotsFn>
inline double irradiance_at_texel(const Face& f, const glm::dvec3& v, double inv_depth, double px, double py,
                                  DotsFn&& dots, LookupCounts& counts) {
    const int W = f.width, H = f.height;
    if (!(px >= 0.0 && py >= 0.0 && px <= W && py <= H)) {
        ++counts.outside;
        return 0.0;
    }
    const int tx = std::min(static_cast<int>(px), W - 1), ty = std::min(static_cast<int>(py), H - 1);
    if (!LookupMask::test(f.mask, f.mask_words, tx, ty)) return 0.0;   // a receiver, and no flux within a texel
    const GBuffer& g = *f.g;
    const std::size_t texel = g.index(tx, ty);
    if (g.id[texel] == -1) {
        ++counts.outside;
        return 0.0;
    }
    // Bilinear between texel centres, clamped at the borders (x0 <= W - 2: the map is at least 2 wide).
    const double fx = std::clamp(px - 0.5, 0.0, W - 1.0), fy = std::clamp(py - 0.5, 0.0, H - 1.0);
    const int x0 = std::min(static_cast<int>(fx), W - 2), y0 = std::min(static_cast<int>(fy), H - 2);
    const float ax = static_cast<float>(fx - x0), ay = static_cast<float>(fy - y0);
    const float* m = f.map + g.index(x0, y0);
    const std::size_t w = static_cast<std::size_t>(W);
    const float top = m[0] + ax * (m[1] - m[0]);
    const float bottom = m[w] + ax * (m[w + 1] - m[w]);
    const float flux = top + ay * (bottom - top);
    if (flux == 0.0f) return 0.0;   // no caustic here: the depth test cannot change that
    return irradiance_with_flux<kPerspective>(f, v, inv_depth, texel, flux, dots, counts);
}

// Texel coordinates (px, py) of view-space point v (perspective: in front of the eye), and 1 / depth.
template <bool kPerspective>
inline void project(const Face& f, const glm::dvec3& v, double& inv_depth, double& px, double& py) {
    texel_coordinates<kPerspective>(f.x0, f.y1, f.sx, f.sy, v.x, v.y, v.z, inv_depth, px, py);
}

// Irradiance at view-space point v of face f (irradiance_at_texel; a point behind the near plane is
// outside the view).
template <bool kPerspective, class NormalFn>
inline double irradiance_in_view(const Face& f, const glm::dvec3& v, NormalFn&& normal, LookupCounts& counts) {
    if constexpr (kPerspective) {
        if (!(v.z > f.near_depth)) {
            ++counts.outside;
            return 0.0;
        }
    }
    double inv_depth, px, py;
    project<kPerspective>(f, v, inv_depth, px, py);
    return irradiance_at_texel<kPerspective>(f, v, inv_depth, px, py, normal_dots(f, normal), counts);
}

glm::dvec3 to_view(const Face& f, const glm::dvec3& p) {
    const glm::dvec3 d = p - f.eye;
    return {glm::dot(d, f.right), glm::dot(d, f.up), glm::dot(d, f.forward)};
}

// Irradiance at world point p.
template <bool kPerspective, class NormalFn>
inline double irradiance_at(const Faces& fs, const glm::dvec3& p, NormalFn&& normal, LookupCounts& counts) {
    const Face& f = fs.face[fs.cube ? static_cast<std::size_t>(cube_face_of(p - fs.face[0].eye)) : 0];
    return irradiance_in_view<kPerspective>(f, to_view(f, p), normal, counts);
}

// The chart's bin corners, (W + 1) x (H + 1), row-major: in the view space of the single face (the view
// transform is affine, so interpolating there is interpolating in the world), or world points for a cube
// map (`view` null), whose samples pick their face one by one.
// With a single face, also each corner's texel coordinates for the bin test (bin_without_caustic), once
// per corner instead of once per bin that shares it, and whether the bin test may use them (in front of
// the eye in perspective, finite).
template <bool kPerspective>
void fill_corners(ReceiverScratch& scratch, const ReceiverChart& chart, const Face* view) {
    const int W = chart.width(), H = chart.height();
    const std::size_t count = static_cast<std::size_t>(W + 1) * static_cast<std::size_t>(H + 1);
    scratch.corners.resize(count);
    if (view) {
        scratch.corner_px.resize(count);
        scratch.corner_py.resize(count);
        scratch.corner_usable.resize(count);
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, H + 1, 8), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i <= W; ++i) {
                const std::size_t k = static_cast<std::size_t>(j) * static_cast<std::size_t>(W + 1) + static_cast<std::size_t>(i);
                const glm::dvec3 p = chart.point(static_cast<double>(i) / W, static_cast<double>(j) / H);
                if (!view) {
                    scratch.corners[k] = p;
                    continue;
                }
                const Face& f = *view;
                const glm::dvec3 c = to_view(f, p);
                scratch.corners[k] = c;
                double x = c.x, y = c.y;
                bool front = true;
                if constexpr (kPerspective) {
                    front = c.z > f.near_depth;
                    x /= c.z;
                    y /= c.z;
                }
                const double px = (x - f.x0) * f.sx, py = (f.y1 - y) * f.sy;
                scratch.corner_px[k] = px, scratch.corner_py[k] = py;
                scratch.corner_usable[k] = front && std::isfinite(px) && std::isfinite(py);
            }
    });
}

// True when bin (corners c[0..3], indices into the scratch's corners) certainly gets no caustic: all its
// points lie in the view (perspective: in front of the eye; finite texel coordinates) and no texel of its
// footprint has its mask bit set. The
// points of the bin are convex combinations of its corners (in homogeneous coordinates, in perspective),
// so they project inside the corners' bounding box; the mask's one texel of dilation covers the bilinear
// reads. A bin that passes is left at 0: each of its lookups would return 0 and count nothing.
bool bin_without_caustic(const Face& f, const ReceiverScratch& scratch, const std::size_t c[4]) {
    double xl = 1e300, xh = -1e300, yl = 1e300, yh = -1e300;
    for (int k = 0; k < 4; ++k) {
        if (!scratch.corner_usable[c[k]]) return false;
        const double px = scratch.corner_px[c[k]], py = scratch.corner_py[c[k]];
        xl = std::min(xl, px), xh = std::max(xh, px), yl = std::min(yl, py), yh = std::max(yh, py);
    }
    constexpr double kMargin = 1e-6;   // texels: round-off of the interpolated points
    if (!(xl > kMargin && yl > kMargin && xh < f.width - kMargin && yh < f.height - kMargin)) return false;
    return !LookupMask::any(f.mask, f.mask_words, static_cast<int>(xl), static_cast<int>(yl), static_cast<int>(xh),
                            static_cast<int>(yh));
}

// Bin x's points at height v in the bin (a row of n points, left + (a + 1/2) step): by bilinear
// interpolation of its four corners (lo: the chart row's lower corners, hi: its upper ones). Exact for a
// plane (the chart is affine there), a small-footprint approximation of a height field's surface within
// one bin. The perspective divide is done per point, so a perspective view of a plane stays exact.
// Normals come from the chart itself, where they are needed.
inline void bin_row(const glm::dvec3* lo, const glm::dvec3* hi, int x, double v, double inv_n, glm::dvec3& left,
                    glm::dvec3& step) {
    left = lo[x] + v * (hi[x] - lo[x]);
    step = (lo[x + 1] + v * (hi[x + 1] - lo[x + 1]) - left) * inv_n;
}

// The mean over bin (x, y)'s n x n points (H rows of bins): `row(left, step, t, sum)` adds the lookups of
// one row of points (chart coordinate t) to `sum`, in order.
template <class RowFn>
inline float bin_mean(const glm::dvec3* lo, const glm::dvec3* hi, int x, int y, int n, int H, RowFn&& row) {
    const double inv_n = 1.0 / n;
    double sum = 0.0;
    for (int b = 0; b < n; ++b) {
        const double v = (b + 0.5) * inv_n;
        glm::dvec3 left, step;
        bin_row(lo, hi, x, v, inv_n, left, step);
        row(left, step, (y + v) / H, sum);
    }
    return static_cast<float>(sum / (static_cast<double>(n) * n));
}

// The receiver map of a single face: bins whose footprint's mask bits are all clear are skipped (left at
// 0), and each row of a bin's n x n points is projected in lanes (project_samples) before the scalar
// lookups. With a plane for receiver (kPlane) the normal is the chart's one normal, so the lookups' dot
// products with it do not change from point to point.
template <bool kPerspective, bool kPlane>
void receiver_single_face(Image& out, const ReceiverScratch& scratch, const Face& f, const ReceiverChart& chart, int n,
                          LookupCounts& counts) {
    const int W = chart.width(), H = chart.height();
    const double inv_n = 1.0 / n, inv_w = 1.0 / W;
    const glm::dvec3 plane_normal = kPlane ? chart.normal(0.5, 0.5) : glm::dvec3(0.0);
    const glm::dvec3 plane_dots = kPlane ? normal_dots(f, [&] { return plane_normal; })() : glm::dvec3(0.0);
    const std::vector<glm::dvec3>& corners = scratch.corners;
    tbb::combinable<LookupCounts> local;
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
        LookupCounts& c = local.local();
        RowLanes lanes;
        lanes.resize(static_cast<std::size_t>(n));
        for (int y = rows.begin(); y != rows.end(); ++y) {
            const std::size_t row = static_cast<std::size_t>(y) * static_cast<std::size_t>(W + 1);
            const glm::dvec3* lo = &corners[row];
            const glm::dvec3* hi = lo + (W + 1);
            for (int x = 0; x < W; ++x) {
                const std::size_t k = row + static_cast<std::size_t>(x);
                const std::size_t bin[4] = {k, k + 1, k + static_cast<std::size_t>(W + 1), k + static_cast<std::size_t>(W + 2)};
                if (bin_without_caustic(f, scratch, bin)) continue;   // 0 already
                out.at(x, y) = bin_mean(lo, hi, x, y, n, H, [&](const glm::dvec3& left, const glm::dvec3& step, double t, double& sum) {
                    project_samples(f, kPerspective, left, step, n, lanes);
                    for (int a = 0; a < n; ++a) {
                        const std::size_t i = static_cast<std::size_t>(a);
                        const glm::dvec3 q(lanes.vx[i], lanes.vy[i], lanes.vz[i]);
                        if (kPerspective && !(q.z > f.near_depth)) {
                            ++c.outside;
                            sum += 0.0;   // as the scalar pass adds the 0 it returns
                            continue;
                        }
                        auto normal = [&] { return chart.normal((x + (a + 0.5) * inv_n) * inv_w, t); };
                        auto dots = [&] {
                            if constexpr (kPlane) return plane_dots;
                            else return normal_dots(f, normal)();
                        };
                        sum += irradiance_at_texel<kPerspective>(f, q, lanes.inv_depth[i], lanes.px[i], lanes.py[i], dots, c);
                    }
                });
            }
        }
    });
    local.combine_each([&](const LookupCounts& c) { counts.outside += c.outside, counts.shadowed += c.shadowed; });
}

// The receiver map of a cube map: each point picks its face.
template <bool kPerspective>
void receiver_cube(Image& out, const std::vector<glm::dvec3>& corners, const Faces& fs, const ReceiverChart& chart,
                   int n, LookupCounts& counts) {
    const int W = chart.width(), H = chart.height();
    const double inv_n = 1.0 / n, inv_w = 1.0 / W;
    tbb::combinable<LookupCounts> local;
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 4), [&](const tbb::blocked_range<int>& rows) {
        LookupCounts& c = local.local();
        for (int y = rows.begin(); y != rows.end(); ++y) {
            const glm::dvec3* lo = &corners[static_cast<std::size_t>(y) * (W + 1)];
            const glm::dvec3* hi = lo + (W + 1);
            for (int x = 0; x < W; ++x)
                out.at(x, y) = bin_mean(lo, hi, x, y, n, H, [&](const glm::dvec3& left, const glm::dvec3& step, double t, double& sum) {
                    for (int a = 0; a < n; ++a) {
                        const glm::dvec3 q = left + (a + 0.5) * step;   // world space
                        auto normal = [&] { return chart.normal((x + (a + 0.5) * inv_n) * inv_w, t); };
                        sum += irradiance_at<kPerspective>(fs, q, normal, c);
                    }
                });
        }
    });
    local.combine_each([&](const LookupCounts& c) { counts.outside += c.outside, counts.shadowed += c.shadowed; });
}

template <bool kPerspective>
void camera_pass(Image& out, const Faces& fs, const CameraGBuffer& gb, LookupCounts& counts) {
    tbb::combinable<LookupCounts> local;
    tbb::parallel_for(tbb::blocked_range<int>(0, gb.height, 4), [&](const tbb::blocked_range<int>& rows) {
        LookupCounts& c = local.local();
        if (!fs.cube) {   // one face: each row's front half in lanes
            const Face& f = fs.face[0];
            RowLanes lanes;
            lanes.resize(static_cast<std::size_t>(gb.width));
            for (int y = rows.begin(); y != rows.end(); ++y) {
                project_row(f, kPerspective, gb.position.data() + gb.index(0, y), gb.width, lanes);
                for (int x = 0; x < gb.width; ++x) {
                    const std::size_t i = gb.index(x, y), k = static_cast<std::size_t>(x);
                    if (!gb.covered[i]) continue;
                    const glm::dvec3 v(lanes.vx[k], lanes.vy[k], lanes.vz[k]);
                    if (kPerspective && !(v.z > f.near_depth)) {
                        ++c.outside;
                        continue;   // 0
                    }
                    auto normal = [&] { return glm::dvec3(gb.normal[i]); };
                    out.at(x, y) = static_cast<float>(irradiance_at_texel<kPerspective>(
                        f, v, lanes.inv_depth[k], lanes.px[k], lanes.py[k], normal_dots(f, normal), c));
                }
            }
            return;
        }
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < gb.width; ++x) {
                const std::size_t i = gb.index(x, y);
                if (!gb.covered[i]) continue;
                auto normal = [&] { return glm::dvec3(gb.normal[i]); };
                out.at(x, y) = static_cast<float>(irradiance_at<kPerspective>(fs, glm::dvec3(gb.position[i]), normal, c));
            }
    });
    local.combine_each([&](const LookupCounts& c) { counts.outside += c.outside, counts.shadowed += c.shadowed; });
}

}  // namespace

int auto_bin_samples(const PositionsTexture& receivers, const ReceiverChart& chart) {
    double ratio = 1.0;
    const int W = chart.width(), H = chart.height();
    for (auto [s, t] : {std::pair{0.5, 0.5}, {0.02, 0.02}, {0.98, 0.02}, {0.02, 0.98}, {0.98, 0.98}}) {
        const glm::dvec3 p = chart.point(s, t);
        Texel where;
        if (!receivers.locate(p, where)) continue;
        const double texel = receivers.faces[static_cast<std::size_t>(where.face)].surface_texel_area(p, chart.normal(s, t));
        const int i = std::clamp(static_cast<int>(s * W), 0, W - 1), j = std::clamp(static_cast<int>(t * H), 0, H - 1);
        ratio = std::max(ratio, std::sqrt(chart.bin_area(i, j) / texel));
    }
    return std::clamp(static_cast<int>(std::ceil(ratio - 1e-6)), 1, 16);
}

void receiver_irradiance(Image& out, ReceiverScratch& scratch, const PositionsTexture& receivers,
                         const std::vector<Image>& caustic, const LookupMask& mask, const ReceiverChart& chart, int n,
                         double depth_bias, LookupCounts& counts) {
    const Faces fs = hoist(receivers, caustic, mask, depth_bias);
    out = Image(chart.width(), chart.height());   // bins without caustic are skipped: 0
    const Face* single = fs.cube ? nullptr : &fs.face[0];
    if (fs.perspective) fill_corners<true>(scratch, chart, single);
    else fill_corners<false>(scratch, chart, single);
    if (fs.cube) {
        if (fs.perspective) receiver_cube<true>(out, scratch.corners, fs, chart, n, counts);
        else receiver_cube<false>(out, scratch.corners, fs, chart, n, counts);
    } else if (chart.is_plane()) {
        if (fs.perspective) receiver_single_face<true, true>(out, scratch, fs.face[0], chart, n, counts);
        else receiver_single_face<false, true>(out, scratch, fs.face[0], chart, n, counts);
    } else {
        if (fs.perspective) receiver_single_face<true, false>(out, scratch, fs.face[0], chart, n, counts);
        else receiver_single_face<false, false>(out, scratch, fs.face[0], chart, n, counts);
    }
}

void camera_irradiance(Image& out, const PositionsTexture& receivers, const std::vector<Image>& caustic,
                       const LookupMask& mask, const CameraGBuffer& gb, double depth_bias, LookupCounts& counts) {
    const Faces fs = hoist(receivers, caustic, mask, depth_bias);
    out = Image(gb.width, gb.height);   // pixels without a diffuse hit: 0
    if (fs.perspective) camera_pass<true>(out, fs, gb, counts);
    else camera_pass<false>(out, fs, gb, counts);
}

}  // namespace caustics::caustic_mapping
