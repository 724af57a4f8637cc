#include "elliptic_splats.hpp"
#include "simd.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

namespace caustics::caustic_mapping {
namespace {

constexpr int kBandRows = 16;
constexpr float kMaxSigma = kMaxAdaptiveRadius / kEllipticCutoff;   // the isotropic footprint's cap
// Half-widths of a support beyond this many texels are refused: build_elliptic_splats' reach at most
// kMaxAdaptiveRadius (64), and a support of 1e6 texels across would take seconds to normalise.
constexpr double kMaxHalfWidth = 4096.0;
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
    double ixx, ixy, iyy;   // 1/2 of the inverse covariance (ixx = 0: the nearest-texel fallback)
    double slope, reach, narrow;   // the cut-off ellipse's chords: see row_span
    double scale;           // value / (sum of the weights over the whole support)
    std::int32_t kept_rows = -1;   // >= 0: its weights were kept (KeptWeights::rows from here); -1: recomputed
};

// One row of a splat's footprint whose weights were kept by the normalising pass: texels [i0, i0 + n)
// of the row, their weights at KeptWeights::weights[w], followed by zeros up to a multiple of kChunk
// (footprint_sum_kept).
struct KeptRow {
    std::int32_t i0, n;
    std::uint32_t w;
};

// The weights of a fixed group of splats (kKeptGroup, in input order), kept from the normalising pass
// for the drawing pass. Footprints narrower than kWideSigma (nearly every splat of a focusing caustic:
// 98 % on the sphere scene) are normalised by summing their weights; keeping those weights lets the
// drawing pass read them instead of evaluating every exponential a second time.
struct KeptWeights {
    std::vector<KeptRow> rows;   // per splat: one per row y0 .. y1
    std::vector<float> weights;
};
constexpr std::size_t kKeptGroup = 256;

// The weights of one row of a footprint: texels [i0, i1] (their centres inside the cut-off ellipse),
// weight exp(-q), q(i) = a t^2 + c0 with t = i - mid (the texel's offset from the chord's midpoint).
struct RowSpan {
    int i0 = 0, i1 = -1;
    double mid = 0;
    float a = 0, c0 = 0;
    float offset(int i) const { return static_cast<float>(i - mid); }   // t at texel i, rounded once
};

constexpr double kQCut = 0.5 * kEllipticCutoff * kEllipticCutoff;   // q on the cut-off ellipse
constexpr float kQMax = static_cast<float>(kQCut) + 0.5f;

// exp(-q) for q in [0, kQMax] (clamped) in single precision, branch-free so that the loops over a row
// vectorise: exp(-q) = 2^t, t = -q log2(e) = n + f with n = round(t) and |f| <= 1/2; 2^f by its Taylor
// polynomial of degree 6 (remainder (ln 2 / 2)^7 / 7! = 1.2e-7, about one float ulp), 2^n put into the
// exponent bits (n >= -10 here, no denormals). It replaced a lookup table whose gathers kept the loops
// scalar; the weights agree with std::exp to a few 1e-7 relative (tested).
inline float neg_exp(float q) {
    q = std::min(std::max(q, 0.0f), kQMax);
    const float t = -1.44269504f * q;
    const int n = static_cast<int>(t + 64.5f) - 64;   // round(t): truncation of a positive number
    const float f = t - static_cast<float>(n);
    float p = 1.53527e-4f;   // (ln 2)^k / k!, k = 6 .. 0
    p = p * f + 1.33335581e-3f;
    p = p * f + 9.61812911e-3f;
    p = p * f + 5.55041087e-2f;
    p = p * f + 2.40226507e-1f;
    p = p * f + 6.93147181e-1f;
    p = p * f + 1.0f;
    return p * std::bit_cast<float>((n + 127) << 23);
}

// Per-splat constants of the chords, set once so that a row costs one square root and no division:
// row j's chord is dx in [-slope dy - h, -slope dy + h], h = sqrt(reach - narrow dy^2), dy = j + 1/2 -
// c.y (the roots of ixx dx^2 + 2 ixy dy dx + iyy dy^2 = R^2 / 2, divided through by ixx).
inline void set_chords(Print& p) {
    if (!(p.ixx > 0.0)) return;
    p.slope = p.ixy / p.ixx;
    p.reach = kQCut / p.ixx;
    p.narrow = p.iyy / p.ixx - p.slope * p.slope;
}

// The span of row j: the texels whose centres lie inside the splat's cut-off ellipse (q <= R^2 / 2).
// Both passes (normalisation and drawing) use this one function, so they see the same texels and weights.
// The nearest-texel fallback (no quadratic form) is the one texel (x0, y0) with weight exp(0) = 1.
inline RowSpan row_span(const Print& p, glm::dvec2 c, int j) {
    RowSpan s;
    if (!(p.ixx > 0.0)) {
        if (j == p.y0) s.i0 = s.i1 = p.x0;
        return s;
    }
    const double dy = j + 0.5 - c.y;
    const double h2 = p.reach - p.narrow * dy * dy;
    if (h2 < 0.0) return s;
    const double h = std::sqrt(h2), mid = c.x - 0.5 - p.slope * dy;
    s.i0 = std::max(static_cast<int>(std::ceil(mid - h)), p.x0);
    s.i1 = std::min(static_cast<int>(std::floor(mid + h)), p.x1);
    // q(i) = ixx u^2 + 2 ixy dy u + iyy dy^2 (u = i + 1/2 - c.x) completed to a square about the chord's
    // midpoint: ixx (i - mid)^2 + ixx narrow dy^2, both terms >= 0. In single precision each term then
    // carries a relative rounding error of a few 1e-7 of itself, and neither exceeds q's cut-off (6.1),
    // whereas the expanded form's terms grow to 1e3 and more on long, sheared footprints and cancel.
    s.mid = mid;
    s.a = static_cast<float>(p.ixx);
    s.c0 = static_cast<float>(p.ixx * p.narrow * dy * dy);
    return s;
}

// Sum of the weights of texels [i0, i1] of a row.
inline float row_sum(const RowSpan& s, int i0, int i1) {
    float sum = 0.0f;
    const float a = s.a, c0 = s.c0, t0 = s.offset(i0);
    const int n = i1 - i0 + 1;
#pragma omp simd reduction(+ : sum)
    for (int k = 0; k < n; ++k) {
        const float t = static_cast<float>(k) + t0;
        sum += neg_exp(a * t * t + c0);
    }
    return sum;
}

// The splat loops have an AVX2 version (simd.hpp): the drawn weights are the same on every machine.

// The sum of the splat's weights over its whole support, and over the part inside a W x H image.
CAUSTICS_AVX2_CLONES void footprint_sums(const Print& p, glm::dvec2 c, int W, int H, double& sum, double& in) {
    sum = in = 0.0;
    for (int j = p.y0; j <= p.y1; ++j) {
        const RowSpan r = row_span(p, c, j);
        if (r.i0 > r.i1) continue;
        const float row = row_sum(r, r.i0, r.i1);
        sum += row;
        if (j < 0 || j >= H) continue;
        const int i0 = std::max(r.i0, 0), i1 = std::min(r.i1, W - 1);
        if (i0 == r.i0 && i1 == r.i1) in += row;
        else if (i0 <= i1) in += row_sum(r, i0, i1);
    }
}

constexpr int kChunk = 8;   // texels of a row evaluated together in the kept and wide footprints' loops

inline int padded_length(int n) { return (n + kChunk - 1) / kChunk * kChunk; }

// One chunk of a row: lanes k = 0 .. kChunk - 1 are texels i0 + k0 + k of the row; lanes k0 + k >= n are 0.
struct Chunk {
    float a, c0, t0;
    std::int32_t k0, n;
};

// footprint_sums for a footprint wholly inside the image (then the sum over the image is the sum), which
// also keeps each row's weights. Nearly every kept footprint is a narrow ellipse whose rows hold a few
// texels (on the sphere scene 9 rows of 4.5 texels on average). A loop per row spent its time in a scalar
// remainder, in adding up a vector's lanes, and in waiting: one row's exponential polynomial is a chain
// of dependent operations, and the next row's set-up (a square root) stood between two chains. So the
// rows' spans come first and are cut into chunks of kChunk texels (lanes past the row's end get weight
// 0, kept as 0: the drawing pass may add them); then all chunks of the footprint are evaluated in one
// loop whose iterations are independent, so that the processor overlaps their chains. The weights are
// row_sum's, element for element. They are summed per lane in double over the whole footprint and the
// lanes added once in a fixed order: the same sum as row_sum's in another order (closer to the exact
// one: no single-precision row sums), the same on every instruction set (footprint_sums, for the few
// footprints that the image's edges clip, still sums rows in a vectorised reduction whose order depends
// on it).
CAUSTICS_AVX2_CLONES double footprint_sum_kept(const Print& p, glm::dvec2 c, KeptWeights& kept,
                                               std::vector<Chunk>& chunks) {
    chunks.clear();
    const std::size_t w0 = kept.weights.size();
    std::size_t w = w0;
    for (int j = p.y0; j <= p.y1; ++j) {
        const RowSpan r = row_span(p, c, j);
        const int n = std::max(r.i1 - r.i0 + 1, 0);
        kept.rows.push_back({r.i0, n, static_cast<std::uint32_t>(w)});
        const float t0 = r.offset(r.i0);
        for (int k0 = 0; k0 < n; k0 += kChunk) chunks.push_back({r.a, r.c0, t0, k0, n});
        w += static_cast<std::size_t>(padded_length(n));
    }
    kept.weights.resize(w);
    float* __restrict out = kept.weights.data() + w0;
    double lanes[kChunk] = {};
    for (const Chunk& ch : chunks) {
#pragma omp simd
        for (int k = 0; k < kChunk; ++k) {
            const float t = static_cast<float>(ch.k0 + k) + ch.t0;
            const float e = neg_exp(ch.a * t * t + ch.c0);
            const float weight = ch.k0 + k < ch.n ? e : 0.0f;
            out[k] = weight;
            lanes[k] += static_cast<double>(weight);
        }
        out += kChunk;
    }
    return ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) + ((lanes[4] + lanes[5]) + (lanes[6] + lanes[7]));
}

