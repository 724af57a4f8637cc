#include <caustics/blocks/gbuffer/gbuffer_raster.hpp>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/band_bins.hpp>
#include <caustics/util/target_clones.hpp>

namespace caustics {
namespace {

constexpr std::size_t kChunk = 2048;           // triangles per binning work item (fixed: keeps order)
constexpr int kSubpixelBits = 8;
constexpr double kSubpixel = 1 << kSubpixelBits;
constexpr std::int64_t kSubpixelOne = 1 << kSubpixelBits;
constexpr double kMaxPixel = 1 << 21;          // keeps fixed-point edge functions well inside int64
constexpr int kSpan = 64;                      // pixels of a row interpolated together
constexpr int kShortSpan = 16;                 // rows covering fewer pixels are drawn one pixel at a time

// Whether e + j step, j in [0, count], stays below 2^53 in magnitude (exact in a double).
inline bool exact_in_double(std::int64_t e, std::int64_t step, int count) {
    constexpr std::int64_t kExact = std::int64_t{1} << 53;
    const std::int64_t a = e < 0 ? -e : e, b = step < 0 ? -step : step;
    return a < kExact / 2 && b < kExact / 2 / (count + 1);
}

// Per-pixel values of one span of a row (structure of arrays, so that the interpolation vectorises).
struct Span {
    float l0[kSpan], l1[kSpan], l2[kSpan], d[kSpan], px[kSpan], py[kSpan], pz[kSpan];
};

// Whether every fragment of a span passes the depth test against `depth`.
CAUSTICS_AVX2_CLONES bool span_passes(const Span& span, int count, bool less, const float* depth) {
    int passed = 0;
    if (less) {
        for (int j = 0; j < count; ++j) passed += span.d[j] < depth[j];
    } else {
        for (int j = 0; j < count; ++j) passed += span.d[j] > depth[j];
    }
    return passed == count;
}

// The stores of a span of a positions-only target (depth, position, id), every fragment passing.
// `position` is the span's glm::vec3 array seen as floats (three per texel, no padding).
static_assert(sizeof(glm::vec3) == 3 * sizeof(float));
CAUSTICS_AVX2_CLONES void store_span(const Span& span, int count, std::int32_t id, float* __restrict depth,
                                     float* __restrict position, std::int32_t* __restrict ids) {
    for (int j = 0; j < count; ++j) {
        depth[j] = span.d[j];
        position[3 * j] = span.px[j];
        position[3 * j + 1] = span.py[j];
        position[3 * j + 2] = span.pz[j];
        ids[j] = id;
    }
}

struct Setup {
    std::int64_t X[3], Y[3];      // fixed-point screen vertices, counter-clockwise in the E > 0 sense
    std::uint32_t v[3];           // vertex indices (after the orientation swap)
    double inv_area;              // 1 / (twice the fixed-point area)
    double z[3];                  // view depth per vertex
    int x0, x1, y0, y1;           // pixel-centre bounding box, inclusive; x0 > x1: nothing to draw
    glm::vec3 flat_normal;        // geometric normal (used when no vertex normals)
    bool front;                   // front facing (draw_front_back: selects the target)
};

// A projected vertex in fixed point: 8 bytes, so that the setup pass's gathers of a large mesh stay in
// cache (|X|, |Y| <= kMaxPixel * kSubpixel = 2^29 fit int32). X == kNotProjected: behind the near plane,
// not finite or too far off-screen. The depth is kept apart (read only for drawable triangles).
struct VertexOut {
    std::int32_t X = 0, Y = 0;
};
constexpr std::int32_t kNotProjected = std::numeric_limits<std::int32_t>::min();

inline std::int64_t floor_div(std::int64_t a, std::int64_t b) {
    const std::int64_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

// Edge a -> b at p: (b.x - a.x)(p.y - a.y) - (b.y - a.y)(p.x - a.x). Positive inside.
inline std::int64_t edge(std::int64_t ax, std::int64_t ay, std::int64_t bx, std::int64_t by, std::int64_t px,
                         std::int64_t py) {
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}
// Top-left rule (y down): a top edge is horizontal with the interior below it (dy == 0, dx > 0), a left
// edge goes up (dy < 0). Two triangles sharing an edge traverse it in opposite directions, so exactly
// one of them owns the centres lying on it.
inline bool top_left(std::int64_t dx, std::int64_t dy) { return dy < 0 || (dy == 0 && dx > 0); }

constexpr int kNarrow = 8;       // rows of a triangle narrower than this many centres are walked, not divided
constexpr int kFewCentres = 4;   // bounding boxes of at most this many pixel centres are tested exactly

// Whether the triangle (counter-clockwise in the E > 0 sense) covers one of the pixel centres of its
// bounding box, by the draw pass's rule: E_k + bias_k >= 0 for the three edges (top-left rule).
inline bool covers_a_centre(const Setup& s) {
    const int a[3] = {1, 2, 0}, c[3] = {2, 0, 1};
    for (int y = s.y0; y <= s.y1; ++y)
        for (int x = s.x0; x <= s.x1; ++x) {
            const std::int64_t px = (2 * static_cast<std::int64_t>(x) + 1) << (kSubpixelBits - 1);
            const std::int64_t py = (2 * static_cast<std::int64_t>(y) + 1) << (kSubpixelBits - 1);
            bool inside = true;
            for (int k = 0; k < 3 && inside; ++k) {
                const std::int64_t dx = s.X[c[k]] - s.X[a[k]], dy = s.Y[c[k]] - s.Y[a[k]];
                const std::int64_t bias = top_left(dx, dy) ? 0 : -1;
                inside = edge(s.X[a[k]], s.Y[a[k]], s.X[c[k]], s.Y[c[k]], px, py) + bias >= 0;
            }
            if (inside) return true;
        }
    return false;
}

// Every target has the projection's size; normals are absent or one per position.
void check_inputs(const LightProjection& view, const GBufferTriangles& batch,
                  std::initializer_list<const GBuffer*> targets) {
    for (const GBuffer* t : targets)
        if (t->width != view.width || t->height != view.height ||
            t->depth.size() != static_cast<std::size_t>(view.width) * view.height)
            throw std::invalid_argument("GBufferRaster: target size differs from the projection's");
    if (!batch.normals.empty() && batch.normals.size() != batch.positions.size())
        throw std::invalid_argument("GBufferRaster: normals must be empty or one per position");
}

// Pass 2 for one triangle: the pixel centres it covers in rows [row0, row1], depth-tested into `out`;
// returns the fragments (covered centres).
std::int64_t draw_triangle(const Setup& s, int row0, int row1, const GBufferTriangles& batch, bool perspective, bool less,
                           bool write_normals, GBuffer& out, Span& span) {
    const bool have_normals = !batch.normals.empty();
    const std::int32_t id = batch.id;
    std::int64_t fragments = 0;
    const int ya = std::max(s.y0, row0), yb = std::min(s.y1, row1);
    // Edge k is opposite vertex k: e0 = v1 -> v2, e1 = v2 -> v0, e2 = v0 -> v1.
    const int a[3] = {1, 2, 0}, c[3] = {2, 0, 1};
    std::int64_t bias[3], step_x[3];
    for (int k = 0; k < 3; ++k) {
        const std::int64_t dx = s.X[c[k]] - s.X[a[k]], dy = s.Y[c[k]] - s.Y[a[k]];
        bias[k] = top_left(dx, dy) ? 0 : -1;
        step_x[k] = -dy * static_cast<std::int64_t>(kSubpixel);
    }
    const glm::vec3 P[3] = {batch.positions[s.v[0]], batch.positions[s.v[1]], batch.positions[s.v[2]]};
    glm::vec3 N[3];
    for (int k = 0; k < 3; ++k) N[k] = have_normals ? batch.normals[s.v[k]] : s.flat_normal;
    const float iz[3] = {static_cast<float>(1.0 / s.z[0]), static_cast<float>(1.0 / s.z[1]),
                         static_cast<float>(1.0 / s.z[2])};
    const float z[3] = {static_cast<float>(s.z[0]), static_cast<float>(s.z[1]), static_cast<float>(s.z[2])};
    const float inv_area = static_cast<float>(s.inv_area);
    // Barycentrics (l0, l1) -> perspective-correct weights (l2 completed) and the depth.
    auto weights = [&](float& l0, float& l1, float& l2) {
        l2 = 1.0f - l0 - l1;
        if (!perspective) return l0 * z[0] + l1 * z[1] + l2 * z[2];
        const float w0 = l0 * iz[0], w1 = l1 * iz[1], w2 = l2 * iz[2];
        const float d = 1.0f / (w0 + w1 + w2);
        l0 = w0 * d, l1 = w1 * d, l2 = w2 * d;
        return d;
    };
    auto position_at = [&](float l0, float l1, float l2) { return l0 * P[0] + l1 * P[1] + l2 * P[2]; };
    // The depth test and the stores of one fragment.
    auto write = [&](std::size_t i, float d, float l0, float l1, float l2, const glm::vec3& position) {
        if (less ? !(d < out.depth[i]) : !(d > out.depth[i])) return;
        out.depth[i] = d;
        out.position[i] = position;
        if (write_normals) {
            const glm::vec3 nn = l0 * N[0] + l1 * N[1] + l2 * N[2];
            const float len2 = glm::dot(nn, nn);
            out.normal[i] = len2 > 0.0f ? nn / std::sqrt(len2) : s.flat_normal;
        }
        out.id[i] = id;
    };
    for (int y = ya; y <= yb; ++y) {
        const std::int64_t py = (2 * static_cast<std::int64_t>(y) + 1) << (kSubpixelBits - 1);
        const std::int64_t px0 = (2 * static_cast<std::int64_t>(s.x0) + 1) << (kSubpixelBits - 1);
        std::int64_t E[3];
        for (int k = 0; k < 3; ++k) E[k] = edge(s.X[a[k]], s.Y[a[k]], s.X[c[k]], s.Y[c[k]], px0, py);
        // The row's covered span, exactly from the integer edge functions: E_k + bias_k >= 0 at
        // x = x0 + j is E_k + bias_k + j step_k >= 0, a half-line in j (or all / nothing).
        std::int64_t j_lo = 0, j_hi = s.x1 - s.x0;
        if (j_hi < kNarrow) {
            // Narrow: walk the few centres (the covered ones form an interval) instead of
            // dividing; the same span.
            std::int64_t e[3] = {E[0] + bias[0], E[1] + bias[1], E[2] + bias[2]};
            const std::int64_t last = j_hi;
            j_lo = 0, j_hi = -1;
            for (std::int64_t j = 0; j <= last; ++j, e[0] += step_x[0], e[1] += step_x[1], e[2] += step_x[2]) {
                if ((e[0] | e[1] | e[2]) < 0) {   // some edge function negative: outside
                    if (j_hi >= j_lo && j > j_lo) break;
                    continue;
                }
                if (j_hi < j_lo) j_lo = j;
                j_hi = j;
            }
        } else {
            for (int k = 0; k < 3; ++k) {
                const std::int64_t e0 = E[k] + bias[k], st = step_x[k];
                if (st > 0) j_lo = std::max(j_lo, e0 >= 0 ? 0 : floor_div(-e0 + st - 1, st));
                else if (st < 0) j_hi = std::min(j_hi, e0 < 0 ? -1 : floor_div(e0, -st));
                else if (e0 < 0) j_hi = -1;
            }
        }
        if (j_lo > j_hi) continue;
        for (int k = 0; k < 3; ++k) E[k] += j_lo * step_x[k];
        const int xs = s.x0 + static_cast<int>(j_lo), xe = s.x0 + static_cast<int>(j_hi);
        fragments += xe - xs + 1;
        if (xe - xs + 1 < kShortSpan) {
            for (int x = xs; x <= xe; ++x, E[0] += step_x[0], E[1] += step_x[1]) {
                float l0 = static_cast<float>(E[0]) * inv_area, l1 = static_cast<float>(E[1]) * inv_area, l2;
                const float d = weights(l0, l1, l2);
                write(out.index(x, y), d, l0, l1, l2, position_at(l0, l1, l2));
            }
            continue;
        }
        // Longer rows in spans of up to kSpan pixels, three loops: the barycentrics from the
        // exact integer edge values (scalar: int64 -> float), the interpolation (float only,
        // so the compiler vectorises it; the same operations as one pixel at a time), then
        // the depth test and the stores.
        for (int xc = xs; xc <= xe; xc += kSpan) {
            const int count = std::min(kSpan, xe - xc + 1);
            if (exact_in_double(E[0], step_x[0], count) && exact_in_double(E[1], step_x[1], count)) {
                // E + j step in double is the integer itself (all below 2^53), so rounding it to
                // float gives the same value as the int64 conversion, and the loop vectorises.
                const double e0 = static_cast<double>(E[0]), e1 = static_cast<double>(E[1]);
                const double s0 = static_cast<double>(step_x[0]), s1 = static_cast<double>(step_x[1]);
                for (int j = 0; j < count; ++j) {
                    span.l0[j] = static_cast<float>(e0 + j * s0) * inv_area;
                    span.l1[j] = static_cast<float>(e1 + j * s1) * inv_area;
                }
                E[0] += count * step_x[0], E[1] += count * step_x[1];
            } else {
                for (int j = 0; j < count; ++j, E[0] += step_x[0], E[1] += step_x[1]) {
                    span.l0[j] = static_cast<float>(E[0]) * inv_area;
                    span.l1[j] = static_cast<float>(E[1]) * inv_area;
                }
            }
            for (int j = 0; j < count; ++j) {
                float l0 = span.l0[j], l1 = span.l1[j], l2;
                span.d[j] = weights(l0, l1, l2);
                span.l0[j] = l0, span.l1[j] = l1, span.l2[j] = l2;
                span.px[j] = l0 * P[0].x + l1 * P[1].x + l2 * P[2].x;
                span.py[j] = l0 * P[0].y + l1 * P[1].y + l2 * P[2].y;
                span.pz[j] = l0 * P[0].z + l1 * P[1].z + l2 * P[2].z;
            }
            const std::size_t i0 = out.index(xc, y);
            // Positions only (the receivers' maps), every fragment of the span passing the
            // depth test (a receiver drawn where nothing nearer was): the same stores as
            // write(), without a test per texel, vectorised.
            if (!write_normals && span_passes(span, count, less, &out.depth[i0])) {
                store_span(span, count, id, &out.depth[i0], &out.position[i0].x, &out.id[i0]);
                continue;
            }
            for (int j = 0; j < count; ++j)
                write(i0 + static_cast<std::size_t>(j), span.d[j], span.l0[j], span.l1[j], span.l2[j],
                      glm::vec3(span.px[j], span.py[j], span.pz[j]));
        }
    }
    return fragments;
}

}  // namespace

void GBuffer::clear(int w, int h, DepthTest test, bool with_normals) {
    width = w;
    height = h;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    const float far = test == DepthTest::Less ? std::numeric_limits<float>::infinity()
                                              : -std::numeric_limits<float>::infinity();
    depth.resize(n);
    id.resize(n);
    position.resize(n);   // only read where id >= 0: no need to clear
    if (with_normals) normal.resize(n);
    else normal.clear();
    // Cleared in parallel: a 768^2 target is 4.7 MB of depth and ids per frame.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<std::size_t>& r) {
        std::fill(depth.begin() + static_cast<std::ptrdiff_t>(r.begin()), depth.begin() + static_cast<std::ptrdiff_t>(r.end()), far);
        std::fill(id.begin() + static_cast<std::ptrdiff_t>(r.begin()), id.begin() + static_cast<std::ptrdiff_t>(r.end()), -1);
    });
}

