#pragma once
// The measurement receiver's chart (docs/design.md section 3): bin (i, j) of a width x height map covers
// s in [i, i+1) / width, t in [j, j+1) / height of the receiver's parameter square.
//   plane:       p(s, t) = center + (s - 1/2) u + (t - 1/2) v
//   heightfield: p(s, t) = (x0 + s X, y0 + t Y, h(x, y)) over the field's rectangle
// Each bin stores mean E_c over its true surface area, so bin_area() is the surface area, not the
// parameter-space area.
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/frame.hpp>

namespace caustics {

class ReceiverChart {
public:
    ReceiverChart(const FrameGeometry& frame, int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }
    glm::dvec3 point(double s, double t) const;
    glm::dvec3 normal(double s, double t) const;
    // The chart coordinates of a world point on (or projected onto) the receiver; false if outside.
    bool coords(const glm::dvec3& p, double& s, double& t) const;
    // Bin index of a world point, or -1 if it is outside the receiver.
    int bin_of(const glm::dvec3& p) const;
    double bin_area(int i, int j) const { return areas_[static_cast<std::size_t>(j) * width_ + i]; }
    double total_area() const { return total_area_; }
    bool is_plane() const { return plane_; }

private:
    const ObjectInstance* receiver_ = nullptr;
    int width_ = 0, height_ = 0;
    bool plane_ = true;
    glm::dvec3 center_{0.0}, u_{1, 0, 0}, v_{0, 1, 0}, n_{0, 0, 1};
    std::vector<double> areas_;
    double total_area_ = 0.0;
};

}  // namespace caustics
