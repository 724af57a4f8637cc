#include <caustics/blocks/splat/splat.hpp>

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <caustics/blocks/raster/band_bins.hpp>

namespace caustics {
namespace {

constexpr std::size_t kChunk = 4096;
constexpr int kMaxTaps = 257;   // support of at most +-128 pixels

struct Footprint {
    int x0, x1, y0, y1;   // full support (pixel indices, may be outside the image)
    bool gaussian;        // false: point splat at (x0, y0)
    std::uint32_t taps;   // Gaussian: offset of its x taps (then its y taps) in its chunk's tap buffer
};

// Pixel indices whose centres lie within r of c: [ceil(c - 1/2 - r), floor(c - 1/2 + r)].
inline void support(double c, double r, int& lo, int& hi) {
    lo = static_cast<int>(std::ceil(c - 0.5 - r));
    hi = static_cast<int>(std::floor(c - 0.5 + r));
}

// Gaussian taps over [lo, hi] around c; returns their sum. Three exponentials per call: with
// d_{i+1} = d_i + 1, exp(-d_{i+1}^2 a) = exp(-d_i^2 a) * exp(-(2 d_i + 1) a) and the second factor is
// multiplied by exp(-2 a) per tap (relative rounding below 1e-13 over the at most 257 taps, in double).
inline double taps(double c, int lo, int hi, double inv2s2, double* w) {
    const double d0 = lo + 0.5 - c;
    double value = std::exp(-d0 * d0 * inv2s2), ratio = std::exp(-(2.0 * d0 + 1.0) * inv2s2);
    const double step = std::exp(-2.0 * inv2s2);
    double sum = 0.0;
    for (int i = lo; i <= hi; ++i) {
        w[i - lo] = value;
        sum += value;
        value *= ratio;
        ratio *= step;
    }
    return sum;
}

}  // namespace

struct SplatRaster::Impl {
    std::vector<Footprint> prints;
    std::vector<std::uint8_t> valid;
    std::vector<std::uint32_t> counts, cursors, band_start, entries;
    std::vector<SplatStats> chunk_stats;
    // Per chunk: every Gaussian splat's taps, computed once (x taps scaled by value / (sum_x sum_y),
    // then y taps), read by every band the splat touches.
    std::vector<std::vector<float>> chunk_taps;
};

SplatRaster::SplatRaster() : impl_(std::make_unique<Impl>()) {}
SplatRaster::~SplatRaster() = default;
SplatRaster::SplatRaster(SplatRaster&&) noexcept = default;
SplatRaster& SplatRaster::operator=(SplatRaster&&) noexcept = default;

SplatStats SplatRaster::draw(std::span<const Splat> splats, SplatKernel kernel, double radius, Image& target) {
    Impl& m = *impl_;
    const int W = target.width, H = target.height;
    const std::size_t n = splats.size();
    // Per splat: its own radius when set, else the call's; Gaussian when that radius is >= 1 pixel.
    constexpr double kMaxRadius = (kMaxTaps - 1) / 2.0 - 1.0;
    auto radius_of = [&](const Splat& s) {
        return std::min(s.radius > 0.0f ? static_cast<double>(s.radius) : radius, kMaxRadius);
    };
    auto is_gaussian = [&](double r) { return kernel == SplatKernel::Gaussian && r >= 1.0; };
    auto inv2s2_of = [](double r) { return 1.0 / (2.0 * (r / 3.5) * (r / 3.5)); };
    const int bands = (H + kBandRows - 1) / kBandRows;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    m.prints.resize(n);
    m.valid.assign(n, 0);
    m.counts.assign(chunks * bands, 0);
    m.chunk_stats.assign(chunks, SplatStats{});
    if (m.chunk_taps.size() < chunks) m.chunk_taps.resize(chunks);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& rr) {
        double wx[kMaxTaps], wy[kMaxTaps];
        for (std::size_t c = rr.begin(); c != rr.end(); ++c) {
            SplatStats& st = m.chunk_stats[c];
            std::uint32_t* count = &m.counts[c * bands];
            std::vector<float>& tap_buffer = m.chunk_taps[c];
            tap_buffer.clear();
            for (std::size_t k = c * kChunk; k < std::min(n, (c + 1) * kChunk); ++k) {
                const Splat& s = splats[k];
                if (!std::isfinite(s.pixel.x) || !std::isfinite(s.pixel.y) || !std::isfinite(s.value) ||
                    std::abs(s.pixel.x) > 1e8f || std::abs(s.pixel.y) > 1e8f) {
                    ++st.nonfinite;
                    continue;
                }
                Footprint f;
                double inside = 1.0;
                const double r = radius_of(s);
                const bool gaussian = is_gaussian(r);
                const double inv2s2 = gaussian ? inv2s2_of(r) : 0.0;
                f.gaussian = gaussian;
                f.taps = 0;
                if (!gaussian) {
                    f.x0 = f.x1 = static_cast<int>(std::floor(s.pixel.x));
                    f.y0 = f.y1 = static_cast<int>(std::floor(s.pixel.y));
                    if (f.x0 < 0 || f.x0 >= W || f.y0 < 0 || f.y0 >= H) inside = 0.0;
                } else {
                    support(s.pixel.x, r, f.x0, f.x1);
                    support(s.pixel.y, r, f.y0, f.y1);
                    const double sx = taps(s.pixel.x, f.x0, f.x1, inv2s2, wx);
                    const double sy = taps(s.pixel.y, f.y0, f.y1, inv2s2, wy);
                    double ix = 0.0, iy = 0.0;
                    for (int i = std::max(f.x0, 0); i <= std::min(f.x1, W - 1); ++i) ix += wx[i - f.x0];
                    for (int j = std::max(f.y0, 0); j <= std::min(f.y1, H - 1); ++j) iy += wy[j - f.y0];
                    inside = (ix / sx) * (iy / sy);
                    if (inside > 0.0) {
                        f.taps = static_cast<std::uint32_t>(tap_buffer.size());
                        const double scale = s.value / (sx * sy);
                        for (int i = f.x0; i <= f.x1; ++i) tap_buffer.push_back(static_cast<float>(scale * wx[i - f.x0]));
                        for (int j = f.y0; j <= f.y1; ++j) tap_buffer.push_back(static_cast<float>(wy[j - f.y0]));
                    }
                }
                st.value_inside += s.value * inside;
                st.value_outside += s.value * (1.0 - inside);
                if (!(inside > 0.0)) {
                    ++st.outside;
                    continue;
                }
                ++st.splatted;
                m.prints[k] = f;
                m.valid[k] = 1;
                const int b0 = std::max(f.y0, 0) / kBandRows, b1 = std::min(f.y1, H - 1) / kBandRows;
                for (int b = b0; b <= b1; ++b) ++count[b];
            }
        }
    });
    m.entries.resize(band_offsets(m.counts, chunks, static_cast<std::size_t>(bands), m.cursors, m.band_start));
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& rr) {
        for (std::size_t c = rr.begin(); c != rr.end(); ++c) {
            std::uint32_t* cursor = &m.cursors[c * bands];
            for (std::size_t k = c * kChunk; k < std::min(n, (c + 1) * kChunk); ++k) {
                if (!m.valid[k]) continue;
                const Footprint& f = m.prints[k];
                const int b0 = std::max(f.y0, 0) / kBandRows, b1 = std::min(f.y1, H - 1) / kBandRows;
                for (int b = b0; b <= b1; ++b) m.entries[cursor[b]++] = static_cast<std::uint32_t>(k);
            }
        }
    });
    tbb::parallel_for(tbb::blocked_range<int>(0, bands, 1), [&](const tbb::blocked_range<int>& rr) {
        for (int b = rr.begin(); b != rr.end(); ++b) {
            const int row0 = b * kBandRows, row1 = std::min(H, row0 + kBandRows) - 1;
            for (std::uint32_t e = m.band_start[static_cast<std::size_t>(b)]; e < m.band_start[static_cast<std::size_t>(b) + 1]; ++e) {
                const std::uint32_t k = m.entries[e];
                const Footprint& f = m.prints[k];
                if (!f.gaussian) {
                    target.at(f.x0, f.y0) += splats[k].value;
                    continue;
                }
                const float* wx = m.chunk_taps[k / kChunk].data() + f.taps;
                const float* wy = wx + (f.x1 - f.x0 + 1);
                const int xa = std::max(f.x0, 0), xb = std::min(f.x1, W - 1);
                for (int y = std::max(f.y0, row0); y <= std::min(f.y1, row1); ++y) {
                    const float wrow = wy[y - f.y0];
                    float* row = &target.pixels[static_cast<std::size_t>(y) * W];
                    for (int x = xa; x <= xb; ++x) row[x] += wrow * wx[x - f.x0];
                }
            }
        }
    });
    SplatStats stats;
    for (const SplatStats& s : m.chunk_stats) {
        stats.splatted += s.splatted;
        stats.outside += s.outside;
        stats.nonfinite += s.nonfinite;
        stats.value_inside += s.value_inside;
        stats.value_outside += s.value_outside;
    }
    return stats;
}

