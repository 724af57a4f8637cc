// Surface resampling, the depth-slice intensity table and its lookup: see wave_field_table.hpp.
#include "wave_field_table.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace caustics::wave_optics {

namespace {

// Raised-cosine weight of the border at distance d outside the surface: 1 at its edge, 0 at d = pad.
double border_weight(double d, double pad) {
    if (d <= 0.0) return 1.0;
    if (d >= pad) return 0.0;
    return 0.5 + 0.5 * std::cos(std::numbers::pi * d / pad);
}

// Periodic index into [0, n).
inline int wrap(int i, int n) {
    i %= n;
    return i < 0 ? i + n : i;
}

// Bilinear value of a row-major table (rows of `stride`) between columns xa, xb and rows ya, yb.
inline float bilinear_texel(const float* t, int stride, int xa, int xb, int ya, int yb, float ax, float ay) {
    const float v00 = t[static_cast<std::size_t>(ya) * stride + xa];
    const float v10 = t[static_cast<std::size_t>(ya) * stride + xb];
    const float v01 = t[static_cast<std::size_t>(yb) * stride + xa];
    const float v11 = t[static_cast<std::size_t>(yb) * stride + xb];
    const float top = v00 + ax * (v10 - v00);
    const float bottom = v01 + ax * (v11 - v01);
    return top + ay * (bottom - top);
}

}  // namespace

WaveFieldTable::WaveFieldTable(int nx, int ny, bool rgb) : nx_(nx), ny_(ny), rgb_(rgb) {
    surface_.height.assign(static_cast<std::size_t>(nx) * ny, 0.0f);
}

EdgeCheck check_edges(const HeightField& hf) {
    // Periodicity: flagged by the generator, or opposite edges equal to within 1e-3 of the height range.
    double edge_sum = 0.0;
    std::size_t edge_count = 0;
    for (int j = 0; j < hf.ny; ++j) {
        edge_sum += hf.z(0, j) + hf.z(hf.nx - 1, j);
        edge_count += 2;
    }
    for (int i = 0; i < hf.nx; ++i) {
        edge_sum += hf.z(i, 0) + hf.z(i, hf.ny - 1);
        edge_count += 2;
    }
    return {tiles_its_rectangle(hf, 1e-3), edge_sum / std::max<std::size_t>(edge_count, 1)};
}

FftWindow fft_window(const EdgeCheck& edges, double lx, double ly) {
    FftWindow w;
    w.periodic = edges.periodic;
    w.edge_mean = edges.edge_mean;
    w.pad = edges.periodic ? 0.0 : border_pad_width(lx, ly);
    w.lx = lx + 2.0 * w.pad;
    w.ly = ly + 2.0 * w.pad;
    return w;
}

