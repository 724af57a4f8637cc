// Box-filtered surface caustics of the beams that end on one diffuse plane (surface_coverage.hpp).
#include "surface_coverage.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <caustics/blocks/raster/raster.hpp>

namespace caustics::adaptive_beams {
namespace {

struct PlaneBatch {
    std::vector<glm::vec2> positions;
    std::vector<glm::uvec3> triangles;
    std::vector<float> values;
};

}  // namespace

bool edge_end_on_plane(const Beam& b, int i, const glm::dvec3& p, const glm::dvec3& n, PlaneEnd how, glm::dvec3& end,
                       double& length) {
    const double stretch = glm::length(b.dp[i]);
    if (how == PlaneEnd::Own) {
        end = b.point(i, b.ye[i]);
        length = (b.ye[i] - b.ys[i]) * stretch;
        return true;
    }
    const glm::dvec3 start = b.point(i, b.ys[i]), d = b.dp[i] / stretch;
    const double dn = glm::dot(d, n);
    const double t = dn != 0.0 ? glm::dot(p - start, n) / dn : -1.0;
    end = start + t * d;
    length = t;
    return t > 0.0;
}

bool ends_on_plane(const Beam& b, const glm::dvec3& p, const glm::dvec3& n) {
    for (int i = 0; i < 3; ++i) {
        const glm::dvec3 end = b.point(i, b.ye[i]);
        const double scale = 1.0 + glm::length(end - p) + (b.ye[i] - b.ys[i]) * glm::length(b.dp[i]);
        if (!(std::abs(glm::dot(end - p, n)) <= 1e-5 * scale)) return false;
    }
    return true;
}

std::vector<std::uint8_t> deposit_plane_beams(const BeamSet& set, const Scene& scene, const CameraGBuffer& g,
                                              const CameraModel& cam, Image& surface, std::int64_t& deposited) {
    const std::size_t nb = set.beams.size();
    std::vector<std::uint8_t> taken(nb, 0);
    std::map<int, PlaneBatch> batches;
    // Projected points further out than this many image sizes are left to the point pass (a section that
    // reaches behind the camera's near region): the raster would clip them, but their screen area is no
    // measure of the section's.
    const double far_out = 16.0 * std::max(g.width, g.height);
    const int receiver = scene.receiver.object_index;
    const bool plane_receiver = receiver >= 0 && scene.objects[static_cast<std::size_t>(receiver)].shape == ShapeType::Plane;
    for (std::size_t n = 0; n < nb; ++n) {
        int object = set.end_object[n];
        const std::uint8_t e = set.ends[n];
        // Edges that end on the plane receiver or on nothing are carried on to its plane where some leave the
        // receiver's edge, or where all end on it but the energy cut ended them short (their light there is
        // faint, and drawing it costs less than testing every pixel of their wide sections point by point): as
        // the receiver map carries them (accumulate_receiver).
        // Beams none of whose edges ends on it too (a corner of the water: accumulate_receiver).
        const bool on_receiver = plane_receiver && (e & kReceiverOrNothing);
        if (object < 0 && on_receiver) object = receiver;
        if (object < 0 || !((e & kEndsOnDiffuse) || on_receiver)) continue;
        const Object& plane = scene.objects[static_cast<std::size_t>(object)];
        if (plane.shape != ShapeType::Plane) continue;
        const Beam& b = set.beams[n];
        const glm::dvec3 np = glm::normalize(glm::cross(plane.u, plane.v));
        // A beam's own ends must lie on the plane (an edge the energy cut ended short of another plane does not
        // end on it, whatever its path's end); carried-on ends lie on it by construction.
        const bool own_on_plane = ends_on_plane(b, plane.center, np);
        const PlaneEnd how =
            on_receiver && object == receiver && !((e & kAllOnReceiver) && own_on_plane) ? PlaneEnd::Extend : PlaneEnd::Own;
        if (how == PlaneEnd::Own && !own_on_plane) continue;
        const double sigma_t = medium_at(scene, b.medium).extinction();
        glm::dvec3 ends[3];
        double px[3], py[3], arriving = 0.0;
        bool ok = true;
        for (int i = 0; i < 3 && ok; ++i) {
            double length = 0.0;
            ok = edge_end_on_plane(b, i, plane.center, np, how, ends[i], length) && cam.project(ends[i], px[i], py[i]) &&
                 std::abs(px[i]) < far_out && std::abs(py[i]) < far_out;
            arriving += b.w[i] * std::exp(-sigma_t * length) / 3.0;
        }
        if (!ok) continue;
        taken[n] = 1;
        const glm::dvec3 centroid = (ends[0] + ends[1] + ends[2]) / 3.0;
        const glm::dvec3 to_camera = cam.position - centroid;
        const glm::dvec3 light = b.dp[0] + b.dp[1] + b.dp[2];
        if (glm::dot(light, np) * glm::dot(to_camera, np) >= 0.0) continue;   // lights the side the camera does not see
        // Screen pixels per unit area of the plane: the projected triangle's area over the section's, or
        // where the section is (nearly) a point, the pinhole's Jacobian cos(theta) / (t^2 Omega_pixel).
        const double a_surface = 0.5 * glm::length(glm::cross(ends[1] - ends[0], ends[2] - ends[0]));
        const double a_screen = 0.5 * std::abs((px[1] - px[0]) * (py[2] - py[0]) - (px[2] - px[0]) * (py[1] - py[0]));
        const double t = glm::length(to_camera);
        const int cx = std::clamp(static_cast<int>((px[0] + px[1] + px[2]) / 3.0), 0, g.width - 1);
        const int cy = std::clamp(static_cast<int>((py[0] + py[1] + py[2]) / 3.0), 0, g.height - 1);
        const double omega = cam.pixel_solid_angle(cx, cy);
        const double scale = a_surface > 1e-9 * t * t * omega
                                 ? a_screen / a_surface
                                 : std::abs(glm::dot(to_camera, np)) / (t * t * t * omega);
        PlaneBatch& batch = batches[object];
        const auto base = static_cast<unsigned>(batch.positions.size());
        for (int i = 0; i < 3; ++i) batch.positions.emplace_back(static_cast<float>(px[i]), static_cast<float>(py[i]));
        batch.triangles.emplace_back(base, base + 1, base + 2);
        batch.values.push_back(static_cast<float>(b.flux * arriving * scale));
        ++deposited;
    }
    TriangleRaster raster;
    RasterOptions options;
    options.coverage = RasterCoverage::Area;
    for (const auto& [object, batch] : batches) {
        Image plane_light(g.width, g.height);
        raster.draw({batch.positions, batch.triangles, batch.values, {}}, options, plane_light);
        for (int y = 0; y < g.height; ++y)
            for (int x = 0; x < g.width; ++x) {
                const std::size_t i = g.index(x, y);
                if (g.covered[i] && g.object[i] == object) surface.at(x, y) += plane_light.at(x, y);
            }
    }
    return taken;
}

}  // namespace caustics::adaptive_beams