// Adds scale x weight(k) to texels k = 0 .. n - 1 of `row`, whose image row has `room` texels from row[0]:
// whole chunks of kChunk texels, then the last chunk, whose lanes past n write back the value they read
// (a select, not an addition of 0: a texel outside every footprint keeps its bits, -0 and NaN included),
// where the room allows; one texel at a time otherwise. Forced inline, so that each AVX2 clone that
// calls it compiles its loops (and weight) for AVX2.
template <class Weight>
[[gnu::always_inline]] inline void add_to_row(float* __restrict row, int n, int room, float scale, Weight weight) {
    const int whole = n / kChunk * kChunk;
    for (int k0 = 0; k0 < whole; k0 += kChunk) {
#pragma omp simd
        for (int k = 0; k < kChunk; ++k) row[k0 + k] += scale * weight(k0 + k);
    }
    if (whole == n) return;
    if (whole + kChunk <= room) {
#pragma omp simd
        for (int k = 0; k < kChunk; ++k) {
            const float e = weight(whole + k), v = row[whole + k];
            row[whole + k] = whole + k < n ? v + scale * e : v;
        }
        return;
    }
    for (int k = whole; k < n; ++k) row[k] += scale * weight(k);
}

// draw_rows for a splat whose weights were kept (wholly inside the image); the weights' padding to a
// multiple of kChunk lets the last chunk read them whole.
CAUSTICS_AVX2_CLONES void draw_kept_rows(const Print& p, const KeptWeights& kept, int j0, int j1, float scale,
                                         Image& target) {
    for (int j = j0; j <= j1; ++j) {
        const KeptRow& r = kept.rows[static_cast<std::size_t>(p.kept_rows + (j - p.y0))];
        if (r.n == 0) continue;   // its i0 may lie one past the image's last column
        const float* __restrict w = kept.weights.data() + r.w;
        add_to_row(&target.at(r.i0, j), r.n, target.width - r.i0, scale, [w](int k) { return w[k]; });
    }
}

