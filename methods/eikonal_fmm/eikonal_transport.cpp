// The transport equation along the rays of the eikonal solution (see eikonal_transport.hpp).
#include "eikonal_transport.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include <caustics/frame/baseline.hpp>
#include <caustics/scene/scene.hpp>
#include "eikonal_solver.hpp"

namespace caustics::eikonal {
namespace {

// ln of the smallest intensity kept (an unlit cell), and the largest gain over E0 before a value is
// clamped (only reachable past a focus, where the Laplacian is already clamped).
constexpr double kLnFloor = -80.0;
constexpr double kInfDepth = 1e300;
constexpr double kLnMaxGain = 20.0;  // e^20: far above any caustic before its focus
// Layers one semi-Lagrangian step spans: rays are straight in the water, so a step back along the ray
// over several layers is exact, and each interpolation of ln I (which diffuses it) serves kJump layers.
constexpr int kJump = 8;

// grad T at cell (i, j, k) by central differences (one-sided on the box's faces).
glm::dvec3 gradient(const VolumeD& T, int i, int j, int k) {
    const VolumeShape& s = T.shape;
    auto diff = [&](int a, int n, auto at) {
        const int lo = std::max(a - 1, 0), hi = std::min(a + 1, n - 1);
        return hi > lo ? (at(hi) - at(lo)) / ((hi - lo) * s.spacing) : 0.0;
    };
    return {diff(i, s.nx, [&](int q) { return T.at(q, j, k); }), diff(j, s.ny, [&](int q) { return T.at(i, q, k); }),
            diff(k, s.nz, [&](int q) { return T.at(i, j, q); })};
}

// Sliding minimum over windows [i - r, i + r] of n values spaced `stride` apart (van Herk / Gil-Werman:
// prefix and suffix minima over blocks of the window's width; values outside count as +inf).
void min_filter_1d(const double* in, double* out, int n, std::ptrdiff_t stride, int r, std::vector<double>& pre,
                   std::vector<double>& suf) {
    const int w = 2 * r + 1, m = n + 2 * r;
    pre.assign(static_cast<std::size_t>(m), kInfDepth);
    suf.assign(static_cast<std::size_t>(m), kInfDepth);
    auto at = [&](int q) { return q >= r && q < r + n ? in[(q - r) * stride] : kInfDepth; };
    for (int q = 0; q < m; ++q) pre[q] = q % w == 0 ? at(q) : std::min(pre[q - 1], at(q));
    for (int q = m - 1; q >= 0; --q) suf[q] = (q % w == w - 1 || q == m - 1) ? at(q) : std::min(suf[q + 1], at(q));
    for (int i = 0; i < n; ++i) out[i * stride] = std::min(suf[i], pre[i + w - 1]);
}

// Per column of the volume, the shallowest focus depth of the interface vertices over it (and of the
// nearest vertex, for height fields coarser than the grid).
std::vector<double> column_focus(const VolumeShape& s, const HeightField& hf, const std::vector<double>& map) {
    std::vector<double> g(static_cast<std::size_t>(s.nx) * s.ny, kInfDepth);
    auto column = [&](double x, double y, int& i, int& j) {
        i = static_cast<int>(std::floor((x - s.origin.x) / s.spacing));
        j = static_cast<int>(std::floor((y - s.origin.y) / s.spacing));
        return i >= 0 && j >= 0 && i < s.nx && j < s.ny;
    };
    for (int b = 0; b < hf.ny; ++b)
        for (int a = 0; a < hf.nx; ++a) {
            int i, j;
            if (column(hf.origin.x + a * hf.spacing.x, hf.origin.y + b * hf.spacing.y, i, j)) {
                double& v = g[static_cast<std::size_t>(j) * s.nx + i];
                v = std::min(v, map[static_cast<std::size_t>(b) * hf.nx + a]);
            }
        }
    for (int j = 0; j < s.ny; ++j)
        for (int i = 0; i < s.nx; ++i) {
            const glm::dvec3 p = s.center(i, j, 0);
            const int a = static_cast<int>(std::lround((p.x - hf.origin.x) / hf.spacing.x));
            const int b = static_cast<int>(std::lround((p.y - hf.origin.y) / hf.spacing.y));
            if (a < 0 || b < 0 || a >= hf.nx || b >= hf.ny) continue;
            double& v = g[static_cast<std::size_t>(j) * s.nx + i];
            v = std::min(v, map[static_cast<std::size_t>(b) * hf.nx + a]);
        }
    return g;
}

// ln I over the cells integrated so far (the layers above the current one), sampled where a ray back
// from a cell crosses a layer.
struct LnField {
    const VolumeShape& s;
    const VolumeF& lap;
    std::vector<double> ln;
    std::vector<std::uint8_t> known;   // ln holds a water cell's value