void gaussian_lowpass(Image& image, double radius) {
    if (radius < 1.0 || image.empty()) return;
    const int R = std::min(static_cast<int>(std::floor(radius)), 128);
    const double sigma = radius / 3.0;
    std::vector<double> w(static_cast<std::size_t>(2 * R + 1));
    for (int k = -R; k <= R; ++k) w[static_cast<std::size_t>(k + R)] = std::exp(-0.5 * k * k / (sigma * sigma));
    const int W = image.width, H = image.height;
    // Scatter form: source pixel i spreads over the taps that stay inside, renormalised by their sum
    // (inv_norm), so every pass keeps the total.
    auto inv_norm = [&](int len) {
        std::vector<double> out(static_cast<std::size_t>(len));
        for (int i = 0; i < len; ++i) {
            double s = 0.0;
            for (int k = -R; k <= R; ++k)
                if (i + k >= 0 && i + k < len) s += w[static_cast<std::size_t>(k + R)];
            out[static_cast<std::size_t>(i)] = 1.0 / s;
        }
        return out;
    };
    const std::vector<double> nx = inv_norm(W), ny = inv_norm(H);
    Image tmp(W, H);
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < W; ++x) {
                double acc = 0.0;
                for (int k = -R; k <= R; ++k) {
                    const int i = x + k;
                    if (i >= 0 && i < W) acc += image.at(i, y) * nx[static_cast<std::size_t>(i)] * w[static_cast<std::size_t>(R - k)];
                }
                tmp.at(x, y) = static_cast<float>(acc);
            }
    });
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y)
            for (int x = 0; x < W; ++x) {
                double acc = 0.0;
                for (int k = -R; k <= R; ++k) {
                    const int j = y + k;
                    if (j >= 0 && j < H) acc += tmp.at(x, j) * ny[static_cast<std::size_t>(j)] * w[static_cast<std::size_t>(R - k)];
                }
                image.at(x, y) = static_cast<float>(acc);
            }
    });
}

}  // namespace caustics