// Adds scale x weight to the texels of rows [j0, j1] (their columns already clipped to the image). (The
// wide footprints' rows hold 28 texels on average on the sphere scene: a loop over n ended each in a
// scalar remainder of up to 7 exponentials, which add_to_row's last chunk replaces.)
CAUSTICS_AVX2_CLONES void draw_rows(const Print& p, glm::dvec2 c, int j0, int j1, float scale, Image& target) {
    for (int j = j0; j <= j1; ++j) {
        const RowSpan r = row_span(p, c, j);
        if (r.i0 > r.i1) continue;
        const float a = r.a, c0 = r.c0, t0 = r.offset(r.i0);
        add_to_row(&target.at(r.i0, j), r.i1 - r.i0 + 1, target.width - r.i0, scale, [=](int k) {
            const float t = static_cast<float>(k) + t0;
            return neg_exp(a * t * t + c0);
        });
    }
}

}  // namespace

int build_elliptic_splats(const std::vector<FaceSplat>& landing, int grid, float sigma, float min_radius,
                          std::vector<std::vector<EllipticSplat>>& per_face) {
    const int g = grid;
    const std::size_t faces = per_face.size();
    const float sigma0 = min_radius / kEllipticCutoff;
    const float s2 = sigma * sigma, o2 = sigma0 * sigma0;
    // Each face's splats in the order of the landed texels (row-major): each row's first slot per face
    // from a count first, so that the rows can then be built in parallel into their slots.
    std::vector<std::size_t> row_slot(static_cast<std::size_t>(g) * faces);
    std::vector<std::size_t> count(faces, 0);
    for (int y = 0; y < g; ++y) {
        for (std::size_t f = 0; f < faces; ++f) row_slot[static_cast<std::size_t>(y) * faces + f] = count[f];
        for (int x = 0; x < g; ++x) {
            const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
            if (fs.splat.value > 0.0f) ++count[static_cast<std::size_t>(fs.face)];
        }
    }
    for (std::size_t f = 0; f < faces; ++f) per_face[f].resize(count[f]);
    std::atomic<int> isolated{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, g, 8), [&](const tbb::blocked_range<int>& rows) {
        int lone = 0;
        for (int y = rows.begin(); y != rows.end(); ++y) {
            std::size_t* slot = row_slot.data() + static_cast<std::size_t>(y) * faces;
            for (int x = 0; x < g; ++x) {
                const FaceSplat& fs = landing[static_cast<std::size_t>(y) * g + x];
                if (!(fs.splat.value > 0.0f)) continue;
                const std::size_t face = static_cast<std::size_t>(fs.face);
                glm::vec2 jx, jy;
                glm::vec3 cov;
                if (lattice_step(landing, g, x, y, 1, 0, jx) && lattice_step(landing, g, x, y, 0, 1, jy)) {
                    cov = {s2 * (jx.x * jx.x + jy.x * jy.x) + o2, s2 * (jx.x * jx.y + jy.x * jy.y),
                           s2 * (jx.y * jx.y + jy.y * jy.y) + o2};
                } else {
                    // An axis without a landed neighbour: the isotropic footprint of splats.hpp (the larger
                    // spacing from the diagonals or the nearest ring). A texel with both axes always has
                    // one, so only these can be isolated.
                    float radius = min_radius;
                    if (!adaptive_radius(landing, g, x, y, min_radius, radius)) ++lone;
                    const float s = radius / kEllipticCutoff;
                    cov = {s * s, 0.0f, s * s};
                }
                per_face[face][slot[face]++] = {fs.splat.pixel, fs.splat.value, clamp_cov(cov, sigma0)};
            }
        }
        isolated += lone;
    });
    return isolated.load();
}