const SurfaceSamples& WaveFieldTable::resample(const HeightField& hf, const FftWindow& window, double lx, double ly,
                                               ResamplePath path) {
    surface_.window = window;
    const double edge_mean = window.edge_mean;
    const double pad = window.pad;

    // Per grid column / row: the surface vertex to the left (bilinear weight), or for a border sample the
    // edge vertex it copies and the border's weight. Grid sample i sits at window coordinate i lx' / N, the
    // surface's coordinate that less the border.
    std::vector<int> i0(static_cast<std::size_t>(nx_)), j0(static_cast<std::size_t>(ny_));
    std::vector<float> fx(static_cast<std::size_t>(nx_)), fy(static_cast<std::size_t>(ny_));
    std::vector<float> wx(static_cast<std::size_t>(nx_), 1.0f), wy(static_cast<std::size_t>(ny_), 1.0f);
    auto axis = [pad](int i, int n, double window_l, double surface_l, int vertices, int& v0, float& f, float& w) {
        double g = static_cast<double>(i) * (vertices - 1) / n;   // no border: the surface is the window
        w = 1.0f;
        if (pad > 0.0) {
            const double s = static_cast<double>(i) * window_l / n - pad;
            w = static_cast<float>(border_weight(std::max(-s, s - surface_l), pad));
            g = std::clamp(s / surface_l, 0.0, 1.0) * (vertices - 1);
        }
        v0 = std::min(static_cast<int>(g), std::max(vertices - 2, 0));
        f = static_cast<float>(g - v0);
    };
    for (int i = 0; i < nx_; ++i) {
        const std::size_t k = static_cast<std::size_t>(i);
        axis(i, nx_, window.lx, lx, hf.nx, i0[k], fx[k], wx[k]);
    }
    for (int j = 0; j < ny_; ++j) {
        const std::size_t k = static_cast<std::size_t>(j);
        axis(j, ny_, window.ly, ly, hf.ny, j0[k], fy[k], wy[k]);
    }
    const int step_x = hf.nx > 1 ? 1 : 0;
    const int step_y = hf.ny > 1 ? 1 : 0;
    const float e = static_cast<float>(edge_mean);
    const bool taper = pad > 0.0;
    // On-vertex samples: g = i (vertices - 1) / N is an integer, so f = 0 and the blend returns the
    // vertex exactly (x + 0 * y = x for finite heights).
    const bool on_vertices = path == ResamplePath::Auto && !taper && hf.nx > 1 && hf.ny > 1 &&
                             (hf.nx - 1) % nx_ == 0 && (hf.ny - 1) % ny_ == 0;
    const int vertex_step_x = on_vertices ? (hf.nx - 1) / nx_ : 0;
    std::vector<double> row_sum(static_cast<std::size_t>(ny_), 0.0);
    float* out = surface_.height.data();
    tbb::parallel_for(tbb::blocked_range<int>(0, ny_, 8), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) {
            const std::size_t ju = static_cast<std::size_t>(j);
            const float* row0 = hf.height.data() + static_cast<std::size_t>(j0[ju]) * hf.nx;
            const float* row1 = row0 + static_cast<std::size_t>(step_y) * hf.nx;
            const float b = fy[ju];
            float* dst = out + ju * nx_;
            double sum = 0.0;
            if (on_vertices) {
                for (int i = 0; i < nx_; ++i) {
                    const float h = row0[static_cast<std::size_t>(i) * vertex_step_x];   // no border here
                    dst[i] = h;
                    sum += h;
                }
                row_sum[ju] = sum;
                continue;
            }
            for (int i = 0; i < nx_; ++i) {
                const std::size_t iu = static_cast<std::size_t>(i);
                const int a = i0[iu];
                const float f = fx[iu];
                const float top = row0[a] + f * (row0[a + step_x] - row0[a]);
                const float bottom = row1[a] + f * (row1[a + step_x] - row1[a]);
                float h = top + b * (bottom - top);
                if (taper) h = e + wx[iu] * wy[ju] * (h - e);
                dst[i] = h;
                sum += h;
            }
            row_sum[ju] = sum;
        }
    });
    double total = 0.0;
    for (double s : row_sum) total += s;
    const double level = total / (static_cast<double>(nx_) * ny_);
    surface_.level = level;
    const float lf = static_cast<float>(level);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, surface_.height.size(), 1 << 14),
                      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) out[k] -= lf;
    });
    return surface_;
}

void WaveFieldTable::begin(int slices) {
    slices_ = slices;
    const std::size_t need = static_cast<std::size_t>(rgb_ ? 4 : 1) * slices * nx_ * ny_;
    if (data_.size() < need) data_.resize(need);
}

float* WaveFieldTable::slice_mut(int s, int channel) {
    return data_.data() + (static_cast<std::size_t>(channel) * slices_ + s) * nx_ * ny_;
}

const float* WaveFieldTable::slice(int s, int channel) const {
    return data_.data() + (static_cast<std::size_t>(channel) * slices_ + s) * nx_ * ny_;
}

