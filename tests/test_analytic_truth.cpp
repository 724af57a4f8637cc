// The analytic truth of the refracting sine (harness/analytic_truth): the Monte Carlo reference agrees
// with the truth per receiver column within its own standard error (normal and oblique light, above and
// below the first focus, absorption, Fresnel, crest shadowing) and a deliberately wrong truth is rejected
// by the same statistic; the mesh the reference traces is measured against the exact sine; the truth
// converges in its sampling, conserves flux exactly, is flat for ior 1, follows the sine along either
// axis and in time, says why where it does not apply, and is fast. The baseline: test_flat_baseline.cpp.
//
// Tolerances: Monte Carlo comparisons are Student-t tests against the reference's standard error (from
// its replicas: replicas - 1 degrees of freedom), Sidak-corrected over the columns compared, family-wise
// level kFamilyAlpha (sine_truth_support.hpp). Deterministic comparisons use round-off-sized tolerances
// stated where they are used.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include "sine_truth_support.hpp"

using namespace caustics;
using namespace caustics::test_support;

// ---------------------------------------------------------------- against the reference

struct ReferenceCase {
    const char* name;
    SineSetup setup;
    std::uint64_t photons;
};
// ctest lists the case by its name, not by a byte dump of the struct.
inline void PrintTo(const ReferenceCase& c, std::ostream* os) { *os << c.name; }

class TruthAgainstReference : public ::testing::TestWithParam<ReferenceCase> {};

TEST_P(TruthAgainstReference, ColumnsWithinStandardErrorAndWrongIorRejected) {
    const ReferenceCase& c = GetParam();
    const TracedScene setup(make_sine_scene(c.setup));
    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    EXPECT_EQ(truth.kind, "analytic:sine");
    const std::vector<double> expected = column_means(truth.receiver);
    const auto [mn, mx] = std::minmax_element(expected.begin(), expected.end());
    EXPECT_GT(*mx / *mn, 1.5) << "the truth must have caustic structure for the test to mean something";

    const ReferenceResult ref = run_reference(setup, c.photons);
    ASSERT_GE(ref.replicas, 2);
    const Columns cols = reference_columns(ref);
    const ZTest t = z_test(cols, expected);
    EXPECT_LE(t.worst, t.threshold) << c.name << ": column " << t.column << " reference " << cols.mean[t.column]
                                    << " +- " << cols.se[t.column] << ", truth " << expected[t.column];
    // The same statistic rejects a truth computed with a slightly wrong index.
    SineSetup wrong = c.setup;
    wrong.ior = 1.30;
    const AnalyticTruth bad = truth_of(wrong);
    ASSERT_TRUE(bad.available) << bad.reason;
    const ZTest tb = z_test(cols, column_means(bad.receiver));
    EXPECT_GT(tb.worst, tb.threshold) << c.name << ": a truth with ior 1.30 was not rejected";
    std::printf("%s: max |t| %.2f (column %d of %d, threshold %.2f, %g dof), ior 1.30 truth: max |t| %.1f\n", c.name,
                t.worst, t.column, t.compared, t.threshold, cols.dof, tb.worst);
}

// Paraxial first focus n / ((n - 1) A k^2) = 0.64 m: floors at 0.4 m (before it) and 1.2 m (past it,
// folded). At 80 degrees the crests shadow each other (A k = 0.25 > cot 80 = 0.18).
INSTANTIATE_TEST_SUITE_P(
    Sine, TruthAgainstReference,
    ::testing::Values(ReferenceCase{"normal_shallow", sine_case(0.0, -0.4, 0.0, false), 4'000'000},
                      ReferenceCase{"normal_deep_absorbing", sine_case(0.0, -1.2, 0.5, false), 4'000'000},
                      ReferenceCase{"oblique30_shallow_absorbing_fresnel", sine_case(30.0, -0.4, 0.5, true), 4'000'000},
                      ReferenceCase{"oblique30_deep", sine_case(30.0, -1.2, 0.0, false), 4'000'000},
                      ReferenceCase{"grazing80_shadowed", sine_case(80.0, -0.4, 0.0, false), 6'000'000}),
    [](const ::testing::TestParamInfo<ReferenceCase>& info) { return std::string(info.param.name); });

