#pragma once
// Scan conversion of beam hulls into the camera (Sec. 4.3, 5.1): the convex polygon a hull projects to,
// clipped by the near plane, and the pixels of each row it holds, either at the pixels' centres (one ray
// per pixel) or wherever it overlaps the pixel's square (a pixel whose box is sampled by several rays).
#include <array>
#include <vector>

#include <glm/glm.hpp>

#include <caustics/frame/camera.hpp>

#include "beam.hpp"

namespace caustics::adaptive_beams {

// Rows of the camera image handled by one task: beams are walked per band, in their order, so that the
// sums are the same for any thread count.
constexpr int kBandRows = 8;

// A convex polygon in pixel coordinates and the rows it may touch.
struct Footprint {
    std::vector<glm::dvec2> poly;
    int y_lo = 0, y_hi = -1;       // rows whose centres it may hold
    int box_lo = 0, box_hi = -1;   // rows whose squares it may overlap
};

// A beam's pixels: the union of the footprints of up to three pieces of its slab. A beam that passes a
// focus (A(y) = 0, Sec. 4.3) is cut there when the hull is tight: the convex hull of all six corners fills
// the waist between its two cones with pixels whose rays miss the beam (on `sphere_fog` a third of all
// fragments); each piece [ya, yb] still holds its part of the beam, as P_i(y) is linear in y and so every
// cross-section in it lies in the hull of P_i(ya), P_i(yb).
struct Coverage {
    std::array<Footprint, 3> part;
    int parts = 0;
    int y_lo = 0, y_hi = -1;       // union of the parts' rows
    int box_lo = 0, box_hi = -1;
};

// The coverage of the whole beam with the given hull corners (hull_corners).
Coverage coverage(const Beam& b, HullType hull, const std::array<glm::dvec3, 6>& corners, const CameraModel& cam,
                  int height, bool& clipped);

// The coverage of the beam's part y in [ya, yb] (the tight hull of its sections there).
Coverage slab_coverage(const Beam& b, double ya, double yb, const CameraModel& cam, int height, bool& clipped);

// The pixel columns of row y whose centres the coverage holds (box = false) or whose squares it overlaps
// (box = true), as disjoint sorted spans [x0, x1]; returns their number.
int row_spans(const Coverage& cov, int y, int width, bool box, int (&spans)[3][2]);

}  // namespace caustics::adaptive_beams
