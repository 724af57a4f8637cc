#pragma once
// A height field sampled on a regular grid of vertices: z(i, j) = height[j * nx + i] at world
// (origin.x + i * spacing.x, origin.y + j * spacing.y). Gradients are stored per vertex (analytic where
// the generator has them) so that refraction can use smooth interpolated normals.
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/scene/scene.hpp>

namespace caustics {

struct HeightField {
    glm::dvec2 origin{0.0};   // world x, y of vertex (0, 0)
    glm::dvec2 spacing{1.0};  // cell size
    int nx = 0;               // vertices along x
    int ny = 0;               // vertices along y
    bool periodic = false;    // the surface tiles (noise generator): vertex nx-1 equals vertex 0 again
    std::vector<float> height;            // world z, nx * ny
    std::vector<glm::vec2> gradient;      // (dz/dx, dz/dy), nx * ny
    // Analytic generators (flat, sine, gaussian) also give the exact gradient at any (x, y), so the
    // reference refracts with the true normal rather than an interpolated one. Empty otherwise.
    std::function<glm::dvec2(double x, double y)> exact_gradient;

    float z(int i, int j) const { return height[static_cast<std::size_t>(j) * nx + i]; }
    glm::vec2 grad(int i, int j) const { return gradient[static_cast<std::size_t>(j) * nx + i]; }
    glm::dvec2 extent() const { return {spacing.x * (nx - 1), spacing.y * (ny - 1)}; }
    bool contains(double x, double y) const;
    // Bilinear interpolation of height and gradient at world (x, y), clamped to the domain (periodic
    // fields wrap); sample_gradient uses exact_gradient when present.
    double sample_height(double x, double y) const;
    glm::dvec2 sample_gradient(double x, double y) const;
    // Upward unit normal (-gx, -gy, 1) / |.| from the interpolated gradient.
    glm::dvec3 sample_normal(double x, double y) const;
    // sample_normal at the n points (x[k], y[k]), into (out_x[k], out_y[k], out_z[k]): the same bits, four
    // points at a time with AVX2 where the CPU has it (heightfield_normals.cpp). For batches of hits.
    void sample_normals(const double* x, const double* y, std::size_t n, double* out_x, double* out_y,
                        double* out_z) const;
    // Two triangles per cell, counter-clockwise seen from above, with per-vertex upward normals.
    TriangleMesh triangulate() const;
};

// The lowest and highest vertex heights (1e300 and -1e300 for an empty field).
void height_range(const HeightField& hf, double& hmin, double& hmax);

// Whether the surface tiles its rectangle: flagged periodic (noise generator), or its opposite edges equal
// to within relative_tolerance of its height range (a sine with a whole number of periods over the
// rectangle, a flat surface): vertex nx-1 then stands for vertex 0 again.
bool tiles_its_rectangle(const HeightField& hf, double relative_tolerance = 1e-3);

// A height map image (the `image` generator): its size from the header, and its first channel decoded as
// floats (8/16-bit images read as [0, 1]). Both throw std::runtime_error with a one-line message naming
// the file (a truncated or corrupt file included) and keep the image libraries' own text (libpng's
// "libpng error: ...") off stderr.
struct HeightMapInfo {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::size_t bytes_per_channel = 0;
    // What decoding holds at its peak: the file's native pixels (the PNG reader keeps the whole image)
    // and the first channel as floats.
    double decode_bytes() const {
        return static_cast<double>(width) * height * (4.0 + static_cast<double>(channels) * bytes_per_channel);
    }
};
HeightMapInfo read_height_map_info(const std::string& path);
std::vector<float> read_height_map(const std::string& path, HeightMapInfo& info);

// Evaluates the height-field generator of `desc` at time t (seconds) for animation frame `frame`
// (the `waves` simulation steps deterministically to that frame). Same result on every machine.
HeightField generate_heightfield(const HeightFieldDesc& desc, double time, int frame, double fps);

}  // namespace caustics
