// The phase-delayed launch of wave_pde (see wave_launch.hpp).
#include "wave_launch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/parallel_for.h>

#include <caustics/frame/baseline.hpp>

namespace caustics::wave {

namespace {
constexpr double kSheetWidth = 1.0;    // Gaussian width of the sheet's vertical profile [cells]
constexpr double kSheetCut = 3.0;      // cells further than this many widths carry nothing
constexpr double kPulseWidths = 4.0;   // a pulse's extent either side of its time (Source)
constexpr double kMinJacobian = 0.05;  // below: the rays have (nearly) crossed above the source plane
// Cells of the scheme's dispersive tail (its short components lag behind the pulse) that the flux
// window also takes: flat water at 30 degrees, std/mean of the floor at grid 128 / 256: 0.013 % /
// 0.083 % with margin 3 alone, 0.009 % / 0.015 % with 7 more; sine at grid 128: 0.395 -> 0.383. The flux
// is quadratic, so the later wakes add energy rather than cancel the caustic as the sum of phi would.
constexpr double kDispersiveTail = 7.0;
}  // namespace

namespace {

// The refracted ray through the surface point above horizontal position q: entry p, direction t (unit),
// the cosines, and where it meets the plane z = z0 (X).
struct Ray {
    glm::dvec3 p, t, big_n;
    double cos_i = 0.0, cos_t = 0.0;
    glm::dvec2 x;
    bool front = false;  // the light meets the surface from above
};

Ray refract_at(const HeightField& hf, glm::dvec2 q, const glm::dvec3& d, double inv_n, double z0) {
    Ray r;
    glm::dvec2 g;
    const double eta = extended_height(hf, q.x, q.y, &g);
    r.p = glm::dvec3(q, eta);
    r.big_n = glm::dvec3(-g.x, -g.y, 1.0);
    const glm::dvec3 normal = glm::normalize(r.big_n);
    r.cos_i = -glm::dot(d, normal);
    r.front = r.cos_i > 1e-9;
    // Snell: t = d / n + (cos_i / n - cos_t) normal.
    r.cos_t = std::sqrt(std::max(0.0, 1.0 - inv_n * inv_n * (1.0 - r.cos_i * r.cos_i)));
    r.t = r.front ? inv_n * d + (inv_n * r.cos_i - r.cos_t) * normal : d;
    const double tz = std::min(r.t.z, -1e-6);
    r.x = q + glm::dvec2(r.t) * ((eta - z0) / -tz);
    return r;
}

}  // namespace

Launch phase_delay_launch(const HeightField& hf, const VolumeShape& s, const glm::dvec3& light, double ior,
                          bool fresnel, const glm::dvec3& mean_refracted, double pulse_width, double margin,
                          const Aperture& aperture) {
    Launch out;
    const double h = s.spacing, inv_n = 1.0 / ior;
    const glm::dvec3 d = glm::normalize(light);
    // The source plane: one cell below the lowest point of the surface over the grid's columns on the
    // water (its linear extension beyond the rectangle may run far down over a wide padding).
    double lowest = std::numeric_limits<double>::infinity(), lowest_any = lowest;
    for (int j = 0; j < s.ny; ++j)
        for (int i = 0; i < s.nx; ++i) {
            const glm::dvec3 c = s.center(i, j, 0);
            const double eta = extended_height(hf, c.x, c.y);
            lowest_any = std::min(lowest_any, eta);
            if (hf.contains(c.x, c.y)) lowest = std::min(lowest, eta);
        }
    if (!std::isfinite(lowest)) lowest = lowest_any;
    const double z0 = lowest - h;
    out.plane_z = z0;
    struct Column {
        double time = 0.0, weight = 0.0, tz = -1.0;
        bool shadowed = false;
    };
    std::vector<Column> columns(static_cast<std::size_t>(s.nx) * s.ny);
    tbb::parallel_for(0, s.ny, [&](int j) {
        for (int i = 0; i < s.nx; ++i) {
            const glm::dvec3 c = s.center(i, j, 0);
            const glm::dvec2 x(c);
            // The entry point whose ray meets the plane at x: the fixed point of q = x - (X(q) - q),
            // which converges while the rays do not cross between the surface and the plane.
            glm::dvec2 q = x;
            Ray r;
            for (int it = 0; it < 6; ++it) {
                r = refract_at(hf, q, d, inv_n, z0);
                q += x - r.x;
            }
            r = refract_at(hf, q, d, inv_n, z0);
            Column& col = columns[static_cast<std::size_t>(j) * s.nx + i];
            col.tz = r.t.z;
            // The phase: the incident wave's arrival (d . p) / n in water path length, plus the path
            // from p to the plane along t.
            col.time = (glm::dot(d, r.p) * inv_n + glm::length(glm::dvec3(x, z0) - r.p)) / h;
            if (!r.front) {  // the light meets this slope from below: nothing enters here
                col.shadowed = true;
                continue;
            }
            // The Jacobian of q -> X(q) (central differences of a quarter cell): the plane's area per
            // unit of the surface's footprint.
            const double e = 0.25 * h;
            const glm::dvec2 ddx = (refract_at(hf, q + glm::dvec2(e, 0), d, inv_n, z0).x -
                                    refract_at(hf, q - glm::dvec2(e, 0), d, inv_n, z0).x) / (2.0 * e);
            const glm::dvec2 ddy = (refract_at(hf, q + glm::dvec2(0, e), d, inv_n, z0).x -
                                    refract_at(hf, q - glm::dvec2(0, e), d, inv_n, z0).x) / (2.0 * e);
            const double jac = ddx.x * ddy.y - ddx.y * ddy.x;
            if (!(jac > kMinJacobian)) {
                col.weight = -1.0;  // rays cross above the plane: marked, no source
                continue;
            }
            // Flux per unit footprint through the surface, |d . N| (times Fresnel), spread over jac of
            // the plane: the horizontal irradiance there; its amplitude squared is that over |t_z|,
            // and a horizontal profile's integral along t is sqrt(2 pi) / |t_z|.
            double flux = std::fabs(glm::dot(d, r.big_n)) / jac;
            if (fresnel) flux *= fresnel_transmittance(r.cos_i, r.cos_t, 1.0, ior);
            col.weight = std::sqrt(flux * std::fabs(r.t.z));
        }
    });
    out.source.width = pulse_width;
    // The stop window: Fermat's principle bounds the first arrival at x by the source plane's time at
    // the point q* the mean refracted direction t joins to x, plus |x - q*|; with the plane's times at
    // most t . q / h + C, that is t . x / h + C: an affine function of the cell (CellWindow).
    const glm::dvec3 tm = glm::normalize(mean_refracted);
    double c_max = -std::numeric_limits<double>::infinity();
    for (int j = 0; j < s.ny; ++j)
        for (int i = 0; i < s.nx; ++i) {
            const Column& col = columns[static_cast<std::size_t>(j) * s.nx + i];
            const glm::dvec3 c = s.center(i, j, 0);
            c_max = std::max(c_max, col.time - glm::dot(tm, glm::dvec3(c.x, c.y, z0)) / h);
            if (col.weight < 0.0) ++out.folded_columns;
            if (col.shadowed) ++out.shadowed_columns;
            const double weight = col.weight * aperture.weight(i, j);
            if (!(weight > 0.0)) continue;
            for (int k = 0; k < s.nz; ++k) {
                const double dz = s.origin.z + (k + 0.5) * h - z0;  // above the plane
                const double u = dz / (h * kSheetWidth);
                if (std::fabs(u) >= kSheetCut) continue;
                const double time = col.time + col.tz * dz / h;  // the local refracted plane wave's time
                out.source.cells.push_back({static_cast<std::uint32_t>(s.index(i, j, k)),
                                            static_cast<float>(weight * std::exp(-0.5 * u * u)), static_cast<float>(time)});
                c_max = std::max(c_max, time - glm::dot(tm, s.center(i, j, k)) / h);
            }
        }
    // Shift the times so the earliest pulse starts after t = 0.
    double first = std::numeric_limits<double>::infinity();
    for (const SourceCell& c : out.source.cells) first = std::min(first, static_cast<double>(c.time));
    const double shift = std::isfinite(first) ? kPulseWidths * pulse_width + 0.5 - first : 0.0;
    for (SourceCell& c : out.source.cells) c.time = static_cast<float>(c.time + shift);
    const double tail = kPulseWidths * pulse_width + kDispersiveTail + margin;
    out.window.s0 = c_max + shift + tail + glm::dot(tm, s.center(0, 0, 0)) / h;
    out.window.sx = tm.x;
    out.window.sy = tm.y;
    out.window.sz = tm.z;
    out.stop.assign(static_cast<std::size_t>(s.nz), 0.0);
    for (int k = 0; k < s.nz; ++k)
        out.stop[static_cast<std::size_t>(k)] = out.window.s0 + std::max(0.0, tm.x * (s.nx - 1)) + std::max(0.0, tm.y * (s.ny - 1)) + tm.z * k;
    return out;
}

AxisPadding upstream_padding(double refracted_component, double refracted_z, int depth_cells, int sponge, int ramp, int gap) {
    AxisPadding pad{sponge, sponge, 0, 0};
    if (std::fabs(refracted_component) < 1e-9) return pad;
    const int reach = static_cast<int>(std::ceil(depth_cells * std::fabs(refracted_component) / std::max(std::fabs(refracted_z), 1e-6)));
    pad.low += ramp + gap;
    pad.high += ramp + gap;
    // Light travelling towards +x comes from the low face.
    (refracted_component > 0.0 ? pad.low : pad.high) += reach;
    pad.ramp_low = pad.ramp_high = ramp;
    return pad;
}

double Aperture::weight(int i, int j) const {
    auto ramp = [](int u, int width) {
        if (u < 0) return 0.0;
        if (u >= width) return 1.0;
        const double x = (u + 0.5) / width;
        const double s = std::sin(0.5 * 3.141592653589793 * x);
        return s * s;
    };
    const int idx[2] = {i, j};
    double w = 1.0;
    for (int a = 0; a < 2; ++a) w *= ramp(idx[a] - begin[a], ramp_begin[a]) * ramp(end[a] - 1 - idx[a], ramp_end[a]);
    return w;
}

}  // namespace caustics::wave