// ---------------------------------------------------------------- the mesh the reference traces

// The reference intersects the height field's triangle mesh (float vertices, chord sag up to
// A k^2 cell^2 / 8) and refracts with the exact normal at the hit's (x, y). Deterministic measurement of
// that difference: a dense family of light rays traced through the mesh (entry point and refraction as
// the reference does them) against the same rays entering the exact sine, binned alike.
namespace {
double mesh_difference(const SineSetup& c) {
    const TracedScene setup(make_sine_scene(c));
    const SinePlane p = plane_of(c);
    const glm::dvec3 l = glm::normalize(setup.scene.lights[0].direction), perp(-l.z, 0.0, l.x);
    // Offsets xi across the beam covering the water; each ray carries E0 dxi per unit width.
    const double xi_lo = glm::dot(glm::dvec3(c.water_lo, 0, -0.02), perp);
    const double xi_hi = glm::dot(glm::dvec3(c.water_hi, 0, 0.02), perp);
    constexpr int kRays = 600'000;
    const double lo = -0.5 * c.floor_size, hi = 0.5 * c.floor_size;
    StripHistogram mesh(lo, hi, c.bins_x), exact(lo, hi, c.bins_x);
    double prev_mesh = 0.0, prev_exact = 0.0, prev_w = 0.0;
    bool prev_ok = false;
    for (int r = 0; r <= kRays; ++r) {
        const double xi = xi_lo + (xi_hi - xi_lo) * r / kRays;
        const glm::dvec3 o = xi * perp + glm::dvec3(0.0, 0.1234, 0.0) - 5.0 * l;
        const Hit hit = setup.tracer->intersect(o, l);
        bool ok = hit.valid && hit.object == 0;
        double land_mesh = 0.0, land_exact = 0.0, w = 0.0;
        if (ok) {
            // The reference: refraction at the mesh point with the exact normal there.
            const SinePlane::Strip at_mesh = p.trace(hit.position.x);
            land_mesh = hit.position.x + at_mesh.dir_s * (hit.position.z - c.floor_z) / -at_mesh.dir_z;
            // The exact entry point of the same ray: Newton on z_ray(t) - h(x(t)) from the mesh hit.
            double t = hit.t;
            for (int it = 0; it < 30; ++it) {
                const double x = o.x + t * l.x, f = o.z + t * l.z - p.height(x);
                t -= f / (l.z - p.slope(x) * l.x);
            }
            const double x = o.x + t * l.x;
            const SinePlane::Strip st = p.trace(x);
            ok = std::fabs(t - hit.t) < 1e-3 && std::fabs(o.z + t * l.z - p.height(x)) < 1e-12 && st.front &&
                 at_mesh.front;   // rays that graze a crest on one surface and not the other are left out
            land_exact = st.landing;
            w = st.density / (l.x * p.slope(x) - l.z);   // per unit xi: E0 T exp(-Ka L)
        }
        if (ok && prev_ok) {
            const double flux = 0.5 * (w + prev_w) * (xi_hi - xi_lo) / kRays;
            mesh.add(prev_mesh, land_mesh, flux);
            exact.add(prev_exact, land_exact, flux);
        }
        prev_ok = ok, prev_mesh = land_mesh, prev_exact = land_exact, prev_w = w;
    }
    double worst = 0.0;
    for (int i = 0; i < c.bins_x; ++i) {
        const double a = mesh.flux()[static_cast<std::size_t>(i)], b = exact.flux()[static_cast<std::size_t>(i)];
        worst = std::max(worst, std::fabs(a / b - 1.0));
    }
    return worst;
}
}  // namespace

TEST(AnalyticTruth, MeshDiscretisation) {
    // At the scenes' 2 mm cells the mesh moves columns by ~1e-5 at normal incidence and a few 1e-4 at 30
    // degrees, far below the reference noise the tests reach; at 80 degrees a hit's height error is
    // stretched by cot(10 deg) along the surface, about 1 % (the test above uses 0.25 mm cells).
    const struct { double tilt, bound; } cases[] = {{0.0, 1e-4}, {30.0, 1e-3}, {80.0, 2e-2}};
    for (const auto& k : cases)
        for (const double floor_z : {-0.4, -1.2}) {
            SineSetup c = sine_case(k.tilt, floor_z, 0.0, false);
            c.cell = 0.002;
            const double d = mesh_difference(c);
            std::printf("2 mm mesh vs exact sine, tilt %g, floor %g: max column difference %.2e\n", k.tilt, floor_z, d);
            EXPECT_LT(d, k.bound);
            RecordProperty("tilt" + std::to_string(int(k.tilt)) + "_floor" + std::to_string(floor_z), std::to_string(d));
        }
}

