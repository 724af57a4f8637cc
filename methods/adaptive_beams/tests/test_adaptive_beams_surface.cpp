// The camera view's surface caustics by pixel coverage (surface_coverage.hpp) for a beam that leaves the edge
// of the plane receiver: one edge ends on the floor, two pass beyond its edge and end on nothing. The beam is
// drawn by coverage with its edges carried on to the floor's plane, and the floor's pixels receive exactly the
// flux of the part of its section that lies on the floor, which a closed form gives; so is a beam the energy
// cut ended short of the floor. And the receiver map under flat water, whose beams are carried on to the
// floor's plane the same way, against the flat interface's irradiance up to the floor's edges and corners.
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/frame/baseline.hpp>
#include <caustics/frame/camera.hpp>
#include <caustics/frame/frame.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/scene/scene.hpp>

#include "../beam.hpp"
#include "../light_grid.hpp"
#include "../surface_coverage.hpp"
#include "adaptive_beams_render.hpp"
#include "conformance_cases.hpp"

using namespace caustics;
using namespace caustics::adaptive_beams;
using caustics::adaptive_beams_test::render;
using caustics::adaptive_beams_test::Rendered;

namespace {

// The flux the camera's floor pixels hold: each pixel's mean irradiance times the floor area it sees (its
// solid angle times the squared distance over the cosine at the floor).
double flux_on_floor(const Image& surface, const CameraGBuffer& g, const CameraModel& cam, int floor) {
    double flux = 0.0;
    for (int y = 0; y < g.height; ++y)
        for (int x = 0; x < g.width; ++x) {
            const std::size_t i = g.index(x, y);
            if (!g.covered[i] || g.object[i] != floor) continue;
            const glm::dvec3 p(g.position[i]);
            const glm::dvec3 to = p - cam.position;
            const double t = glm::length(to);
            const double cosine = std::abs(to.z) / t;   // the floor's normal is z
            flux += surface.at(x, y) * cam.pixel_solid_angle(x, y) * t * t / cosine;
        }
    return flux;
}

}  // namespace

TEST(AdaptiveBeamsSurface, BeamLeavingThePlaneReceiverIsDrawnByCoverage) {
    // A 2 x 2 m floor at z = 0 seen from above and aside, no medium.
    Scene scene = test_support::shipped_scene("sphere");
    scene.objects.erase(scene.objects.begin());   // the ball: only the floor is left
    scene.objects[0].u = {2, 0, 0};   // the floor spans [-1, 1] x [-1, 1]
    scene.objects[0].v = {0, 2, 0};
    scene.receiver.object_index = 0;
    scene.camera.width = 320;
    scene.camera.height = 240;
    scene.camera.position = {0.3, -1.6, 2.4};
    scene.camera.look_at = {0.6, 0.0, 0.0};
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const RayTracer tracer(frame);
    const CameraGBuffer g = build_camera_gbuffer(tracer, scene.camera);
    const CameraModel cam(scene.camera);

    // Light falling straight down through the triangle (0.5, 0), (1.5, 0), (1, 0.5): the floor's edge x = 1
    // halves it. Edge 0 ends on the floor; edges 1 and 2 (x >= 1) pass its edge and end 1 m below it.
    const double xs[3] = {0.5, 1.5, 1.0}, ys[3] = {0.0, 0.0, 0.5};
    std::array<EdgeRay, 3> edges;
    for (int i = 0; i < 3; ++i) {
        edges[i].start = {xs[i], ys[i], 1.0};
        edges[i].dir = {0.0, 0.0, -1.0};
        edges[i].length = i == 0 ? 1.0 : 2.0;
    }
    BeamSet set;
    set.beams.resize(1);
    constexpr double kFlux = 2.0;
    ASSERT_EQ(make_beam(edges, kFlux, -1, 1e-3, set.beams[0]), BeamStatus::Ok);
    set.ends = {static_cast<std::uint8_t>(kEndsOnDiffuse | kEndsOnReceiver | kReceiverOrNothing)};
    set.end_object = {-1};

    Image surface(g.width, g.height);
    std::int64_t deposited = 0;
    const std::vector<std::uint8_t> taken = deposit_plane_beams(set, scene, g, cam, surface, deposited);
    ASSERT_EQ(taken.size(), 1u);
    EXPECT_EQ(taken[0], 1);
    EXPECT_EQ(deposited, 1);
    // Half of the section lies on the floor: half of the flux. The pixels' box averages are exact; what is
    // left is the pinhole's Jacobian taken at each pixel's centre (the footprint is some 40 x 20 pixels).
    const double on_floor = flux_on_floor(surface, g, cam, 0);
    std::printf("flux on the floor's pixels %.5f of the %.5f its half of the section brings\n", on_floor, 0.5 * kFlux);
    EXPECT_NEAR(on_floor, 0.5 * kFlux, 0.005 * kFlux);
    // No light where the pixels see anything but the floor.
    for (std::size_t i = 0; i < surface.pixels.size(); ++i) {
        if (!g.covered[i] || g.object[i] != 0) {
            EXPECT_EQ(surface.pixels[i], 0.0f) << i;
        }
    }

    // A beam whose three edges' paths end on the floor but which the energy cut ended 0.4 m above it (so its
    // ends are off the plane): carried on to the floor, with all of its flux (the section (-0.5, 0), (0, 0),
    // (-0.25, 0.5) lies on the floor).
    {
        const double xa[3] = {-0.5, 0.0, -0.25}, ya[3] = {0.0, 0.0, 0.5};
        std::array<EdgeRay, 3> cut;
        for (int i = 0; i < 3; ++i) {
            cut[i].start = {xa[i], ya[i], 1.0};
            cut[i].dir = {0.0, 0.0, -1.0};
            cut[i].length = 0.6;
        }
        BeamSet short_of;
        short_of.beams.resize(1);
        ASSERT_EQ(make_beam(cut, kFlux, -1, 1e-3, short_of.beams[0]), BeamStatus::Ok);
        short_of.ends = {static_cast<std::uint8_t>(kEndsOnDiffuse | kEndsOnReceiver | kAllOnReceiver | kReceiverOrNothing)};
        short_of.end_object = {0};
        Image cut_surface(g.width, g.height);
        EXPECT_EQ(deposit_plane_beams(short_of, scene, g, cam, cut_surface, deposited)[0], 1);
        EXPECT_NEAR(flux_on_floor(cut_surface, g, cam, 0), kFlux, 0.005 * kFlux);
    }

    // Edge 0 ending elsewhere than on the floor or nothing (on another diffuse object): not taken.
    set.ends = {static_cast<std::uint8_t>(kEndsOnDiffuse | kEndsOnReceiver)};
    Image other(g.width, g.height);
    EXPECT_EQ(deposit_plane_beams(set, scene, g, cam, other, deposited)[0], 0);
}

