#pragma once
// The camera view's surface caustics as each pixel's box average (docs/design.md section 3: a pixel holds
// the mean irradiance over the part of the surface it sees), for the beams that end with all three edges on
// one diffuse plane. Such a beam brings its flux Phi (times the transmittance of its edges) onto its end
// section, the triangle of its edges' hits; its irradiance there is Phi / A_surface, and a pixel's mean
// irradiance is that times the fraction of the pixel the projected triangle covers. The projected
// triangles are split among the pixels by exact area coverage (blocks/raster), so a beam focused to less
// than a pixel still brings its whole flux, where the paper's point-in-beam at pixel centres (Sec. 5.3)
// hits or misses it and then low-pass filters the result (Sec. 7); the receiver map does the same on its
// chart (accumulate.cpp). A pixel takes a triangle's light only where it sees the same plane (a plane
// cannot hide part of itself, so the pixel sees the triangle's point). A beam that leaves the edge of a plane
// receiver (each edge ends on it or on nothing) is taken too, its edges extended to the receiver's plane as
// the receiver map extends them: the part of its section beyond the receiver's edge falls on pixels that do
// not see the receiver. So is a beam whose edges all end on the plane receiver but which the energy cut ended
// short of it, its edges carried on to the plane as the receiver map carries them. Beams whose edges end on
// different surfaces, on curved ones, or behind the camera are left to the point-in-beam pass.
#include <cstdint>
#include <vector>

#include <caustics/frame/camera.hpp>
#include <caustics/util/image.hpp>

#include "light_grid.hpp"

namespace caustics::adaptive_beams {

// How an edge's end is put on a plane: its own end (the edge ends there), or its line carried on to the plane
// (it left the plane's edge, or the energy cut ended it short of the plane).
enum class PlaneEnd { Own, Extend };

// Whether all three edges of `b` end on the plane through p with unit normal n (within the single-precision
// hits' tolerance, relative to the coordinates and the edge's length): false where the energy cut ended one
// short of it, whatever its path's end.
bool ends_on_plane(const Beam& b, const glm::dvec3& p, const glm::dvec3& n);

// Where edge i of `b` meets the plane through p with unit normal n, and the length of its path there (the
// light's path, whose transmittance the flux keeps). False where an extended edge meets the plane only behind
// its start (or never).
bool edge_end_on_plane(const Beam& b, int i, const glm::dvec3& p, const glm::dvec3& n, PlaneEnd how, glm::dvec3& end,
                       double& length);

// Adds the box-filtered irradiance of the beams it takes to `surface` (covered pixels of their plane), adds
// the number it deposited to `deposited`, and returns, per beam, 1 where it took the beam (the point-in-beam
// pass must then skip it). A beam whose light reaches the side of the plane the camera does not see is
// taken and deposits nothing, as point-in-beam would give it nothing there.
std::vector<std::uint8_t> deposit_plane_beams(const BeamSet& set, const Scene& scene, const CameraGBuffer& g,
                                              const CameraModel& cam, Image& surface, std::int64_t& deposited);

}  // namespace caustics::adaptive_beams
