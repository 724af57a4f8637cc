#pragma once
// A regular 3-D scalar grid over an axis-aligned box, the storage of the 3-D caustic textures of
// Mercier's eikonal and wave methods. Cells are cubes of edge
// `spacing`; value (i, j, k) sits at the cell centre origin + (i + 1/2, j + 1/2, k + 1/2) * spacing.
// Also: the 7-point Laplacian (Mercier Eq. 4) and an indexed min-heap for fast marching.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <string>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>
#include <caustics/scene/heightfield/heightfield.hpp>
#include <caustics/api/method.hpp>

namespace caustics {

struct VolumeShape {
    glm::dvec3 origin{0.0};  // world position of the box's lowest corner
    double spacing = 1.0;    // cell edge (the same along x, y and z)
    int nx = 0, ny = 0, nz = 0;

    std::size_t size() const { return static_cast<std::size_t>(nx) * ny * nz; }
    std::size_t index(int i, int j, int k) const {
        return (static_cast<std::size_t>(k) * ny + j) * nx + i;
    }
    glm::dvec3 center(int i, int j, int k) const {
        return origin + spacing * glm::dvec3(i + 0.5, j + 0.5, k + 0.5);
    }
    glm::dvec3 extent() const { return spacing * glm::dvec3(nx, ny, nz); }
    // Inside the box [origin, origin + extent] (closed).
    bool contains(const glm::dvec3& p) const;
    // The box grown by `lateral` cells on its x and y faces and `vertical` on its z faces (new origin,
    // same spacing).
    VolumeShape padded(int lateral, int vertical) const;
};

template <class T>
struct VolumeGrid {
    VolumeShape shape;
    std::vector<T> data;

    VolumeGrid() = default;
    explicit VolumeGrid(const VolumeShape& s, T fill = T(0)) : shape(s), data(s.size(), fill) {}
    T& at(int i, int j, int k) { return data[shape.index(i, j, k)]; }
    T at(int i, int j, int k) const { return data[shape.index(i, j, k)]; }
    std::size_t bytes() const { return data.size() * sizeof(T); }
};

using VolumeF = VolumeGrid<float>;
using VolumeD = VolumeGrid<double>;

// Trilinear interpolation between cell centres at world point p. Points inside the box but within
// half a cell of its faces clamp to the outermost centres. Returns false (and 0) outside the box.
bool trilinear(const VolumeF& grid, const glm::dvec3& p, float& value);

// 7-point Laplacian (Mercier 2013, Eq. 4) divided by spacing^2, so the result is in 1/length for a
// distance field. On a face of the box the missing neighbour is extrapolated quadratically
// (phi_-1 = 3 phi_0 - 3 phi_1 + phi_2), i.e. the second difference normal to the face is taken one
// cell inside, so a boundary adds no artificial curvature. Parallel over z slices.
void laplacian(const VolumeD& phi, VolumeF& out);

// Binary min-heap of cell indices keyed by double, with decrease-key through a position table
// (Sethian 1996: the trial set of fast marching).
class CellHeap {
public:
    explicit CellHeap(std::size_t cells) : pos_(cells, kAbsent) {}
    bool empty() const { return heap_.empty(); }
    std::size_t size() const { return heap_.size(); }
    bool contains(std::size_t cell) const { return pos_[cell] != kAbsent; }
    // Inserts `cell` or lowers its key (a higher key is ignored).
    void push_or_decrease(std::size_t cell, double key);
    // Removes and returns the cell with the smallest key.
    std::size_t pop(double& key);

private:
    static constexpr std::uint32_t kAbsent = 0xffffffffu;
    struct Entry {
        double key;
        std::uint32_t cell;
    };
    void sift_up(std::size_t at);
    void sift_down(std::size_t at);
    std::vector<Entry> heap_;
    std::vector<std::uint32_t> pos_;
};

// ---- Height-field water interfaces and the volume under them (shared by the volume methods) ----

// The water interface: the first height-field object with a dielectric material, or nullptr.
const ObjectInstance* find_water_interface(const FrameGeometry& frame);
// Empty if the scene has what a height-field volume-caustics method needs (a height-field dielectric
// interface lit by a directional light), otherwise the reason it is not supported.
std::string volume_caustics_unsupported(const Scene& scene);

// Height of the interface extended linearly past its rectangle with the edge gradient (Mercier 2013,
// Sec. 3.2: "extend linearly the water-air interface at the boundary"); `gradient` receives dz/dx,y.
double extended_height(const HeightField& hf, double x, double y, glm::dvec2* gradient = nullptr);
// Height of grid vertex (a, b), extended linearly for vertices outside [0, nx) x [0, ny).
double extended_vertex_height(const HeightField& hf, int a, int b);
// Signed distance from p to the triangulated interface (two triangles per height-field cell, as
// HeightField::triangulate), extended linearly past its rectangle: > 0 below (in the water), < 0 above.
// Exact over a window of triangles around the foot point of p (found by a projection iteration).
double signed_distance_to_interface(const HeightField& hf, const glm::dvec3& p);

// The caustic volume of a frame: horizontally the diffuse receivers' footprint clipped to the
// interface's rectangle (the whole rectangle when nothing is below it), grown by `margin_fraction` of
// its extent on each side; vertically from one cell below the lowest diffuse receiver under the
// interface to one cell above the interface's highest point. `grid` cells along the longer
// horizontal side; z at the same spacing.
VolumeShape caustic_volume(const FrameGeometry& frame, const ObjectInstance& water, int grid,
                           double margin_fraction = 0.0);
// The caustic volume for light refracted along `refracted` (unit, downward; oblique light): horizontally
// the diffuse receivers' footprint where light can reach it through the water's rectangle (the
// rectangle moved along the rays down to the receivers' depth, so receivers past the water's edge
// downstream are inside), together with the part of the rectangle the light they receive enters
// through (the footprint moved back up the rays, widened by `spread` times the depth for the rays'
// spread about `refracted`), so fronts reach every receiver from the interface rather than from a
// side face. Spacing: `grid` cells along the longer side of the receivers' footprint (grown by
// `margin_fraction` on each side); vertically as caustic_volume.
VolumeShape caustic_volume_along(const FrameGeometry& frame, const ObjectInstance& water, int grid,
                                 const glm::dvec3& refracted, double spread, double margin_fraction = 0.0);

}  // namespace caustics