struct GBufferRaster::Impl {
    std::vector<float> vz;                 // perspective: view depth per vertex
    std::vector<glm::vec3> cpos, cnorm;    // near-clipped copy of the batch
    std::vector<glm::uvec3> ctri;
    std::vector<VertexOut> verts;
    std::vector<double> vdepth;            // view depth per projected vertex
    std::vector<Setup> setups;             // chunk c's drawable triangles packed from c * kChunk, in order
    std::vector<std::uint32_t> drawable;   // per chunk: how many
    std::vector<std::uint32_t> counts, cursors, band_start;
    std::vector<std::uint32_t> entries;
    std::vector<GBufferStats> chunk_stats;
    std::vector<std::int64_t> band_fragments;

    void project(const LightProjection& view, const GBufferTriangles& batch);
    void set_up(const LightProjection& view, const GBufferTriangles& batch, CullMode cull, int W, int H, int bands,
                std::size_t chunks);
};

GBufferRaster::GBufferRaster() : impl_(std::make_unique<Impl>()) {}
GBufferRaster::~GBufferRaster() = default;
GBufferRaster::GBufferRaster(GBufferRaster&&) noexcept = default;
GBufferRaster& GBufferRaster::operator=(GBufferRaster&&) noexcept = default;

GBufferStats GBufferRaster::draw(const LightProjection& view, const GBufferTriangles& batch, CullMode cull,
                                 DepthTest test, GBuffer& target) {
    check_inputs(view, batch, {&target});
    GBufferStats pre;
    GBufferTriangles eff = batch;
    if (view.type == ProjectionType::Perspective) clip_near(view, batch, eff, pre);
    return draw_clipped(view, eff, cull, test, target, nullptr, pre);
}

