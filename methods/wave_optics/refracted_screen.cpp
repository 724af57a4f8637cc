// The refracted wave on the reference plane from the exact refraction at each surface sample: see
// refracted_screen.hpp.
#include "refracted_screen.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "wave_math.hpp"

namespace caustics::wave_optics {

namespace {

// Periodic index for |i| < 2n (neighbours and the small offsets of this file): no division.
inline int wrap(int i, int n) {
    i = i < 0 ? i + n : i;
    return i >= n ? i - n : i;
}

// Periodic index for any i (the crossing offsets are a few cells; a steep surface may have more).
inline int wrap_far(int i, int n) {
    if (i >= 0 && i < n) return i;
    i %= n;
    return i < 0 ? i + n : i;
}

}  // namespace

double fresnel_transmittance(double ci, double n) {
    const double si2 = std::max(0.0, 1.0 - ci * ci);
    const double st2 = si2 / (n * n);
    if (st2 >= 1.0) return 0.0;
    const double ct = std::sqrt(1.0 - st2);
    const double rs = (ci - n * ct) / (ci + n * ct);
    const double rp = (n * ci - ct) / (n * ci + ct);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

void build_refracted_screen(const float* height, const RefractionSetup& s, RefractedScreen& out) {
    const int nx = s.nx, ny = s.ny;
    const std::size_t cells = static_cast<std::size_t>(nx) * ny;
    const double dx = s.lx / nx, dy = s.ly / ny;
    const glm::dvec3 d = s.light;
    const double cos_i = -d.z, n = s.ior;
    const double flat = cos_i * (s.fresnel ? fresnel_transmittance(cos_i, n) : 1.0);

    // 1. Per surface sample: exact refraction, the crossing offset D (in cells), P and the flux weight,
    // packed so that step 3 gathers them together.
    using Sample = RefractedScreen::Sample;
    std::vector<Sample>& samples = out.samples;
    samples.resize(cells);
    std::vector<std::int32_t> unlit(static_cast<std::size_t>(ny), 0), folded(static_cast<std::size_t>(ny), 0);
    // Reciprocals hoisted out of the per-sample loop (divisions dominate it otherwise).
    const double ihx = 0.5 / dx, ihy = 0.5 / dy, idx = 1.0 / dx, idy = 1.0 / dy, inv_n = 1.0 / n, inv_n2 = inv_n * inv_n;
    const double inv_flat = 1.0 / flat;
    const double cos_t0 = std::sqrt(std::max(0.0, 1.0 - (1.0 - cos_i * cos_i) / (n * n)));
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 16), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) {
            const float* hm = height + static_cast<std::size_t>(wrap(j - 1, ny)) * nx;
            const float* h0 = height + static_cast<std::size_t>(j) * nx;
            const float* hp = height + static_cast<std::size_t>(wrap(j + 1, ny)) * nx;
            for (int i = 0; i < nx; ++i) {
                const std::size_t k = static_cast<std::size_t>(j) * nx + i;
                const double hk = h0[i];
                const glm::dvec2 g((h0[wrap(i + 1, nx)] - h0[wrap(i - 1, nx)]) * ihx, (hp[i] - hm[i]) * ihy);
                const glm::dvec3 m(-g.x, -g.y, 1.0);            // upward normal, |m| = sqrt(1 + |g|^2)
                const double facing = -glm::dot(d, m);          // cos_i + d_xy . g: intercepted flux per unit area
                if (!(facing > 0.0)) {                          // the light grazes or hits the back of the slope
                    ++unlit[static_cast<std::size_t>(j)];
                    samples[k] = {0.0f, 0.0f, static_cast<float>(hk * (n * cos_t0 - cos_i)), 0.0f};
                    continue;
                }
                const double inv_m = 1.0 / std::sqrt(1.0 + glm::dot(g, g));
                const glm::dvec3 nn = m * inv_m;
                const double ci = facing * inv_m;
                // Snell in vector form: t = d / n + (ci / n - ct) nn.
                const double ct = std::sqrt(std::max(0.0, 1.0 - (1.0 - ci * ci) * inv_n2));
                const glm::dvec3 t = d * inv_n + (ci * inv_n - ct) * nn;
                const double inv_tz = 1.0 / std::max(-t.z, 1e-9);
                const double tr = s.fresnel ? fresnel_transmittance(ci, n) : 1.0;
                const double absorbed = s.absorption > 0.0 ? std::exp(-s.absorption * hk * inv_tz) : 1.0;
                samples[k] = {static_cast<float>(hk * t.x * inv_tz * idx), static_cast<float>(hk * t.y * inv_tz * idy),
                              static_cast<float>(hk * ((n - d.x * t.x - d.y * t.y) * inv_tz - cos_i)),
                              static_cast<float>(facing * tr * absorbed * inv_flat)};
            }
        }
    });
    // 2. Flux density on the plane: the weight over the Jacobian det(I + dD/dx_s) of the map x_s -> X
    // (only the density member is written; the offsets read are not).
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 16), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j) {
            const Sample* sm = samples.data() + static_cast<std::size_t>(wrap(j - 1, ny)) * nx;
            Sample* s0 = samples.data() + static_cast<std::size_t>(j) * nx;
            const Sample* sp = samples.data() + static_cast<std::size_t>(wrap(j + 1, ny)) * nx;
            for (int i = 0; i < nx; ++i) {
                const Sample& a = s0[wrap(i + 1, nx)];
                const Sample& b = s0[wrap(i - 1, nx)];
                const double ddx_x = 0.5 * (a.dx - b.dx), ddx_y = 0.5 * (a.dy - b.dy);
                const double ddy_x = 0.5 * (sp[i].dx - sm[i].dx), ddy_y = 0.5 * (sp[i].dy - sm[i].dy);
                const double det = (1.0 + ddx_x) * (1.0 + ddy_y) - ddx_y * ddy_x;
                if (!(det > 0.0)) {
                    ++folded[static_cast<std::size_t>(j)];
                    s0[i].density = 0.0f;
                } else {
                    s0[i].density = static_cast<float>(s0[i].density / det);
                }
            }
        }
    });
    // 3. Resample onto the plane's grid: the preimage x_s of each node X solves x_s + D(x_s) = X, by fixed
    // point iteration from x_s = X - D(X) (a contraction: |dD/dx_s| ~ slope tan(theta_t), ~0.1 for steep
    // water; two more steps leave ~1e-3 of the offset, a few micrometres).
    out.path.resize(cells);
    out.amplitude.resize(cells);
    const int ishift = 4 * std::max(nx, ny);
    const float shift = static_cast<float>(ishift);
    tbb::parallel_for(tbb::blocked_range<int>(0, ny, 16), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j < r.end(); ++j)
            for (int i = 0; i < nx; ++i) {
                const Sample& self = samples[static_cast<std::size_t>(j) * nx + i];
                float x = static_cast<float>(i) - self.dx, y = static_cast<float>(j) - self.dy;
                // Bilinear weights and the four samples around (x, y).
                const Sample *s00, *s10, *s01, *s11;
                float ax, ay;
                auto locate = [&] {
                    // Floor by truncating a shifted positive value (std::floor is a libm call without
                    // SSE4.1, and this loop is the screen's main cost).
                    x = std::max(x, 1.0f - shift);
                    y = std::max(y, 1.0f - shift);
                    const int ix = static_cast<int>(x + shift) - ishift;
                    const int iy = static_cast<int>(y + shift) - ishift;
                    ax = x - static_cast<float>(ix);
                    ay = y - static_cast<float>(iy);
                    const int x0 = wrap_far(ix, nx), x1 = wrap(x0 + 1, nx);
                    const Sample* r0 = samples.data() + static_cast<std::size_t>(wrap_far(iy, ny)) * nx;
                    const Sample* r1 = samples.data() + static_cast<std::size_t>(wrap(wrap_far(iy, ny) + 1, ny)) * nx;
                    s00 = r0 + x0;
                    s10 = r0 + x1;
                    s01 = r1 + x0;
                    s11 = r1 + x1;
                };
                auto lerp = [&](float a00, float a10, float a01, float a11) {
                    const float top = a00 + ax * (a10 - a00), bottom = a01 + ax * (a11 - a01);
                    return top + ay * (bottom - top);
                };
                for (int it = 0; it < 2; ++it) {
                    locate();
                    x = static_cast<float>(i) - lerp(s00->dx, s10->dx, s01->dx, s11->dx);
                    y = static_cast<float>(j) - lerp(s00->dy, s10->dy, s01->dy, s11->dy);
                }
                locate();
                Sample v{};
                v.path = lerp(s00->path, s10->path, s01->path, s11->path);
                v.density = lerp(s00->density, s10->density, s01->density, s11->density);
                const std::size_t k = static_cast<std::size_t>(j) * nx + i;
                out.path[k] = v.path;
                out.amplitude[k] = std::sqrt(std::max(0.0f, v.density));
            }
    });
    out.folded_cells = 0;
    out.unlit_cells = 0;
    for (int j = 0; j < ny; ++j) {
        out.folded_cells += folded[static_cast<std::size_t>(j)];
        out.unlit_cells += unlit[static_cast<std::size_t>(j)];
    }
}