int WaveFieldTable::targets(int slice, int sample, float mono_weight, const float rgb[3], IntensityTarget* t) {
    int count = 0;
    t[count++] = {slice_mut(slice, 0), mono_weight, sample == 0};
    if (rgb_)
        for (int c = 0; c < 3; ++c) t[count++] = {slice_mut(slice, c + 1), rgb[c], sample == 0};
    return count;
}

void WaveFieldTable::blur(double sigma_m, double lx, double ly) {
    // Separable, periodic (the table is one period of a tiling). Kernel radius 3 sigma, at most half
    // the period.
    auto kernel = [](double sigma_cells, int n) {
        const int radius = std::min(static_cast<int>(std::ceil(3.0 * sigma_cells)), (n - 1) / 2);
        std::vector<float> w(static_cast<std::size_t>(2 * radius + 1));
        double sum = 0.0;
        for (int i = -radius; i <= radius; ++i) {
            const double v = std::exp(-0.5 * i * i / (sigma_cells * sigma_cells));
            w[static_cast<std::size_t>(i + radius)] = static_cast<float>(v);
            sum += v;
        }
        for (float& v : w) v = static_cast<float>(v / sum);
        return w;
    };
    const std::vector<float> kx = kernel(sigma_m / (lx / nx_), nx_), ky = kernel(sigma_m / (ly / ny_), ny_);
    const int rx = static_cast<int>(kx.size() / 2), ry = static_cast<int>(ky.size() / 2);
    std::vector<float> tmp(static_cast<std::size_t>(nx_) * ny_);
    const int channels = rgb_ ? 4 : 1;
    for (int c = 0; c < channels; ++c)
        for (int s = 0; s < slices_; ++s) {
            float* t = slice_mut(s, c);
            tbb::parallel_for(0, ny_, [&](int j) {
                const float* row = t + static_cast<std::size_t>(j) * nx_;
                float* dst = tmp.data() + static_cast<std::size_t>(j) * nx_;
                for (int i = 0; i < nx_; ++i) {
                    float acc = 0.0f;
                    for (int d = -rx; d <= rx; ++d) acc += kx[static_cast<std::size_t>(d + rx)] * row[wrap(i + d, nx_)];
                    dst[i] = acc;
                }
            });
            tbb::parallel_for(0, ny_, [&](int j) {
                float* dst = t + static_cast<std::size_t>(j) * nx_;
                std::fill(dst, dst + nx_, 0.0f);
                for (int d = -ry; d <= ry; ++d) {
                    const float w = ky[static_cast<std::size_t>(d + ry)];
                    const float* src = tmp.data() + static_cast<std::size_t>(wrap(j + d, ny_)) * nx_;
                    for (int i = 0; i < nx_; ++i) dst[i] += w * src[i];
                }
            });
        }
}