GBufferStats GBufferRaster::draw_front_back(const LightProjection& view, const GBufferTriangles& batch, DepthTest test,
                                            GBuffer& front, GBuffer& back) {
    check_inputs(view, batch, {&front, &back});
    GBufferStats pre;
    GBufferTriangles eff = batch;
    if (view.type == ProjectionType::Perspective) clip_near(view, batch, eff, pre);
    return draw_clipped(view, eff, CullMode::None, test, front, &back, pre);
}

// Perspective: a copy of the batch clipped against the near plane, only when some triangle needs it.
void GBufferRaster::clip_near(const LightProjection& view, const GBufferTriangles& batch, GBufferTriangles& eff,
                              GBufferStats& stats) {
    Impl& m = *impl_;
    const double zc = std::max(view.near_depth, 1e-3);
    const std::size_t nv = batch.positions.size();
    if (m.vz.size() < nv) m.vz.resize(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
            m.vz[i] = static_cast<float>(glm::dot(glm::dvec3(batch.positions[i]) - view.eye, view.forward));
    });
    auto behind = [&](unsigned i) { return i < nv && !(m.vz[i] > zc); };
    bool any = false;
    for (const glm::uvec3& t : batch.triangles)
        if (behind(t.x) || behind(t.y) || behind(t.z)) {
            any = true;
            break;
        }
    if (!any) return;
    const bool normals = !batch.normals.empty();
    m.cpos.assign(batch.positions.begin(), batch.positions.end());
    m.cnorm.assign(batch.normals.begin(), batch.normals.end());
    m.ctri.clear();
    for (const glm::uvec3& t : batch.triangles) {
        if (t.x >= nv || t.y >= nv || t.z >= nv || !(behind(t.x) || behind(t.y) || behind(t.z))) {
            m.ctri.push_back(t);   // invalid indices are reported by the raster pass
            continue;
        }
        // Sutherland-Hodgman against z > zc, keeping the winding.
        unsigned poly[4];
        int k = 0;
        for (int e = 0; e < 3; ++e) {
            const unsigned a = t[e], b = t[(e + 1) % 3];
            const double za = m.vz[a], zb = m.vz[b];
            if (za > zc) poly[k++] = a;
            if ((za > zc) != (zb > zc)) {
                const float f = static_cast<float>((zc - za) / (zb - za));
                m.cpos.push_back(m.cpos[a] + f * (m.cpos[b] - m.cpos[a]));
                if (normals) m.cnorm.push_back(m.cnorm[a] + f * (m.cnorm[b] - m.cnorm[a]));
                poly[k++] = static_cast<unsigned>(m.cpos.size() - 1);
            }
        }
        if (k < 3) {
            ++stats.clipped;
            continue;
        }
        ++stats.near_split;
        m.ctri.push_back({poly[0], poly[1], poly[2]});
        if (k == 4) m.ctri.push_back({poly[0], poly[2], poly[3]});
    }
    eff = {m.cpos, normals ? std::span<const glm::vec3>(m.cnorm) : std::span<const glm::vec3>(), m.ctri, batch.id};
}

