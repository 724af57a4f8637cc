// Height fields: grid sampling and triangulation, and the surface generators of docs/design.md section 8.
// The analytic generators (flat, sine, gaussian) live here; noise, waves and image are in
// heightfield_noise.cpp, heightfield_waves.cpp and heightfield_image.cpp.
#include <caustics/scene/heightfield/heightfield.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "detail/heightfield_generators.hpp"

namespace caustics {

namespace {

// Grid coordinate of world coordinate x along one axis: clamped to [0, n-1], or wrapped for periodic
// fields (vertex n-1 is vertex 0 again, so the period is n-1 cells).
[[gnu::always_inline]] inline void grid_coord(double x, double origin, double spacing, int n, bool periodic, int& i0,
                                              int& i1, double& f) {
    double g = (x - origin) / spacing;
    const int cells = n - 1;
    if (cells <= 0) {
        i0 = i1 = 0;
        f = 0.0;
        return;
    }
    if (periodic) {
        g = std::fmod(g, static_cast<double>(cells));
        if (g < 0.0) g += cells;
        if (!(g < cells)) g = 0.0;  // fmod rounding up to exactly `cells`
    } else {
        g = std::clamp(g, 0.0, static_cast<double>(cells));
        if (!(g >= 0.0)) g = 0.0;   // NaN: a cell, not an index out of range
    }
    // g >= 0 here (NaN aside), so truncation is floor, without a libm call.
    i0 = std::min(static_cast<int>(g), cells - 1);
    f = g - i0;
    i1 = i0 + 1;
}

// The grid cell around (x, y) and the position inside it (a single-vertex axis gives i0 = i1 = 0).
struct GridCell {
    int i0, i1, j0, j1;
    double fx, fy;
};

[[gnu::always_inline]] inline GridCell locate(const HeightField& hf, double x, double y) {
    GridCell c;
    grid_coord(x, hf.origin.x, hf.spacing.x, hf.nx, hf.periodic, c.i0, c.i1, c.fx);
    grid_coord(y, hf.origin.y, hf.spacing.y, hf.ny, hf.periodic, c.j0, c.j1, c.fy);
    return c;
}

// Bilinear interpolation of the vertex values value(i, j) over the cell.
template <class Value>
[[gnu::always_inline]] inline auto bilinear(const GridCell& c, Value value) {
    const auto a = value(c.i0, c.j0), b = value(c.i1, c.j0), d = value(c.i0, c.j1), e = value(c.i1, c.j1);
    return (1.0 - c.fy) * ((1.0 - c.fx) * a + c.fx * b) + c.fy * ((1.0 - c.fx) * d + c.fx * e);
}

}  // namespace

bool HeightField::contains(double x, double y) const {
    const glm::dvec2 e = extent();
    return x >= origin.x && x <= origin.x + e.x && y >= origin.y && y <= origin.y + e.y;
}

double HeightField::sample_height(double x, double y) const {
    return bilinear(locate(*this, x, y), [this](int i, int j) { return static_cast<double>(z(i, j)); });
}

glm::dvec2 HeightField::sample_gradient(double x, double y) const {
    if (exact_gradient) return exact_gradient(x, y);
    return bilinear(locate(*this, x, y), [this](int i, int j) { return glm::dvec2(grad(i, j)); });
}

glm::dvec3 HeightField::sample_normal(double x, double y) const {
    const glm::dvec2 g = sample_gradient(x, y);
    return glm::normalize(glm::dvec3(-g.x, -g.y, 1.0));
}

TriangleMesh HeightField::triangulate() const {
    TriangleMesh mesh;
    const std::size_t count = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
    mesh.positions.resize(count);
    mesh.normals.resize(count);
    for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
            const std::size_t k = static_cast<std::size_t>(j) * nx + i;
            mesh.positions[k] = glm::vec3(static_cast<float>(origin.x + i * spacing.x),
                                          static_cast<float>(origin.y + j * spacing.y), height[k]);
            const glm::vec2 g = gradient[k];
            mesh.normals[k] = glm::normalize(glm::vec3(-g.x, -g.y, 1.0f));
        }
    }
    if (nx < 2 || ny < 2) return mesh;
    mesh.triangles.reserve(static_cast<std::size_t>(nx - 1) * (ny - 1) * 2);
    for (int j = 0; j + 1 < ny; ++j) {
        for (int i = 0; i + 1 < nx; ++i) {
            const unsigned a = static_cast<unsigned>(j * nx + i), b = a + 1;
            const unsigned c = a + static_cast<unsigned>(nx), d = c + 1;
            // Counter-clockwise seen from +z (the outward, upward side).
            mesh.triangles.emplace_back(a, b, d);
            mesh.triangles.emplace_back(a, d, c);
        }
    }
    return mesh;
}