// ---------------------------------------------------------------- the truth's own exactness

TEST(AnalyticTruth, SamplingConverges) {
    // Halving the source strips changes no bin by more than 1e-5 relative, past the focus (folds) and at
    // grazing light (shadow edges), on 256 bins as the scenes use.
    for (const SineSetup& c :
         {sine_case(0.0, -1.2, 0.5, false), sine_case(30.0, -1.2, 0.0, true), sine_case(80.0, -0.4, 0.0, false)}) {
        const SinePlane p = plane_of(c);
        const std::size_t n = sine_profile_segments(p, 1.0 / 256);
        std::vector<double> a, b;
        std::string why;
        ASSERT_TRUE(sine_profile(p, -0.5, 0.5, 256, n, a, why)) << why;
        ASSERT_TRUE(sine_profile(p, -0.5, 0.5, 256, 2 * n, b, why)) << why;
        double worst = 0.0;
        for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::fabs(a[i] / b[i] - 1.0));
        std::printf("tilt %g floor %g: %zu strips, max change from doubling %.2e\n", c.tilt_deg, c.floor_z, n, worst);
        EXPECT_LT(worst, 1e-5);
    }
}

TEST(AnalyticTruth, ConservesFlux) {
    // A floor 4 m long catches all the light that enters the 1.2 m x 1 m (overlap) water from above. With
    // xi = s cos t + z sin t the coordinate across the beam, the lit points are exactly the running records
    // of xi along the light's travel, so the entering flux is E0 W (max xi - xi(upstream edge)), shadowed
    // or not (rays below the edge's xi would pass under the open edge). Without shadowing that is
    // E0 W (cos t L + sin t (h(s_hi) - h(s_lo))), the integral of E0 (cos t + h' sin t).
    for (const double tilt : {0.0, 30.0, 80.0}) {
        SineSetup c;
        c.tilt_deg = tilt;
        c.floor_size = 4.0;
        c.bins_x = 1024;
        c.bins_y = 4;
        c.water_lo = -1.13;   // not at a trough: the truth needs none
        c.water_hi = 0.07;
        c.floor_z = -0.4;
        const TracedScene setup(make_sine_scene(c));
        const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
        ASSERT_TRUE(truth.available) << truth.reason;
        const double total = receiver_flux(truth.receiver, *setup.chart);
        const SinePlane p = plane_of(c);
        const double ct = std::cos(tilt * kPi / 180.0), st = std::sin(tilt * kPi / 180.0);
        const double xi_lo = c.water_lo * ct + p.height(c.water_lo) * st;
        double xi_hi = -1e300;
        for (int i = 0; i <= 4'000'000; ++i) {   // the maximum of a smooth function: sampling error ~1e-14 m
            const double s = c.water_lo + (c.water_hi - c.water_lo) * i / 4e6;
            xi_hi = std::max(xi_hi, s * ct + p.height(s) * st);
        }
        const double expected = 1.0 * (xi_hi - xi_lo);   // E0 = 1, width 1 m (the floor's, inside the water's 1.2 m)
        std::printf("tilt %g: flux %.9f, closed form %.9f\n", tilt, total, expected);
        EXPECT_NEAR(total, expected, 1e-6 * expected);   // float bins
        if (tilt < 45.0) {
            EXPECT_NEAR(expected, ct * 1.2 + st * (p.height(c.water_hi) - p.height(c.water_lo)), 1e-9);
        }
    }
    // Flat water (A = 0) with Fresnel and absorption: E0 cos t (lit area) T exp(-Ka depth / cos theta_t).
    SineSetup c;
    c.tilt_deg = 30.0, c.amplitude = 0.0, c.absorption = 0.5, c.fresnel = true;
    c.floor_size = 4.0, c.bins_x = 512, c.bins_y = 2;
    const TracedScene setup(make_sine_scene(c));
    const AnalyticTruth truth = analytic_truth(*setup.frame, *setup.chart);
    ASSERT_TRUE(truth.available) << truth.reason;
    const double total = receiver_flux(truth.receiver, *setup.chart);
    const double cos_i = std::cos(kPi / 6), sin_t = 0.5 / 1.33, cos_t = std::sqrt(1.0 - sin_t * sin_t);   // Snell
    const double expected = cos_i * 1.2 * 1.0 * fresnel_transmittance(cos_i, cos_t, 1.0, 1.33) * std::exp(-0.5 * 0.4 / cos_t);
    EXPECT_NEAR(total, expected, 1e-6 * expected);
}
TEST(AnalyticTruth, IndexOneIsFlat) {
    // n = 1 bends nothing: E0 (cos t + h' sin t) per unit length lands on dX = (1 + h' tan t) dx, so the
    // truth is E0 cos t on every lit bin (the upstream bins that only light passing beside the water's
    // edge could reach are dark).
    SineSetup c = sine_case(30.0, -0.4, 0.0, false);
    c.ior = 1.0;
    c.bins_x = 256;
    const AnalyticTruth truth = truth_of(c);
    ASSERT_TRUE(truth.available) << truth.reason;
    const double e = std::cos(30.0 * kPi / 180.0);
    int lit = 0;
    for (int j = 0; j < c.bins_y; ++j)
        for (int i = 0; i < c.bins_x; ++i) {
            const double v = truth.receiver.at(i, j);
            EXPECT_LE(v, e * (1.0 + 1e-6));
            if (v > 0.5 * e) {
                ++lit;
                EXPECT_NEAR(v, e, 1e-6 * e) << i << ", " << j;
            }
        }
    EXPECT_EQ(lit, c.bins_x * c.bins_y);   // this water feeds the whole floor
}