// Pass 0 of draw_clipped (the vertex stage): every vertex projected once to fixed-point pixel coordinates.
void GBufferRaster::Impl::project(const LightProjection& view, const GBufferTriangles& batch) {
    const std::size_t nv = batch.positions.size();
    if (verts.size() < nv) verts.resize(nv);
    if (vdepth.size() < nv) vdepth.resize(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
            VertexOut& o = verts[i];
            double px, py, z;
            const bool ok = view.project(glm::dvec3(batch.positions[i]), px, py, z) && std::isfinite(px) &&
                            std::isfinite(py) && std::abs(px) <= kMaxPixel && std::abs(py) <= kMaxPixel;
            if (!ok) {
                o.X = kNotProjected;
                continue;
            }
            o.X = static_cast<std::int32_t>(std::llround(px * kSubpixel));
            o.Y = static_cast<std::int32_t>(std::llround(py * kSubpixel));
            vdepth[i] = z;
        }
    });
}

// Pass 1 of draw_clipped: set up, cull and count every triangle per (chunk, band), then list each band's
// drawable triangles in input order.
void GBufferRaster::Impl::set_up(const LightProjection& view, const GBufferTriangles& batch, CullMode cull, int W, int H,
                                 int bands, std::size_t chunks) {
    const std::size_t n = batch.triangles.size(), nv = batch.positions.size();
    const bool perspective = view.type == ProjectionType::Perspective;
    // Pixel centre indices i with (i + 1/2) * 256 in [lo, hi] (fixed point).
    auto centre_lo = [](std::int64_t lo) {
        return static_cast<int>(floor_div(lo - (kSubpixelOne / 2) + kSubpixelOne - 1, kSubpixelOne));
    };
    auto centre_hi = [](std::int64_t hi) { return static_cast<int>(floor_div(hi - (kSubpixelOne / 2), kSubpixelOne)); };

    // Pass 1: setup, cull and count per (chunk, band).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            GBufferStats st;   // local: no false sharing between chunks
            std::uint32_t* count = &counts[c * bands];
            // Setups are packed: the band pass then reads only drawable triangles, nearly sequentially
            // (most triangles of a dense mesh at a coarse grid are not drawable).
            std::size_t slot = c * kChunk;
            for (std::size_t t = c * kChunk; t < std::min(n, (c + 1) * kChunk); ++t) {
                ++st.triangles;
                const glm::uvec3 tri = batch.triangles[t];
                if (tri.x >= nv || tri.y >= nv || tri.z >= nv) {
                    ++st.clipped;
                    continue;
                }
                const VertexOut* V[3] = {&verts[tri.x], &verts[tri.y], &verts[tri.z]};
                if (V[0]->X == kNotProjected || V[1]->X == kNotProjected || V[2]->X == kNotProjected) {
                    ++st.clipped;
                    continue;
                }
                // Cheap reject first: most triangles of a dense mesh at a coarse grid cover no centre.
                const std::int64_t xl = std::min({V[0]->X, V[1]->X, V[2]->X}), xh = std::max({V[0]->X, V[1]->X, V[2]->X});
                const std::int64_t yl = std::min({V[0]->Y, V[1]->Y, V[2]->Y}), yh = std::max({V[0]->Y, V[1]->Y, V[2]->Y});
                Setup s;
                s.x0 = std::max(0, centre_lo(xl));
                s.x1 = std::min(W - 1, centre_hi(xh));
                s.y0 = std::max(0, centre_lo(yl));
                s.y1 = std::min(H - 1, centre_hi(yh));
                if (s.x0 > s.x1 || s.y0 > s.y1) continue;   // covers no pixel centre of the image
                for (int k = 0; k < 3; ++k) {
                    s.X[k] = V[k]->X;
                    s.Y[k] = V[k]->Y;
                    s.v[k] = tri[k];
                }
                std::int64_t area = edge(s.X[0], s.Y[0], s.X[1], s.Y[1], s.X[2], s.Y[2]);
                // Degenerate, then (orientation fixed) a small bounding box whose few centres are all
                // missed (most triangles of a dense mesh at a coarse grid): dropped before the world-space
                // facing test when nothing is culled (then the statistics are the same in either order),
                // so such triangles cost no position reads; with culling the cull test counts first.
                auto screen_reject = [&] {
                    if (area == 0) {
                        ++st.culled;
                        return true;
                    }
                    if (area < 0) {
                        std::swap(s.X[1], s.X[2]);
                        std::swap(s.Y[1], s.Y[2]);
                        std::swap(s.v[1], s.v[2]);
                        area = -area;
                    }
                    return (s.x1 - s.x0 + 1) * (s.y1 - s.y0 + 1) <= kFewCentres && !covers_a_centre(s);
                };
                if (cull == CullMode::None && screen_reject()) continue;
                const glm::dvec3 P[3] = {glm::dvec3(batch.positions[tri.x]), glm::dvec3(batch.positions[tri.y]),
                                         glm::dvec3(batch.positions[tri.z])};
                const glm::dvec3 ng = glm::cross(P[1] - P[0], P[2] - P[0]);
                const double facing = perspective ? glm::dot(ng, P[0] - view.eye) : glm::dot(ng, view.forward);
                const bool front = facing < 0.0;
                if ((cull == CullMode::Back && !front) || (cull == CullMode::Front && front)) {
                    ++st.culled;
                    continue;
                }
                if (cull != CullMode::None && screen_reject()) continue;
                for (int k = 0; k < 3; ++k) s.z[k] = vdepth[s.v[k]];
                s.inv_area = 1.0 / static_cast<double>(area);
                s.front = front;
                const double len = glm::length(ng);
                s.flat_normal = len > 0.0 ? glm::vec3(ng / len) : glm::vec3(0.0f);
                setups[slot++] = s;
                for (int b = s.y0 / kBandRows; b <= s.y1 / kBandRows; ++b) ++count[b];
            }
            drawable[c] = static_cast<std::uint32_t>(slot - c * kChunk);
            chunk_stats[c] = st;
        }
    });
    // Offsets, band-major then chunk order: each band lists its triangles in input order.
    entries.resize(band_offsets(counts, chunks, static_cast<std::size_t>(bands), cursors, band_start));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            std::uint32_t* cursor = &cursors[c * bands];
            for (std::size_t t = c * kChunk; t < c * kChunk + drawable[c]; ++t) {
                const Setup& s = setups[t];
                for (int b = s.y0 / kBandRows; b <= s.y1 / kBandRows; ++b) entries[cursor[b]++] = static_cast<std::uint32_t>(t);
            }
        }
    });
}