// Oblique light through flat water with Fresnel: the receiver matches the flat interface's irradiance.
TEST(AdaptiveBeamsSurface, FlatObliqueMatchesTheFlatInterface) {
    const Scene scene = test_support::shipped_scene("flat_oblique");
    const Rendered r = render(scene, {}, 64, 2, false);
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, 64, 64);
    const Image truth = flat_interface_baseline(frame, chart);
    int compared = 0;
    for (int y = 2; y < 62; ++y)
        for (int x = 2; x < 62; ++x)
            if (truth.at(x, y) > 0.0f && truth.at(x - 2, y) > 0.0f && truth.at(x + 2, y) > 0.0f &&
                truth.at(x, y - 2) > 0.0f && truth.at(x, y + 2) > 0.0f) {
                EXPECT_NEAR(r.out.receiver.at(x, y), truth.at(x, y), 1e-3 * truth.at(x, y)) << x << ", " << y;
                ++compared;
            }
    EXPECT_GT(compared, 1000);
}

// The same up to the receiver's edges and corners, under straight and oblique light: where the water is as
// wide as the floor, the light through its last lattice row and column lands a hair outside the floor, and
// the beams spanning two corners (all three edges just outside) were dropped from the receiver map and the
// camera: a dark triangle of 2.5 x 2.5 bins at 256 x 256, all of the 0.0058 that `sine_ior1` scored and
// 0.0089 of a weak drawn `gaussian`'s 0.0089 (accumulate_receiver).
TEST(AdaptiveBeamsSurface, FlatWaterLightsTheFloorToItsCorners) {
    for (const char* name : {"sine_ior1", "flat_oblique"}) {
        const Scene scene = test_support::shipped_scene(name);
        const Rendered r = render(scene, {}, 64, 2, false);
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        const ReceiverChart chart(frame, 64, 64);
        const Image truth = flat_interface_baseline(frame, chart);
        int compared = 0, corners = 0;
        double flux = 0.0, flux_truth = 0.0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                flux += r.out.receiver.at(x, y) * chart.bin_area(x, y);
                flux_truth += truth.at(x, y) * chart.bin_area(x, y);
                bool lit = true;   // the bin and its neighbours inside the receiver fully lit (no shadow edge)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx)
                        if (x + dx >= 0 && x + dx < 64 && y + dy >= 0 && y + dy < 64) lit = lit && truth.at(x + dx, y + dy) > 0.0f;
                if (!lit) continue;
                EXPECT_NEAR(r.out.receiver.at(x, y), truth.at(x, y), 1e-3 * truth.at(x, y)) << name << " " << x << ", " << y;
                ++compared;
                corners += (x == 0 || x == 63) && (y == 0 || y == 63);
            }
        EXPECT_GT(compared, 3000) << name;
        EXPECT_EQ(corners, 4) << name;   // every corner compared, the two that were dark among them
        // The beams carried on to the plane bring no light from beyond the receiver: its flux is the truth's.
        EXPECT_NEAR(flux / flux_truth, 1.0, 1e-4) << name;
    }
}