std::int64_t screen_field(const RefractedScreen& screen, int n, double k0, std::vector<ComplexF>& field) {
    field.resize(static_cast<std::size_t>(n) * n);
    std::vector<std::int64_t> aliased(static_cast<std::size_t>(n), 0);
    const double limit = std::numbers::pi / k0;
    tbb::parallel_for(0, n, [&](int j) {
        const std::size_t row = static_cast<std::size_t>(j) * n, next = static_cast<std::size_t>((j + 1) % n) * n;
        std::int64_t count = 0;
        for (int i = 0; i < n; ++i) {
            const float* P = screen.path.data();
            float s, c;
            fast_sincos(static_cast<float>(k0 * P[row + i]), s, c);   // |phase| < 1e4, as set_phase_screen's
            const float a = screen.amplitude[row + i];
            field[row + i] = ComplexF(a * c, a * s);
            const int i1 = (i + 1) % n;
            count += static_cast<int>(std::abs(P[row + i1] - P[row + i]) > limit) |
                     static_cast<int>(std::abs(P[next + i] - P[row + i]) > limit);
        }
        aliased[static_cast<std::size_t>(j)] = count;
    });
    std::int64_t total = 0;
    for (std::int64_t c : aliased) total += c;
    return total;
}

}  // namespace caustics::wave_optics