TEST(AnalyticTruth, FollowsTheSineAlongEitherAxisAndInTime) {
    // The same sine along +y (the receiver's v axis: the map transposes); along -x with the light
    // mirrored, and along +x shifted by half a period with the light travelling towards -x (both mirror
    // the map; the latter marches and shadows against the axis); and a travelling sine at frame 5 equals a
    // static one whose phase has moved by k speed t, as the generator does it.
    auto truth_of_scene = [](Scene s, int frame = 0) {
        const TracedScene setup(std::move(s), frame);
        const AnalyticTruth t = analytic_truth(*setup.frame, *setup.chart);
        EXPECT_TRUE(t.available) << t.reason;
        return t.receiver;
    };
    for (const double tilt : {30.0, 80.0}) {
        SineSetup c = sine_case(tilt, -0.4, 0.0, false);
        c.bins_x = 64, c.bins_y = 8;
        const Image a = truth_of(c).receiver;
        Scene along_y = make_sine_scene(c);
        std::swap(along_y.lights[0].direction.x, along_y.lights[0].direction.y);
        HeightFieldDesc& hy = along_y.objects[0].heightfield;
        hy.direction = {0.0, 1.0};
        std::swap(hy.center.x, hy.center.y), std::swap(hy.size.x, hy.size.y), std::swap(hy.resolution.x, hy.resolution.y);
        std::swap(along_y.receiver.width, along_y.receiver.height);
        Scene minus_x = make_sine_scene(c), light_back = make_sine_scene(c);
        for (Scene* m : {&minus_x, &light_back}) {
            m->lights[0].direction.x *= -1.0;
            m->objects[0].heightfield.center.x *= -1.0;
        }
        minus_x.objects[0].heightfield.direction = {-1.0, 0.0};   // h(x) = A sin(-k x)
        light_back.objects[0].heightfield.phase = kPi;            // h(x) = A sin(k x + pi), the same
        Scene moving = make_sine_scene(c), moved = make_sine_scene(c);
        moving.animation = {10, 25.0};
        moving.objects[0].heightfield.speed = 0.1;
        moved.objects[0].heightfield.phase = 2.0 * kPi / c.wavelength * 0.1 * 5 / 25.0;
        const Image b = truth_of_scene(std::move(along_y)), m = truth_of_scene(std::move(minus_x));
        const Image r = truth_of_scene(std::move(light_back));
        const Image t5 = truth_of_scene(std::move(moving), 5), p5 = truth_of_scene(std::move(moved));
        ASSERT_EQ(b.width, c.bins_y);
        double worst = 0.0, peak = *std::max_element(a.pixels.begin(), a.pixels.end());
        for (int j = 0; j < c.bins_y; ++j)
            for (int i = 0; i < c.bins_x; ++i) {
                const double e = a.at(i, j), mirrored = a.at(c.bins_x - 1 - i, j);
                worst = std::max({worst, std::fabs(b.at(j, i) - e), std::fabs(m.at(i, j) - mirrored),
                                  std::fabs(r.at(i, j) - mirrored), std::fabs(double(t5.at(i, j)) - p5.at(i, j))});
            }
        EXPECT_LT(worst, 1e-5 * peak) << tilt;   // the same strips in another order: round-off only
        EXPECT_GT(std::fabs(t5.at(10, 0) - a.at(10, 0)), 1e-3 * peak);   // the sine did move
    }
}

