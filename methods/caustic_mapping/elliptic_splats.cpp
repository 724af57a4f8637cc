#include "elliptic_splats.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::caustic_mapping {
namespace {

constexpr int kBandRows = 16;
constexpr float kMaxSigma = kMaxAdaptiveRadius / kEllipticCutoff;   // the isotropic footprint's cap
constexpr double kWideSigma = 1.0;   // texels: footprints at least this wide are normalised in closed form

// Covariance with its eigenvalues clamped to [lo^2, kMaxSigma^2].
glm::vec3 clamp_cov(glm::vec3 c, float lo) {
    const double a = c.x, b = c.y, d = c.z;
    const double mean = 0.5 * (a + d), dev = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
    const double l1 = mean + dev, l2 = mean - dev;
    const double lo2 = static_cast<double>(lo) * lo, hi2 = static_cast<double>(kMaxSigma) * kMaxSigma;
    const double c1 = std::clamp(l1, lo2, hi2), c2 = std::clamp(l2, lo2, hi2);
    if (c1 == l1 && c2 == l2) return c;
    // Eigenvector of l1: (b, l1 - a) or (l1 - d, b); an isotropic matrix has any.
    glm::dvec2 e = std::abs(b) > 1e-30 ? glm::dvec2(b, l1 - a) : (a >= d ? glm::dvec2(1, 0) : glm::dvec2(0, 1));
    e /= glm::length(e);
    const glm::dvec2 f(-e.y, e.x);
    return glm::vec3(static_cast<float>(c1 * e.x * e.x + c2 * f.x * f.x), static_cast<float>(c1 * e.x * e.y + c2 * f.x * f.y),
                     static_cast<float>(c1 * e.y * e.y + c2 * f.y * f.y));
}

struct Print {
    int x0, x1, y0, y1;     // support (may leave the image)
    double ixx, ixy, iyy;   // 1/2 of the inverse covariance
    double scale;           // value / (sum of the weights over the whole support)
};

// exp(-q) for q in [0, kQMax] (the cut-off ellipse; clamped), linear interpolation in a table: the
// splats' inner loops then cost a few multiply-adds per texel, no exponential (a per-row exp made the
// elliptical footprints six times slower than the separable isotropic ones). Relative error below 1e-7.
class NegExpTable {
public:
    static constexpr int kSize = 8192;
    static constexpr double kQMax = 0.5 * kEllipticCutoff * kEllipticCutoff + 0.5;
    NegExpTable() {
        for (int k = 0; k <= kSize + 1; ++k) t_[static_cast<std::size_t>(k)] = std::exp(-k * kQMax / kSize);
    }
    double operator()(double q) const {
        const double x = std::clamp(q, 0.0, kQMax) * (kSize / kQMax);
        const int k = std::min(static_cast<int>(x), kSize);
        const double f = x - k;
        return t_[static_cast<std::size_t>(k)] + f * (t_[static_cast<std::size_t>(k) + 1] - t_[static_cast<std::size_t>(k)]);
    }

private:
    std::array<double, kSize + 2> t_{};
};

const NegExpTable& neg_exp() {
    static const NegExpTable table;   // thread-safe initialisation, once
    return table;
}

// Calls f(i, w) for the texels i of row j whose centres lie inside the splat's cut-off ellipse, with
// their weights exp(-q), q = (d^T Sigma^-1 d) / 2. Both passes (normalisation and drawing) use this one function, so they see the same
// texels and weights.
template <class F>
inline void row_weights(const Print& p, glm::dvec2 c, int j, const NegExpTable& ex, F&& f) {
    const double dy = j + 0.5 - c.y;
    const double qmax = 0.5 * kEllipticCutoff * kEllipticCutoff;
    double lo, hi;   // offsets dx of the ellipse's chord on this row
    if (p.ixx > 0.0) {
        const double disc = p.ixy * p.ixy * dy * dy - p.ixx * (p.iyy * dy * dy - qmax);
        if (disc < 0.0) return;
        const double root = std::sqrt(disc);
        lo = (-p.ixy * dy - root) / p.ixx, hi = (-p.ixy * dy + root) / p.ixx;
    } else {   // the nearest-texel fallback (no quadratic form): the one texel (x0, y0)
        if (j == p.y0) f(p.x0, 1.0);
        return;
    }
    const int i0 = std::max(static_cast<int>(std::ceil(c.x - 0.5 + lo)), p.x0);
    const int i1 = std::min(static_cast<int>(std::floor(c.x - 0.5 + hi)), p.x1);
    if (i0 > i1) return;
    // q(i) = ixx u^2 + (2 ixy dy) u + iyy dy^2, u = i + 1/2 - c.x: evaluated per texel (independent
    // iterations pipeline better than a running recurrence).
    const double b = 2.0 * p.ixy * dy, c0 = p.iyy * dy * dy, u0 = 0.5 - c.x;
    for (int i = i0; i <= i1; ++i) {
        const double u = i + u0;
        f(i, ex((p.ixx * u + b) * u + c0));
    }
}

}  // namespace