    LnField(const VolumeShape& shape, const VolumeF& laplacian)
        : s(shape), lap(laplacian), ln(shape.size(), kLnFloor), known(shape.size(), 0) {}

    // Bilinear sample of layer k at (x, y) over the known cells: false when they weigh too little.
    bool sample(int k, double x, double y, double& out) const {
        const double h = s.spacing;
        const double fx = (x - s.origin.x) / h - 0.5, fy = (y - s.origin.y) / h - 0.5;
        if (fx < -0.5 || fy < -0.5 || fx > s.nx - 0.5 || fy > s.ny - 0.5) return false;
        const double cx = std::clamp(fx, 0.0, s.nx - 1.0), cy = std::clamp(fy, 0.0, s.ny - 1.0);
        const int i0 = std::min(static_cast<int>(cx), s.nx - 1), j0 = std::min(static_cast<int>(cy), s.ny - 1);
        const int i1 = std::min(i0 + 1, s.nx - 1), j1 = std::min(j0 + 1, s.ny - 1);
        const double wx = cx - i0, wy = cy - j0;
        const int ii[4] = {i0, i1, i0, i1}, jj[4] = {j0, j0, j1, j1};
        const double ww[4] = {(1 - wx) * (1 - wy), wx * (1 - wy), (1 - wx) * wy, wx * wy};
        double wsum = 0.0, l = 0.0;
        for (int q = 0; q < 4; ++q) {
            if (ww[q] <= 0.0) continue;
            const std::size_t u = s.index(ii[q], jj[q], k);
            if (!known[u]) return false;
            wsum += ww[q];
            l += ww[q] * ln[u];
        }
        if (wsum <= 0.0) return false;
        out = l / wsum;
        return true;
    }

    // Bilinear Laplacian of T on layer k at (x, y) (clamped to the box).
    double laplacian(int k, double x, double y) const {
        const double h = s.spacing;
        const double cx = std::clamp((x - s.origin.x) / h - 0.5, 0.0, s.nx - 1.0);
        const double cy = std::clamp((y - s.origin.y) / h - 0.5, 0.0, s.ny - 1.0);
        const int i0 = std::min(static_cast<int>(cx), s.nx - 1), j0 = std::min(static_cast<int>(cy), s.ny - 1);
        const int i1 = std::min(i0 + 1, s.nx - 1), j1 = std::min(j0 + 1, s.ny - 1);
        const double wx = cx - i0, wy = cy - j0;
        return (1 - wy) * ((1 - wx) * lap.at(i0, j0, k) + wx * lap.at(i1, j0, k)) +
               wy * ((1 - wx) * lap.at(i0, j1, k) + wx * lap.at(i1, j1, k));
    }
};

// Past-focus flags of one layer: with a focus map, the column minimum of the vertex focus depths,
// min-filtered over the window the layer's light can enter through, moved down the mean ray; without
// one, the whole layer once it is deeper than the first focus.
class PastFocusFlags {
public:
    PastFocusFlags(const VolumeShape& s, const HeightField& hf, const TransportInput& in, glm::dvec2 run)
        : s_(s), in_(in), run_(run), flags_(static_cast<std::size_t>(s.nx) * s.ny, 0) {
        if (in.focus_map) {
            col_focus_ = column_focus(s, hf, *in.focus_map);
            filtered_.resize(col_focus_.size());
            rowpass_.resize(col_focus_.size());
        }
        shallowest_ = in.focus_map ? *std::min_element(col_focus_.begin(), col_focus_.end()) : in.first_focus_depth;
    }