namespace detail {

HeightField make_grid(const HeightFieldDesc& desc) {
    HeightField hf;
    hf.nx = desc.resolution.x + 1;
    hf.ny = desc.resolution.y + 1;
    hf.origin = desc.center - 0.5 * desc.size;
    hf.spacing = desc.size / glm::dvec2(desc.resolution);
    const std::size_t count = static_cast<std::size_t>(hf.nx) * static_cast<std::size_t>(hf.ny);
    hf.height.assign(count, static_cast<float>(desc.base_height));
    hf.gradient.assign(count, glm::vec2(0.0f));
    return hf;
}

void gradients_by_central_differences(HeightField& hf) {
    for (int j = 0; j < hf.ny; ++j) {
        for (int i = 0; i < hf.nx; ++i) {
            const int il = std::max(i - 1, 0), ir = std::min(i + 1, hf.nx - 1);
            const int jl = std::max(j - 1, 0), jr = std::min(j + 1, hf.ny - 1);
            const double gx = ir > il ? (double(hf.z(ir, j)) - hf.z(il, j)) / ((ir - il) * hf.spacing.x) : 0.0;
            const double gy = jr > jl ? (double(hf.z(i, jr)) - hf.z(i, jl)) / ((jr - jl) * hf.spacing.y) : 0.0;
            hf.gradient[static_cast<std::size_t>(j) * hf.nx + i] = glm::vec2(float(gx), float(gy));
        }
    }
}

}  // namespace detail

namespace {

// Fills the grid from an analytic height h(x, y) and gradient, and keeps the gradient for exact normals.
template <class HeightFn, class GradFn>
void fill_analytic(HeightField& hf, double base, HeightFn h, GradFn g) {
    for (int j = 0; j < hf.ny; ++j) {
        const double y = hf.origin.y + j * hf.spacing.y;
        for (int i = 0; i < hf.nx; ++i) {
            const double x = hf.origin.x + i * hf.spacing.x;
            const std::size_t k = static_cast<std::size_t>(j) * hf.nx + i;
            hf.height[k] = static_cast<float>(base + h(x, y));
            hf.gradient[k] = glm::vec2(g(x, y));
        }
    }
    hf.exact_gradient = g;
}

}  // namespace

HeightField generate_heightfield(const HeightFieldDesc& desc, double time, int frame, double fps) {
    constexpr double kTwoPi = 2.0 * std::numbers::pi;
    HeightField hf = detail::make_grid(desc);
    switch (desc.generator) {
    case HeightGenerator::Flat:
        hf.exact_gradient = [](double, double) { return glm::dvec2(0.0); };
        break;
    case HeightGenerator::Sine: {
        // amplitude * sin(2 pi (d . p) / wavelength + phase + 2 pi speed t / wavelength)
        const double len = glm::length(desc.direction);
        const glm::dvec2 d = len > 0.0 ? desc.direction / len : glm::dvec2(1.0, 0.0);
        const double k = kTwoPi / desc.wavelength, amplitude = desc.amplitude;
        const double offset = desc.phase + k * desc.speed * time;
        fill_analytic(
            hf, desc.base_height,
            [=](double x, double y) { return amplitude * std::sin(k * (d.x * x + d.y * y) + offset); },
            [=](double x, double y) {
                return (amplitude * k * std::cos(k * (d.x * x + d.y * y) + offset)) * d;
            });
        break;
    }
    case HeightGenerator::Gaussian: {
        // amplitude * exp(-|p - c|^2 / (2 sigma^2))
        const glm::dvec2 c = desc.gauss_center;
        const double amplitude = desc.amplitude, inv_s2 = 1.0 / (desc.sigma * desc.sigma);
        fill_analytic(
            hf, desc.base_height,
            [=](double x, double y) {
                const glm::dvec2 r(x - c.x, y - c.y);
                return amplitude * std::exp(-0.5 * glm::dot(r, r) * inv_s2);
            },
            [=](double x, double y) {
                const glm::dvec2 r(x - c.x, y - c.y);
                return (-amplitude * inv_s2 * std::exp(-0.5 * glm::dot(r, r) * inv_s2)) * r;
            });
        break;
    }
    case HeightGenerator::Noise:
        detail::generate_noise(desc, time, hf);
        break;
    case HeightGenerator::Waves:
        detail::generate_waves(desc, frame, fps, hf);
        break;
    case HeightGenerator::Image:
        detail::generate_image(desc, hf);
        break;
    }
    return hf;
}

void height_range(const HeightField& hf, double& hmin, double& hmax) {
    hmin = 1e300;
    hmax = -1e300;
    for (float z : hf.height) {
        hmin = std::min(hmin, double(z));
        hmax = std::max(hmax, double(z));
    }
}

bool tiles_its_rectangle(const HeightField& hf, double relative_tolerance) {
    if (hf.periodic) return true;
    if (hf.nx < 2 || hf.ny < 2 || hf.height.size() != static_cast<std::size_t>(hf.nx) * hf.ny) return false;
    // The edges' mismatch first: the height range (a pass over every vertex) only where it is not exactly 0.
    double mismatch = 0.0;
    for (int j = 0; j < hf.ny; ++j) mismatch = std::max(mismatch, std::abs(static_cast<double>(hf.z(0, j)) - hf.z(hf.nx - 1, j)));
    for (int i = 0; i < hf.nx; ++i) mismatch = std::max(mismatch, std::abs(static_cast<double>(hf.z(i, 0)) - hf.z(i, hf.ny - 1)));
    if (mismatch == 0.0) return true;
    double lo = 0.0, hi = 0.0;
    height_range(hf, lo, hi);
    return mismatch <= std::max(relative_tolerance * (hi - lo), 1e-9);
}

}  // namespace caustics