int build_elliptic_splats(const std::vector<FaceSplat>& landing, int grid, float min_radius,
                          std::vector<std::vector<EllipticSplat>>& per_face) {
    // The isotropic footprints first (same order: landed texels row-major, per face): the fallback where
    // an axis has no landed neighbour.
    std::vector<std::vector<Splat>> iso(per_face.size());
    const int isolated = build_splats(landing, grid, FootprintMode::Adaptive, min_radius, iso);
    for (auto& v : per_face) v.clear();
    const int g = grid;
    const float sigma0 = min_radius / kEllipticCutoff;
    auto at = [&](int x, int y, int face) -> const Splat* {
        if (x < 0 || y < 0 || x >= g || y >= g) return nullptr;
        const FaceSplat& o = landing[static_cast<std::size_t>(y) * g + x];
        return o.splat.value > 0.0f && o.face == face ? &o.splat : nullptr;
    };
    // Column of J along grid offset (dx, dy): central difference, one-sided at an edge of the lit region.
    auto column = [&](int x, int y, int face, const Splat& c, int dx, int dy, glm::vec2& j) {
        const Splat* p = at(x + dx, y + dy, face);
        const Splat* m = at(x - dx, y - dy, face);
        if (p && m) j = 0.5f * (p->pixel - m->pixel);
        else if (p) j = p->pixel - c.pixel;
        else if (m) j = c.pixel - m->pixel;
        else return false;
        return true;
    };
    std::vector<std::size_t> next(per_face.size(), 0);
    for (int y = 0; y < g; ++y)
        for (int x = 0; x < g; ++x) {
            const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
            if (!(fs.splat.value > 0.0f)) continue;
            const std::size_t face = static_cast<std::size_t>(fs.face);
            const Splat& fallback = iso[face][next[face]++];
            glm::vec2 jx, jy;
            glm::vec3 cov;
            if (column(x, y, fs.face, fs.splat, 1, 0, jx) && column(x, y, fs.face, fs.splat, 0, 1, jy)) {
                const float s2 = kEllipticSigma * kEllipticSigma, o2 = sigma0 * sigma0;
                cov = {s2 * (jx.x * jx.x + jy.x * jy.x) + o2, s2 * (jx.x * jx.y + jy.x * jy.y),
                       s2 * (jx.y * jx.y + jy.y * jy.y) + o2};
            } else {
                const float s = fallback.radius / kEllipticCutoff;
                cov = {s * s, 0.0f, s * s};
            }
            per_face[face].push_back({fs.splat.pixel, fs.splat.value, clamp_cov(cov, sigma0)});
        }
    return isolated;
}