    // The flags of a layer `depth` below the interface's mean height, one per column.
    const std::vector<std::uint8_t>& layer(double depth) {
        std::fill(flags_.begin(), flags_.end(), std::uint8_t(depth >= shallowest_));
        if (!in_.focus_map || depth < shallowest_) return flags_;
        const double h = s_.spacing;
        const int r = static_cast<int>(std::ceil((in_.spread * depth + h) / h));
        tbb::parallel_for(0, s_.ny, [&](int j) {
            std::vector<double> pre, suf;
            const std::size_t row = static_cast<std::size_t>(j) * s_.nx;
            min_filter_1d(&col_focus_[row], &rowpass_[row], s_.nx, 1, r, pre, suf);
        });
        tbb::parallel_for(0, s_.nx, [&](int i) {
            std::vector<double> pre, suf;
            min_filter_1d(&rowpass_[i], &filtered_[i], s_.ny, s_.nx, r, pre, suf);
        });
        const int sx = static_cast<int>(std::lround(run_.x * depth / h)), sy = static_cast<int>(std::lround(run_.y * depth / h));
        tbb::parallel_for(0, s_.ny, [&](int j) {
            for (int i = 0; i < s_.nx; ++i) {
                const int fi = std::clamp(i - sx, 0, s_.nx - 1), fj = std::clamp(j - sy, 0, s_.ny - 1);
                flags_[static_cast<std::size_t>(j) * s_.nx + i] = filtered_[static_cast<std::size_t>(fj) * s_.nx + fi] <= depth;
            }
        });
        return flags_;
    }

private:
    const VolumeShape& s_;
    const TransportInput& in_;
    glm::dvec2 run_;
    double shallowest_ = kInfDepth;
    std::vector<double> col_focus_, filtered_, rowpass_;
    std::vector<std::uint8_t> flags_;
};

// ln I at one water cell (before the past-focus fallback and the cap) and the ray direction t there.
// `clamped` counts a nearly horizontal ray.
double integrate_cell(const VolumeD& T, const LnField& field, const TransportInput& in, const glm::dvec3& light, int i,
                      int j, int k, double depth, glm::dvec3& t, std::int64_t& clamped) {
    const VolumeShape& s = T.shape;
    const double h = s.spacing;
    // Bound on |Laplacian| in the integration (a front radius of one cell): only reached at a focus.
    const double lap_limit = 1.0 / h;
    const glm::dvec3 p = s.center(i, j, k);
    const double lap_c = field.lap.data[s.index(i, j, k)];
    t = gradient(T, i, j, k);
    const double len = glm::length(t);
    if (!(len > 0.0) || t.z / len > -0.2) {
        // Nearly horizontal (or undefined) ray: no semi-Lagrangian step across a layer.
        ++clamped;
        t = glm::dvec3(0.0, 0.0, -1.0);
    } else {
        t /= len;
    }
    if (depth >= 2.0 * h) {
        // Back along the (straight) ray up to kJump layers, to the farthest layer whose cells around the
        // ray are all known, integrating -Laplacian T - Ka by the trapezoid rule over the layer crossings:
        // one interpolation of ln I per kJump layers.
        const double ds = h / -t.z;
        double integral = 0.5 * std::clamp(lap_c, -lap_limit, lap_limit), best_integral = 0.0, best = 0.0;
        int best_m = 0;
        for (int m = 1; m <= kJump && k + m < s.nz; ++m) {
            const glm::dvec3 q = p - (m * ds) * t;
            const double lq = std::clamp(field.laplacian(k + m, q.x, q.y), -lap_limit, lap_limit);
            double smp;
            if (!field.sample(k + m, q.x, q.y, smp)) break;
            best = smp;
            best_m = m;
            best_integral = integral + 0.5 * lq;
            integral += lq;
        }
        if (best_m > 0) return best - best_integral * ds - in.absorption * best_m * ds;
    }
    // At the interface: the flux E0 cos_i T dA through an interface element leaves in the refracted beam,
    // whose cross-section is cos_t dA, so I = E0 cos_i T / cos_t; then along the exact refracted ray down
    // to the cell.
    Refraction r;
    const double run = std::max(0.0, refracted_foot(*in.interface, p, light, in.ior, r));
    const double transmittance = in.fresnel ? fresnel_transmittance(r.cos_i, r.cos_t, 1.0, in.ior) : 1.0;
    const double i0 = r.lit && r.cos_t > 0.0 ? in.irradiance * r.cos_i * transmittance / r.cos_t : 0.0;
    const double lap_used = std::clamp(lap_c, -lap_limit, lap_limit);
    if (depth < 2.0 * h) t = r.direction;  // the exact ray at the interface
    return i0 > 0.0 ? std::log(i0) - lap_used * run - in.absorption * run : kLnFloor;
}

}  // namespace

void transport(const VolumeD& T, const VolumeF& lap, const TransportInput& in, VolumeF& out, TransportStats& stats) {
    const VolumeShape& s = T.shape;
    const HeightField& hf = *in.interface;
    const glm::dvec3 light = glm::normalize(in.light);
    const double ln_cap = std::log(std::max(in.irradiance, 1e-300)) + kLnMaxGain;
    out.shape = s;
    out.data.assign(s.size(), 0.0f);
    std::vector<double> column_height(static_cast<std::size_t>(s.nx) * s.ny);
    tbb::parallel_for(0, s.ny, [&](int j) {
        for (int i = 0; i < s.nx; ++i) {
            const glm::dvec3 p = s.center(i, j, 0);
            column_height[static_cast<std::size_t>(j) * s.nx + i] = extended_height(hf, p.x, p.y);
        }
    });
    // Past the first focus: the flat interface's transmitted irradiance along the mean refracted ray
    // (what the light averages to), so the values stay bounded and the flux stays near the truth's.
    double surface_z = 0.0;
    for (float z : hf.height) surface_z += z;
    surface_z /= std::max<std::size_t>(hf.height.size(), 1);
    Light sun;
    sun.direction = light;
    sun.irradiance = in.irradiance;
    const FlatTransmission flat = flat_interface_transmission(sun, 1.0, in.ior, in.fresnel);
    auto fallback_ln = [&](double z) {
        const double path = std::max(0.0, surface_z - z) / std::max(-flat.direction.z, 1e-6);
        return flat.horizontal_irradiance > 0.0
                   ? std::log(flat.horizontal_irradiance / -flat.direction.z) - in.absorption * path
                   : kLnFloor;
    };
    LnField field(s, lap);
    std::vector<std::int64_t> past(static_cast<std::size_t>(s.ny)), clamped(past.size()), nonfinite(past.size());
    PastFocusFlags past_focus(s, hf, in, glm::dvec2(flat.direction) / std::max(-flat.direction.z, 1e-6));

    for (int k = s.nz - 1; k >= 0; --k) {
        const std::vector<std::uint8_t>& layer_past = past_focus.layer(surface_z - s.center(0, 0, k).z);
        tbb::parallel_for(0, s.ny, [&](int j) {
            for (int i = 0; i < s.nx; ++i) {
                const std::size_t c = s.index(i, j, k);
                const glm::dvec3 p = s.center(i, j, k);
                const double depth = column_height[static_cast<std::size_t>(j) * s.nx + i] - p.z;
                if (depth < 0.0) continue;  // air: no light
                glm::dvec3 t;
                double ln = integrate_cell(T, field, in, light, i, j, k, depth, t, clamped[static_cast<std::size_t>(j)]);
                // Below the first focus (the shallowest point where refracted rays cross) first-arrival
                // times no longer describe the light: the discrete front rounds the focus off (its
                // Laplacian saturates near -0.06 / h on the sine scenes instead of diverging), so the
                // depth comes from the surface (blocks/regime/first_focus.hpp), not from the Laplacian.
                if (layer_past[static_cast<std::size_t>(j) * s.nx + i] != 0) {
                    ++past[static_cast<std::size_t>(j)];
                    ln = fallback_ln(p.z);
                    t = flat.direction;
                }
                if (ln > ln_cap) {
                    ln = ln_cap;
                    ++clamped[static_cast<std::size_t>(j)];
                }
                ln = std::max(ln, kLnFloor);
                field.ln[c] = ln;
                field.known[c] = 1;
                // Irradiance on a horizontal receiver: I |t . z|.
                float e = static_cast<float>(std::exp(ln) * -t.z);
                if (!std::isfinite(e)) {
                    ++nonfinite[static_cast<std::size_t>(j)];
                    e = 0.0f;
                }
                out.data[c] = ln <= kLnFloor ? 0.0f : e;
            }
        });
    }
    for (std::size_t j = 0; j < past.size(); ++j) {
        stats.past_first_focus += past[j];
        stats.clamped += clamped[j];
        stats.nonfinite += nonfinite[j];
    }
}

}  // namespace caustics::eikonal