// ---------------------------------------------------------------- where the closed form does not apply

TEST(AnalyticTruth, SaysWhyItDoesNotApply) {
    auto reason = [](const SineSetup& c, auto change) {
        Scene s = make_sine_scene(c);
        change(s);
        const TracedScene setup(std::move(s));
        const AnalyticTruth t = analytic_truth(*setup.frame, *setup.chart);
        EXPECT_FALSE(t.available);
        EXPECT_TRUE(t.receiver.empty());
        return t.reason;
    };
    auto says = [](const std::string& why, const char* word) { return why.find(word) != std::string::npos; };
    const SineSetup c;
    EXPECT_TRUE(says(reason(c, [](Scene& s) { s.lights[0].type = LightType::Point; }), "not directional"));
    EXPECT_TRUE(says(reason(c, [](Scene& s) { s.objects[0].heightfield.direction = {1.0, 1.0}; }), "direction"));
    EXPECT_TRUE(says(reason(c, [](Scene& s) { s.lights[0].direction = glm::normalize(glm::dvec3(0.3, 0.2, -1)); }),
                     "vertical plane"));
    EXPECT_TRUE(says(reason(c, [](Scene& s) { s.objects[0].material.dispersion = 0.02; }), "dispersive"));
    EXPECT_TRUE(says(reason(c, [](Scene& s) { s.objects[1].u = {0.8, 0.6, 0}, s.objects[1].v = {-0.6, 0.8, 0}; }),
                     "parallel"));
    EXPECT_TRUE(says(reason(c, [](Scene& s) { s.objects[0].heightfield.generator = HeightGenerator::Noise; }),
                     "neither a sine nor a Gaussian"));
    // Steep waves under grazing light: refracted rays run almost along the surface and meet it again.
    SineSetup steep = c;
    steep.tilt_deg = 85.0, steep.amplitude = 0.06;
    EXPECT_TRUE(says(reason(steep, [](Scene&) {}), "refracted ray meets the surface again"));
    // With Fresnel at 80 degrees, light reflected off a lee slope skims the water into the next crest.
    SineSetup glancing = c;
    glancing.tilt_deg = 80.0, glancing.fresnel = true;
    EXPECT_TRUE(says(reason(glancing, [](Scene&) {}), "reflected ray meets the surface again"));
}

// ---------------------------------------------------------------- cost

TEST(AnalyticTruth, SceneFilesAndTiming) {
    // The built-in sine scenes all have their truth; a 256 x 256 receiver takes well under 100 ms.
    for (const char* name : {"sine.json", "sine_oblique.json", "sine_deep.json", "sine_ior1.json",
                             "sine_grazing.json"}) {
        const Scene scene = load_scene(scene_path(name));
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        const ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
        const auto start = std::chrono::steady_clock::now();
        const AnalyticTruth truth = analytic_truth(frame, chart);
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        ASSERT_TRUE(truth.available) << name << ": " << truth.reason;
        EXPECT_EQ(truth.receiver.width, 256);
        std::printf("%s: analytic truth %dx%d in %.1f ms\n", name, truth.receiver.width, truth.receiver.height, ms);
        RecordProperty(std::string(name) + "_ms", std::to_string(ms));
    }
}