void WaveFieldTable::lookup(const LookupGeometry& geo, const std::vector<ShadePoint>& points,
                            std::vector<glm::vec4>& values, LookupCounters& counters) const {
    const int channels = rgb_ ? 4 : 1;
    const int slices = static_cast<int>(geo.depths.size());
    const double dx = geo.lx / nx_, dy = geo.ly / ny_;
    const double cos_t = std::max(1e-9, -geo.refracted.z);
    const glm::dvec2 beam_walk(geo.refracted.x / cos_t, geo.refracted.y / cos_t);
    const double z0 = slices > 0 ? geo.depths.front() : 0.0;
    const double z1 = slices > 0 ? geo.depths.back() : 0.0;
    const double sx = geo.lx - 2.0 * geo.pad, sy = geo.ly - 2.0 * geo.pad;   // the surface's size
    std::vector<std::int64_t> not_covered(points.size(), 0), tapered(points.size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
            values[k] = glm::vec4(0.0f);
            const ShadePoint& p = points[k];
            const double z = geo.level - p.position.z;
            if (slices == 0 || !(z > 0.0)) {
                not_covered[k] = 1;
                continue;
            }
            // Where the light reaching p crossed the mean surface (geometric beam), and where the
            // propagator's shifted frame holds p's intensity.
            const glm::dvec2 entry = glm::dvec2(p.position) - z * beam_walk;
            const glm::dvec2 rel = entry - geo.origin - glm::dvec2(geo.pad);   // from the surface's corner
            if (rel.x < 0.0 || rel.y < 0.0 || rel.x > sx || rel.y > sy) {
                not_covered[k] = 1;
                continue;
            }
            if (geo.pad > 0.0 && std::min({rel.x, rel.y, sx - rel.x, sy - rel.y}) < z * geo.reach_per_m)
                tapered[k] = 1;
            const glm::dvec2 table = glm::dvec2(p.position) - z * geo.walk - geo.origin;
            const double gx = table.x / dx, gy = table.y / dy;
            const double fxf = std::floor(gx), fyf = std::floor(gy);
            const float ax = static_cast<float>(gx - fxf), ay = static_cast<float>(gy - fyf);
            const int xa = wrap(static_cast<int>(fxf), nx_), xb = wrap(xa + 1, nx_);
            const int ya = wrap(static_cast<int>(fyf), ny_), yb = wrap(ya + 1, ny_);
            int sa = 0, sb = 0;
            float as = 0.0f;
            if (slices > 1 && z1 > z0) {
                const double u = std::clamp((z - z0) / (z1 - z0) * (slices - 1), 0.0, static_cast<double>(slices - 1));
                sa = std::min(static_cast<int>(u), slices - 2);
                sb = sa + 1;
                as = static_cast<float>(u - sa);
            }
            const double facing = std::max(0.0, -glm::dot(geo.refracted, p.normal)) / cos_t;
            const float scale = static_cast<float>(geo.irradiance * std::exp(-geo.absorption * z / cos_t) * facing);
            for (int c = 0; c < channels; ++c) {
                auto bilinear = [&](int s) { return bilinear_texel(slice(s, c), nx_, xa, xb, ya, yb, ax, ay); };
                float v = bilinear(sa);
                if (sb != sa) v += as * (bilinear(sb) - v);
                values[k][c] = scale * v;
            }
        }
    });
    for (std::size_t k = 0; k < points.size(); ++k) {
        counters.not_covered += not_covered[k];
        counters.tapered += tapered[k];
    }
}

void fill_periodic_texture(const WaveFieldTable& table, int n, const LookupGeometry& geo, Image& mono, Image* rgb) {
    const int W = mono.width, H = mono.height;
    const double z = geo.depths.empty() ? 0.0 : geo.depths.front();
    const double dx = geo.lx / n, dy = geo.ly / n;
    const double cos_t = std::max(1e-9, -geo.refracted.z);
    const float scale = static_cast<float>(geo.irradiance * std::exp(-geo.absorption * z / cos_t));
    tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) {
            const double ty = ((j + 0.5) * geo.ly / H - z * geo.walk.y) / dy;
            const double fyf = std::floor(ty);
            const float ay = static_cast<float>(ty - fyf);
            const int ya = wrap(static_cast<int>(fyf), n), yb = wrap(ya + 1, n);
            for (int i = 0; i < W; ++i) {
                const double tx = ((i + 0.5) * geo.lx / W - z * geo.walk.x) / dx;
                const double fxf = std::floor(tx);
                const float ax = static_cast<float>(tx - fxf);
                const int xa = wrap(static_cast<int>(fxf), n), xb = wrap(xa + 1, n);
                auto bilinear = [&](int c) { return bilinear_texel(table.slice(0, c), n, xa, xb, ya, yb, ax, ay); };
                mono.at(i, j) = scale * bilinear(0);
                if (rgb != nullptr)
                    for (int c = 0; c < 3; ++c) rgb->at(i, j, c) = scale * bilinear(c + 1);
            }
        }
    });
}

}  // namespace caustics::wave_optics
