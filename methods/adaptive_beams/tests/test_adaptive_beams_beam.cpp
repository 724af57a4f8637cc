// One beam against its own closed forms: the in-scattered radiance a camera ray collects crossing a beam
// of known cross-section (a parallel prism with extinction and Henyey-Greenstein scattering; a cone that
// converges to a point, whose cross-section shrinks as (1 - y/h)^2), the irradiance of the point-in-beam
// test, the focus (flip) and the hulls.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "../beam.hpp"

using namespace caustics;
using namespace caustics::adaptive_beams;

namespace {

std::array<EdgeRay, 3> prism_edges(double length) {
    std::array<EdgeRay, 3> e;
    const glm::dvec3 v[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    for (int i = 0; i < 3; ++i) e[i] = {v[i], {0, 0, 1}, length, 1.0};
    return e;
}

// Rays from the equilateral triangle of circumradius 1/2 around the z axis (z = 0) to the focus F = (0, 0, h):
// symmetric, so the beam's axis is z and its sections are horizontal, A(z) = A0 (1 - z/h)^2.
constexpr double kR = 0.5;
const double kA0 = 0.75 * std::sqrt(3.0) * kR * kR;

std::array<EdgeRay, 3> cone_edges(double h, double length_z) {
    std::array<EdgeRay, 3> e;
    const glm::dvec3 f{0, 0, h};
    for (int i = 0; i < 3; ++i) {
        const double a = std::numbers::pi / 2 + i * 2.0 * std::numbers::pi / 3.0;
        const glm::dvec3 v{kR * std::cos(a), kR * std::sin(a), 0.0};
        const glm::dvec3 d = glm::normalize(f - v);
        e[i] = {v, d, length_z / d.z, 1.0};
    }
    return e;
}

}  // namespace

// A parallel beam of flux Phi over a base of area 1/2 has E = 2 Phi perpendicular to it. A camera ray
// crossing it at right angles at height z0 = 4, from x = 5 to 5.8 inside (its chord at y = 0.2), collects
//   L = sigma_s p(0) E exp(-sigma_t z0) (exp(-sigma_t 5) - exp(-sigma_t 5.8)) / sigma_t.
TEST(AdaptiveBeamsBeam, ParallelBeamRadianceMatchesClosedForm) {
    Beam b;
    ASSERT_EQ(make_beam(prism_edges(10.0), 2.0, -1, 1e-3, b), BeamStatus::Ok);
    EXPECT_NEAR(std::abs(b.area(0.0)), 0.5, 1e-12);
    EXPECT_NEAR(b.a1, 0.0, 1e-12);
    EXPECT_FALSE(b.flipped);
    const MediumCoefficients m{0.2, 0.3, 0.4};
    BeamCounters c;
    const glm::dvec3 o{-5, 0.2, 4}, w{1, 0, 0};
    const double st = m.extinction();
    const double expected = m.scattering * henyey_greenstein(0.0, m.anisotropy) * 4.0 * std::exp(-st * 4.0) *
                            (std::exp(-st * 5.0) - std::exp(-st * 5.8)) / st;
    EXPECT_NEAR(volume_radiance(b, m, o, w, 1e30, 4, c), expected, 1e-9 * expected);
    // One midpoint sample (the paper's) is within the second-order error of the exponential's curvature.
    EXPECT_NEAR(volume_radiance(b, m, o, w, 1e30, 1, c), expected, 0.01 * expected);
    // The camera ray stops at its hit: ending inside the beam at s = 5.4 keeps half the chord.
    const double half = m.scattering * henyey_greenstein(0.0, m.anisotropy) * 4.0 * std::exp(-st * 4.0) *
                        (std::exp(-st * 5.0) - std::exp(-st * 5.4)) / st;
    EXPECT_NEAR(volume_radiance(b, m, o, w, 5.4, 4, c), half, 1e-9 * half);
    // A ray beside the beam, or past its end (z = 11 > 10), collects nothing.
    EXPECT_EQ(volume_radiance(b, m, {-5, 1.2, 4}, w, 1e30, 4, c), 0.0);
    EXPECT_EQ(volume_radiance(b, m, {-5, 0.2, 11}, w, 1e30, 4, c), 0.0);
    // A ray looking back along the beam sees forward scattering: p(1) over the path from z = 9 to 1.
    const glm::dvec3 o2{0.2, 0.2, 9.0}, w2{0, 0, -1};
    // Light path z, camera path 9 - z: exp(-st z) exp(-st (9 - z)) = exp(-9 st) on the 8 m inside.
    const double back = m.scattering * henyey_greenstein(1.0, m.anisotropy) * 4.0 * std::exp(-9.0 * st) * 8.0;
    EXPECT_NEAR(volume_radiance(b, m, o2, w2, 8.0, 2, c), back, 1e-9 * back);
    EXPECT_EQ(c.clamped, 0);
}

// A cone converging to F at height h: A(z) = A0 (1 - z/h)^2. At z = h/2 a horizontal camera ray at
// distance rho from F's vertical line collects, with isotropic scattering thin enough that extinction is
// below 1e-5 on the 5 m of the paths,
//   L = sigma_s / (4 pi) Phi / A(h/2) * (2 / h) * integral |F - X(s)| ds
// (X on the chord: the local ray through X runs towards F, and |d'| = |F - v| / h = 2 |F - X| / h).
TEST(AdaptiveBeamsBeam, ConvergingConeRadianceMatchesClosedForm) {
    const double h = 2.0, phi = 3.0;
    Beam b;
    ASSERT_EQ(make_beam(cone_edges(h, 1.5), phi, -1, 1e-3, b), BeamStatus::Ok);
    EXPECT_NEAR(b.n.z, 1.0, 1e-12);
    const double a_half = kA0 / 4.0;
    EXPECT_NEAR(std::abs(b.area(1.0)), a_half, 1e-12);
    // The section at z = 1 has corners 0.25 (cos, sin) of 90, 210, 330 deg; the line y = yc crosses it
    // between x = -+ 0.25 cos 30 (0.25 - yc) / 0.375.
    const double yc = 0.05, half = 0.25 * std::cos(std::numbers::pi / 6) * (0.25 - yc) / 0.375;
    const MediumCoefficients m{0.0, 1e-6, 0.0};
    const glm::dvec3 o{-3.0, yc, 1.0}, w{1, 0, 0};
    const double rho = std::hypot(yc, 1.0 - h);
    auto prim = [&](double u) { return 0.5 * (u * std::hypot(rho, u) + rho * rho * std::asinh(u / rho)); };
    const double integral = prim(half) - prim(-half);
    const double expected = m.scattering / (4.0 * std::numbers::pi) * phi / a_half * (2.0 / h) * integral;
    BeamCounters c;
    EXPECT_NEAR(volume_radiance(b, m, o, w, 1e30, 4, c), expected, 1e-5 * expected);
    // Point-in-beam: on the plane z = 1 facing the light, E = Phi / A(1).
    EXPECT_NEAR(surface_irradiance(b, 0.0, {0.0, 0.0, 1.0}, {0, 0, -1}, true, 0.0, c), phi / a_half, 1e-9);
    EXPECT_EQ(surface_irradiance(b, 0.0, {0.3, 0.0, 1.0}, {0, 0, -1}, true, 0.0, c), 0.0);
    // Lit from behind: nothing on a one-sided surface.
    EXPECT_EQ(surface_irradiance(b, 0.0, {0.0, 0.0, 1.0}, {0, 0, 1}, true, 0.0, c), 0.0);
    EXPECT_EQ(c.clamped, 0);
}

// Past the focus the section flips (A changes sign): counted, clamped near the focus, never infinite,
// and the flux density after it is Phi / |A| again.
TEST(AdaptiveBeamsBeam, BeamThroughAFocusIsFlippedClampedAndFinite) {
    const double h = 2.0, phi = 1.0;
    Beam b;
    ASSERT_EQ(make_beam(cone_edges(h, 3.0), phi, -1, 1e-3, b), BeamStatus::Ok);
    EXPECT_TRUE(b.flipped);
    BeamCounters c;
    const double at_focus = surface_irradiance(b, 0.0, {0.0, 0.0, h + 1e-7}, {0, 0, -1}, true, 0.0, c);
    EXPECT_TRUE(std::isfinite(at_focus));
    EXPECT_GT(c.clamped, 0);
    EXPECT_LE(at_focus, phi / b.a_min * 1.5);
    EXPECT_NEAR(b.area(h), 0.0, 1e-12);
    // At z = 3 the section is the base scaled by 1/2 again (mirrored): E = Phi / (A0 / 4).
    EXPECT_NEAR(surface_irradiance(b, 0.0, {0.0, 0.0, 3.0}, {0, 0, -1}, true, 0.0, c), phi / (kA0 / 4.0), 1e-6);
    // A camera ray through the focus stays finite.
    const double l = volume_radiance(b, {0.0, 1.0, 0.0}, {-3.0, 0.0, h}, {1, 0, 0}, 1e30, 2, c);
    EXPECT_TRUE(std::isfinite(l));
    EXPECT_GE(l, 0.0);
}

// The tight corners hold every point of the beam; the prism (Ernst) holds the tight corners; a strongly
// focused beam's prism is larger (the fill the tight hull saves, Fig. 6).
TEST(AdaptiveBeamsBeam, HullsHoldTheBeam) {
    Beam b;
    ASSERT_EQ(make_beam(cone_edges(2.0, 1.8), 1.0, -1, 1e-3, b), BeamStatus::Ok);
    std::array<glm::dvec3, 6> tight, prism;
    ASSERT_TRUE(hull_corners(b, HullType::Tight, tight));
    ASSERT_TRUE(hull_corners(b, HullType::Prism, prism));
    // The prism's side planes: every tight corner lies inside its triangular slab section at its height.
    auto extent = [](const std::array<glm::dvec3, 6>& c) {
        double lo = 1e300, hi = -1e300;
        for (int i = 3; i < 6; ++i) lo = std::min(lo, c[i].x), hi = std::max(hi, c[i].x);
        return hi - lo;
    };
    EXPECT_GE(extent(prism) + 1e-12, extent(tight));
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(prism[i].z, tight[i].z, 1e-12);
}

TEST(AdaptiveBeamsBeam, DegenerateBeamsAreRefused) {
    Beam b;
    auto e = prism_edges(1.0);
    e[2].start = {2.0, 0.0, 0.0};   // collinear starts: zero area
    EXPECT_EQ(make_beam(e, 1.0, -1, 1e-3, b), BeamStatus::Degenerate);
    e = prism_edges(1.0);
    e[0].dir = {0, 0, -1};   // edges going opposite ways
    e[1].dir = {1, 0, 0};
    EXPECT_EQ(make_beam(e, 1.0, -1, 1e-3, b), BeamStatus::Degenerate);
}