// The buffers of one draw, kept between draws: a frame's splats need several MB of them (on the sphere
// scene 0.7 MB of footprints and 2.4 MB of kept weights), which fresh allocations would take from newly
// mapped pages, a page fault per 4 KiB (about 10 % of the splats' time when they were allocated per draw).
struct EllipticSplatter::Buffers {
    std::vector<Print> prints;
    std::vector<std::uint8_t> valid;
    std::vector<double> inside;
    std::vector<KeptWeights> kept;
    std::vector<std::vector<std::uint32_t>> in_band;
    tbb::enumerable_thread_specific<std::vector<Chunk>> chunks;   // footprint_sum_kept's scratch
};

EllipticSplatter::EllipticSplatter() : buffers_(std::make_unique<Buffers>()) {}
EllipticSplatter::~EllipticSplatter() = default;
EllipticSplatter::EllipticSplatter(EllipticSplatter&&) noexcept = default;
EllipticSplatter& EllipticSplatter::operator=(EllipticSplatter&&) noexcept = default;

SplatStats draw_elliptic(const std::vector<EllipticSplat>& splats, Image& target) {
    return EllipticSplatter().draw(splats, target);
}

SplatStats EllipticSplatter::draw(const std::vector<EllipticSplat>& splats, Image& target) {
    const int W = target.width, H = target.height;
    const std::size_t n = splats.size();
    Buffers& bu = *buffers_;
    // Every element read below is written first in this draw (valid marks the splats whose print and
    // inside fraction were), so only the sizes are set here.
    std::vector<Print>& prints = bu.prints;
    std::vector<std::uint8_t>& valid = bu.valid;
    std::vector<double>& inside = bu.inside;
    std::vector<KeptWeights>& kept = bu.kept;
    prints.resize(n);
    valid.assign(n, 0);
    inside.resize(n);
    // Groups only grow: draws of different sizes alternate (a cube map's faces), and shrinking would free
    // the kept vectors of the groups past the smaller size.
    const std::size_t groups_used = (n + kKeptGroup - 1) / kKeptGroup;
    if (kept.size() < groups_used) kept.resize(groups_used);
    // Per splat: support, inverse covariance, normalisation over the whole support.
    // Whole groups per task, so that each group's kept weights are written by one thread, in order.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups_used, 4), [&](const tbb::blocked_range<std::size_t>& groups) {
        const std::size_t end = std::min(n, groups.end() * kKeptGroup);
        std::vector<Chunk>& chunks = bu.chunks.local();
        for (std::size_t g = groups.begin(); g != groups.end(); ++g) kept[g].rows.clear(), kept[g].weights.clear();
        for (std::size_t k = groups.begin() * kKeptGroup; k != end; ++k) {
            const std::size_t group = k / kKeptGroup;
            const EllipticSplat& s = splats[k];
            if (!std::isfinite(s.pixel.x) || !std::isfinite(s.pixel.y) || !std::isfinite(s.value) ||
                std::abs(s.pixel.x) > 1e8f || std::abs(s.pixel.y) > 1e8f)
                continue;
            const double a = s.cov.x, b = s.cov.y, d = s.cov.z, det = a * d - b * b;
            if (!(det > 0.0) || !std::isfinite(det) || !(a > 0.0) || !(d > 0.0)) continue;   // not positive definite
            const double hx = kEllipticCutoff * std::sqrt(a), hy = kEllipticCutoff * std::sqrt(d);
            if (hx > kMaxHalfWidth || hy > kMaxHalfWidth) continue;
            Print p{};
            p.ixx = 0.5 * d / det, p.ixy = -0.5 * b / det, p.iyy = 0.5 * a / det;
            set_chords(p);
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
            } else if (in_image) {
                p.kept_rows = static_cast<std::int32_t>(kept[group].rows.size());
                sum = in = footprint_sum_kept(p, c, kept[group], chunks);
            } else {
                footprint_sums(p, c, W, H, sum, in);
            }
            if (!(sum > 0.0)) {   // a footprint narrower than a texel between centres: the nearest texel
                p.x0 = p.x1 = static_cast<int>(std::floor(s.pixel.x));
                p.y0 = p.y1 = static_cast<int>(std::floor(s.pixel.y));
                p.ixx = p.ixy = p.iyy = 0.0;
                p.kept_rows = -1;
                sum = 1.0;
                in = (p.x0 >= 0 && p.y0 >= 0 && p.x0 < W && p.y0 < H) ? 1.0 : 0.0;
            }
            p.scale = s.value / sum;
            if (!(std::abs(p.scale) <= std::numeric_limits<float>::max())) continue;   // drawn in float
            prints[k] = p;
            inside[k] = in / sum;
            valid[k] = 1;
        }
    });
    SplatStats st;
    // Splats per band of rows, in input order.
    const int bands = (H + kBandRows - 1) / kBandRows;
    std::vector<std::vector<std::uint32_t>>& in_band = bu.in_band;
    in_band.resize(static_cast<std::size_t>(bands));
    for (auto& band : in_band) band.clear();
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
                if (prints[k].kept_rows >= 0) {
                    const Print& p = prints[k];
                    draw_kept_rows(p, kept[k / kKeptGroup], std::max(p.y0, r0), std::min(p.y1, r1),
                                   static_cast<float>(p.scale), target);
                    continue;
                }
                Print p = prints[k];   // its columns clipped to the image: the same weights, fewer texels
                p.x0 = std::max(p.x0, 0), p.x1 = std::min(p.x1, W - 1);
                const glm::dvec2 c(splats[k].pixel);
                const float scale = static_cast<float>(p.scale);
                draw_rows(p, c, std::max(p.y0, r0), std::min(p.y1, r1), scale, target);
            }
        }
    });
    return st;
}

}  // namespace caustics::caustic_mapping