SplatStats draw_elliptic(const std::vector<EllipticSplat>& splats, Image& target) {
    const int W = target.width, H = target.height;
    const std::size_t n = splats.size();
    std::vector<Print> prints(n);
    std::vector<std::uint8_t> valid(n, 0);
    std::vector<double> inside(n, 0.0);
    const NegExpTable& ex = neg_exp();
    // Per splat: support, inverse covariance, normalisation over the whole support.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k) {
            const EllipticSplat& s = splats[k];
            if (!std::isfinite(s.pixel.x) || !std::isfinite(s.pixel.y) || !std::isfinite(s.value) ||
                std::abs(s.pixel.x) > 1e8f || std::abs(s.pixel.y) > 1e8f)
                continue;
            const double a = s.cov.x, b = s.cov.y, d = s.cov.z, det = a * d - b * b;
            if (!(det > 0.0) || !std::isfinite(det)) continue;
            Print p;
            p.ixx = 0.5 * d / det, p.ixy = -0.5 * b / det, p.iyy = 0.5 * a / det;
            const double hx = kEllipticCutoff * std::sqrt(a), hy = kEllipticCutoff * std::sqrt(d);
            p.x0 = static_cast<int>(std::ceil(s.pixel.x - 0.5 - hx)), p.x1 = static_cast<int>(std::floor(s.pixel.x - 0.5 + hx));
            p.y0 = static_cast<int>(std::ceil(s.pixel.y - 0.5 - hy)), p.y1 = static_cast<int>(std::floor(s.pixel.y - 0.5 + hy));
            double sum = 0.0, in = 0.0;
            const glm::dvec2 c(s.pixel);
            const bool in_image = p.x0 >= 0 && p.y0 >= 0 && p.x1 < W && p.y1 < H;
            const double minor2 = 0.5 * (a + d) - std::sqrt(0.25 * (a - d) * (a - d) + b * b);   // smaller eigenvalue
            if (in_image && minor2 >= kWideSigma * kWideSigma) {
                // Wide and wholly inside the image: the sum of the weights over the texel centres is the
                // Gaussian's integral over the cut-off ellipse, 2 pi sqrt(det) (1 - exp(-R^2 / 2)), to
                // within 1e-4 (Poisson summation: the sampled Gaussian's sum differs from its integral
                // by 2 exp(-2 pi^2 sigma^2), 5e-9 at sigma = 1; the rest is the ellipse's boundary), so
                // the normalising pass over the footprint is needed only near the image's edges and for
                // narrow footprints (folds, foci), where it is exact.
                sum = 2.0 * M_PI * std::sqrt(det) * (1.0 - std::exp(-0.5 * kEllipticCutoff * kEllipticCutoff));
                in = sum;
            } else {
                for (int j = p.y0; j <= p.y1; ++j) {
                    const bool row_in = j >= 0 && j < H;
                    row_weights(p, c, j, ex, [&](int i, double w) {
                        sum += w;
                        if (row_in && i >= 0 && i < W) in += w;
                    });
                }
            }
            if (!(sum > 0.0)) {   // a footprint narrower than a texel between centres: the nearest texel
                p.x0 = p.x1 = static_cast<int>(std::floor(s.pixel.x));
                p.y0 = p.y1 = static_cast<int>(std::floor(s.pixel.y));
                p.ixx = p.ixy = p.iyy = 0.0;
                sum = 1.0;
                in = (p.x0 >= 0 && p.y0 >= 0 && p.x0 < W && p.y0 < H) ? 1.0 : 0.0;
            }
            p.scale = s.value / sum;
            prints[k] = p;
            inside[k] = in / sum;
            valid[k] = 1;
        }
    });
    SplatStats st;
    // Splats per band of rows, in input order.
    const int bands = (H + kBandRows - 1) / kBandRows;
    std::vector<std::vector<std::uint32_t>> in_band(static_cast<std::size_t>(bands));
    for (std::size_t k = 0; k < n; ++k) {
        const EllipticSplat& s = splats[k];
        if (!valid[k]) {
            ++st.nonfinite;
            continue;
        }
        st.value_inside += s.value * inside[k];
        st.value_outside += s.value * (1.0 - inside[k]);
        if (!(inside[k] > 0.0)) {
            ++st.outside;
            continue;
        }
        ++st.splatted;
        const Print& p = prints[k];
        for (int b = std::max(p.y0, 0) / kBandRows; b <= std::min(p.y1, H - 1) / kBandRows; ++b)
            in_band[static_cast<std::size_t>(b)].push_back(static_cast<std::uint32_t>(k));
    }
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& r) {
        for (int b = r.begin(); b != r.end(); ++b) {
            const int r0 = b * kBandRows, r1 = std::min(H, r0 + kBandRows) - 1;
            for (std::uint32_t k : in_band[static_cast<std::size_t>(b)]) {
                Print p = prints[k];   // its columns clipped to the image: the same weights, fewer texels
                p.x0 = std::max(p.x0, 0), p.x1 = std::min(p.x1, W - 1);
                const glm::dvec2 c(splats[k].pixel);
                const double scale = p.scale;
                for (int j = std::max(p.y0, r0); j <= std::min(p.y1, r1); ++j) {
                    float* row = &target.at(0, j);
                    row_weights(p, c, j, ex, [&](int i, double w) { row[i] += static_cast<float>(scale * w); });
                }
            }
        }
    });
    return st;
}

}  // namespace caustics::caustic_mapping