GBufferStats GBufferRaster::draw_clipped(const LightProjection& view, const GBufferTriangles& batch, CullMode cull,
                                         DepthTest test, GBuffer& front_target, GBuffer* back_target,
                                         const GBufferStats& pre) {
    GBuffer& target = front_target;
    Impl& m = *impl_;
    const std::size_t n = batch.triangles.size();
    const int W = target.width, H = target.height;
    const int bands = (H + kBandRows - 1) / kBandRows;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    // Scratch only grows: batches of different sizes alternate every frame (a dense mesh, then a plane),
    // and shrinking would make the next frame value-initialise the whole array again.
    if (m.setups.size() < n) m.setups.resize(n);
    m.drawable.assign(chunks, 0);
    m.counts.assign(chunks * bands, 0);
    m.chunk_stats.assign(chunks, GBufferStats{});
    const bool perspective = view.type == ProjectionType::Perspective;

    m.project(view, batch);
    m.set_up(view, batch, cull, W, H, bands, chunks);

    // Pass 2: each band draws its triangles in order.
    m.band_fragments.assign(static_cast<std::size_t>(bands), 0);
    const bool less = test == DepthTest::Less;
    if (back_target && back_target->normal.empty() != target.normal.empty())
        throw std::invalid_argument("GBufferRaster: front and back targets must both have normals or neither");
    const bool write_normals = !target.normal.empty();
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& r) {
        Span span;
        for (int b = r.begin(); b != r.end(); ++b) {
            const int row0 = b * kBandRows, row1 = std::min(H, row0 + kBandRows) - 1;
            std::int64_t fragments = 0;
            for (std::uint32_t e = m.band_start[static_cast<std::size_t>(b)]; e < m.band_start[static_cast<std::size_t>(b) + 1]; ++e) {
                const Setup& s = m.setups[m.entries[e]];
                GBuffer& out = back_target && !s.front ? *back_target : target;
                fragments += draw_triangle(s, row0, row1, batch, perspective, less, write_normals, out, span);
            }
            m.band_fragments[static_cast<std::size_t>(b)] = fragments;
        }
    });
    GBufferStats stats = pre;
    for (const GBufferStats& s : m.chunk_stats) {
        stats.triangles += s.triangles;
        stats.culled += s.culled;
        stats.clipped += s.clipped;
    }
    for (std::int64_t f : m.band_fragments) stats.fragments += f;
    return stats;
}

}  // namespace caustics
