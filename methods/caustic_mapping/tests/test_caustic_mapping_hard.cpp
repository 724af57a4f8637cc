// caustic_mapping on the hard cases of issue 13, against the exact sine truth (harness/analytic_truth):
// tilted light (the receivers' window must cover the specular objects), a caustic line focused across
// (elliptical splats), ior = 1 (flat, no bad derivatives, nothing lost), Newton at convergence, past the
// first focus (folds), and the accuracy claim's bound.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <tbb/global_control.h>
#include <map>
#include <string>
#include <utility>

#include "../caustic_mapping.hpp"
#include "../estimator.hpp"
#include <caustics/reference/analytic_truth.hpp>
#include "method_support.hpp"
#include "sine_truth_support.hpp"

using namespace caustics;
using namespace caustics::caustic_mapping;
using test_support::SineSetup;

namespace {

struct Result {
    CausticOutput out;
    Image truth;
    double nrmse = 0.0, baseline = 0.0, flux_ratio = 0.0, std_over_mean = 0.0;
    AccuracyClaim claim;
};

// Renders a sine case at 128 x 32 bins and compares it with the exact truth: nrmse = rms error / mean
// truth (the flat baseline's: the truth's own rms deviation from its mean).
Result run(const SineSetup& c, const std::map<std::string, std::string>& overrides) {
    Result r;
    const Scene scene = test_support::make_sine_scene(c);
    r.out = test_support::render_method("caustic_mapping", scene, overrides, c.bins_x, c.bins_y);
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, c.bins_x, c.bins_y);
    const AnalyticTruth t = analytic_truth(frame, chart);
    EXPECT_TRUE(t.available) << t.reason;
    r.truth = t.receiver;
    double se = 0, mean = 0, var = 0, s1 = 0, s2 = 0;
    int lit = 0;
    const double n = static_cast<double>(r.truth.pixels.size());
    for (float v : r.truth.pixels) mean += v / n;
    for (std::size_t i = 0; i < r.truth.pixels.size(); ++i) {
        const double m = r.out.receiver.pixels[i], tr = r.truth.pixels[i];
        se += (m - tr) * (m - tr) / n;
        var += (tr - mean) * (tr - mean) / n;
        if (tr > 0.0) s1 += m, s2 += m * m, ++lit;
    }
    r.nrmse = std::sqrt(se) / mean;
    r.baseline = std::sqrt(var) / mean;
    r.flux_ratio = test_support::receiver_flux(r.out.receiver, chart) / test_support::receiver_flux(r.truth, chart);
    const double m1 = s1 / lit;
    r.std_over_mean = std::sqrt(std::max(0.0, s2 / lit - m1 * m1)) / m1;
    const MethodInfo& info = require_method("caustic_mapping");
    r.claim = claim_for(frame, settings_from(ParamSet::resolve(info.name, info.params, overrides)));
    return r;
}

SineSetup sine(double tilt, double floor_z, double absorption = 0.0, double ior = 1.33) {
    SineSetup c;
    c.tilt_deg = tilt;
    c.floor_z = floor_z;
    c.absorption = absorption;
    c.ior = ior;
    c = test_support::with_water_feeding_floor(c);
    c.bins_x = 128;
    c.bins_y = 32;
    return c;
}

double column_mean(const Image& img, int i) {
    double s = 0.0;
    for (int j = 0; j < img.height; ++j) s += img.at(i, j) / img.height;
    return s;
}

}  // namespace

// Under light tilted 30 deg the estimator's first lookup (the light ray through the water vertex) lies
// downstream of the receiver's edge for the light that lands near that edge. A window fitted to the
// receiver alone (extend=32: the old rim) returns the null value there: the last columns went dark and
// 6 % of the flux was lost. The window now covers the water too, extrapolated to its edges.
TEST(CausticMappingHard, TiltedLightKeepsTheFluxAtTheDownstreamEdge) {
    const SineSetup c = sine(30.0, -0.4);
    const Result r = run(c, {});
    EXPECT_NEAR(r.flux_ratio, 1.0, 0.01);
    for (int i = c.bins_x - 4; i < c.bins_x; ++i)
        EXPECT_NEAR(column_mean(r.out.receiver, i), column_mean(r.truth, i), 0.35 * column_mean(r.truth, i) + 0.05) << i;
    EXPECT_EQ(r.out.health.get("lost_samples"), 0);
    EXPECT_EQ(r.out.health.get("null_value"), 0);
    // The paper's behaviour (no extrapolated rim: extend = 0) loses the light at the edge, and counts it.
    const Result paper = run(c, {{"extend", "0"}});
    EXPECT_LT(paper.flux_ratio, 0.97);
    EXPECT_GT(paper.out.health.get("null_value"), 0);
}

// The caustic lines of sine_oblique are nearly focused (focus 0.44 m, floor 0.4 m): the landing lattice
// is compressed across the lines and not along them. An isotropic footprint sized by the larger spacing
// (splat=adaptive) spreads each line over a grid spacing; the elliptical one follows the lattice.
TEST(CausticMappingHard, EllipticalSplatsKeepFocusedLinesSharp) {
    const SineSetup c = sine(30.0, -0.4);
    const Result elliptic = run(c, {});
    const Result isotropic = run(c, {{"splat", "adaptive"}});
    std::printf("sine_oblique grid 128: nrmse elliptic %.4f, adaptive %.4f, baseline %.4f\n", elliptic.nrmse,
                isotropic.nrmse, elliptic.baseline);
    EXPECT_LT(elliptic.nrmse, 0.03);
    EXPECT_GT(isotropic.nrmse, 2.0 * elliptic.nrmse);
    EXPECT_NEAR(elliptic.flux_ratio, 1.0, 0.01);
}

// Refining the grid refines the caustic map with it (map = 0: 6 x grid, at least 768): with the map fixed
// at 768 the map's texels limit the focused lines of sine_oblique and grid 256 measured worse than grid
// 128 on 256 bins (nrmse 0.060 against 0.044).
TEST(CausticMappingHard, ErrorFallsWithTheGridOnFineBins) {
    SineSetup c = sine(30.0, -0.4);
    c.bins_x = 256;
    c.bins_y = 16;
    const Result r128 = run(c, {});
    const Result r256 = run(c, {{"grid", "256"}});
    std::printf("sine_oblique on 256 bins: nrmse grid 128 %.4f, grid 256 %.4f\n", r128.nrmse, r256.nrmse);
    EXPECT_LT(r256.nrmse, 0.5 * r128.nrmse);
}

// ior = 1: the interface bends nothing and the truth is flat. Before: 1087 bad derivatives (Newton's
// forward difference across the kink of |P - q| at convergence) and 3776 lost samples (the window).
TEST(CausticMappingHard, IndexOneIsFlatWithNoBadDerivativesOrLostSamples) {
    SineSetup c = sine(30.0, -0.4, 0.0, 1.0);
    c.bins_y = 128;   // the conformance suite's square bins: the lattice's ripple shows in both directions
    const Result r = run(c, {});
    std::printf("ior 1: std/mean %.5f flux ratio %.5f\n", r.std_over_mean, r.flux_ratio);
    EXPECT_LT(r.std_over_mean, 0.01);
    EXPECT_NEAR(r.flux_ratio, 1.0, 0.01);
    EXPECT_EQ(r.out.health.get("bad_derivative"), 0);
    EXPECT_EQ(r.out.health.get("lost_samples"), 0);
    EXPECT_EQ(r.out.health.get("nonfinite"), 0);
    EXPECT_TRUE(r.claim.inside);   // judged by flatness and flux: the flat baseline's error is 0 here
}

// The splat lattice's ripple at the conformance suite's 256 x 256 bins, at the grids the claim admits up to
// the fold settings, and at those (grid 512, map 6144, whose footprints stay half a grid spacing wide): a
// Gaussian of half a grid spacing kept the lattice's first harmonic at std/mean 1.3 % (grid 64), 1.2 %
// (96) and 0.99 % (128), at the 1 % a flat truth allows, and drawn cases of ior 1.01 failed their claim at
// nrmse 0.0100-0.0106 (elliptic_splats.hpp, elliptic_sigma). Held here to half the flat tolerance.
TEST(CausticMappingHard, LatticeRippleWellWithinTheFlatToleranceOnFineBins) {
    SineSetup c = sine(30.0, -0.4, 0.0, 1.0);
    c.bins_x = c.bins_y = 256;
    const std::map<std::string, std::string> settings[] = {
        {{"grid", "64"}}, {{"grid", "96"}}, {{"grid", "128"}}, {{"grid", "256"}}, {{"grid", "512"}, {"map", "6144"}}};
    for (const auto& p : settings) {
        const Result r = run(c, p);
        std::printf("ior 1 on 256 x 256 bins, grid %s: std/mean %.5f\n", p.at("grid").c_str(), r.std_over_mean);
        EXPECT_LT(r.std_over_mean, 0.5 * kFlatTolerance) << "grid " << p.at("grid");
        EXPECT_NEAR(r.flux_ratio, 1.0, 0.01) << "grid " << p.at("grid");
    }
}

// Newton on a curved surface seen from above: once an estimate is within eps of the surface, the
// forward difference straddles it. On the paper's |P - q| that slope has the wrong sign whenever the
// estimate is in front (a bad derivative on a converged ray); on the signed distance it is the true slope.
TEST(CausticMappingHard, NewtonAtConvergenceHasNoBadDerivative) {
    struct Surface {   // z = -0.4 + 0.02 sin(5 x) seen by a light looking down: fetch is exact
        bool fetch(const glm::dvec3& p, glm::dvec3& q) const {
            q = {p.x, p.y, -0.4 + 0.02 * std::sin(5.0 * p.x)};
            return true;
        }
        double depth(const glm::dvec3& p) const { return -p.z; }
    } tex;
    EstimatorSettings s;
    s.kind = EstimatorKind::Newton;
    s.iterations = 8;
    s.tolerance = 0.0;   // keep iterating at the root
    s.eps = 0.01;
    int bad = 0;
    for (int k = 0; k < 64; ++k) {
        const glm::dvec3 v(0.01 * k, 0.0, 0.0), r = glm::normalize(glm::dvec3(0.3 - 0.01 * k, 0.1, -1.0));
        const EstimateResult e = estimate_intersection(tex, v, r, s, 0.0);
        ASSERT_TRUE(e.hit);
        EXPECT_LT(glm::length(e.point - (v + e.d * r)), 1e-9) << k;
        bad += e.bad_derivative;
    }
    EXPECT_EQ(bad, 0);
}

// Past the first focus (floor 1.2 m, focus 0.64 m) the Snell map folds: every preimage's splat adds.
// Flux is kept and the error falls with the grid (the map follows it); drawn at the grid asked for
// (refine_past_focus off), the claim calls the case outside, by the depth over the first focus (the folds'
// singularities leak across a map texel).
TEST(CausticMappingHard, PastTheFocusFoldsAreSummed) {
    const SineSetup c = sine(0.0, -1.2, 0.5);
    const Result r128 = run(c, {{"refine_past_focus", "false"}});
    const Result r256 = run(c, {{"grid", "256"}, {"refine_past_focus", "false"}});
    EXPECT_EQ(r128.out.health.get("refined_past_focus"), 0);
    std::printf("sine_deep: nrmse grid 128 %.4f, grid 256 %.4f, baseline %.4f\n", r128.nrmse, r256.nrmse, r128.baseline);
    EXPECT_NEAR(r128.flux_ratio, 1.0, 0.01);
    EXPECT_FALSE(r128.claim.inside);
    EXPECT_NE(r128.claim.reason.find("first focus"), std::string::npos) << r128.claim.reason;
    EXPECT_LT(r256.nrmse, r128.nrmse);
}

// The regime past the first focus: grid 512 with a caustic map of 6144 samples the folds finely enough to
// be held to 0.10 (measured from 1.1 to 3 x the focus on three seeds of 200 drawn cases, to 6 x on the
// default seed); the defaults, another map, splats, lookups or estimator, light beyond 40 deg, the cusp just
// past the focus or a floor past 6 x keep the case outside, each naming its bound. Before the focus the
// same settings keep the 0.05 claim.
TEST(CausticMappingHard, PastTheFocusClaimedAtTheFoldSettings) {
    const std::map<std::string, std::string> fold = {{"grid", "512"}, {"map", "6144"}};
    const SineSetup deep = sine(20.0, -1.2, 0.2);
    const Result r = run(deep, fold);
    std::printf("past the focus at 20 deg, grid 512, map 6144: nrmse %.4f, baseline %.4f\n", r.nrmse, r.baseline);
    ASSERT_TRUE(r.claim.inside) << r.claim.reason;
    EXPECT_DOUBLE_EQ(r.claim.max_error, kFoldClaimError);
    EXPECT_LT(r.nrmse, r.claim.bound(r.baseline));
    // The claim of one setting on one case (a frame points at its scene: the scene lives while it is taken),
    // and a refusal that names its bound.
    auto claim_at = [](const SineSetup& c, const Settings& s) {
        const Scene scene = test_support::make_sine_scene(c);
        return claim_for(build_frame_geometry(scene, 0), s);
    };
    auto expect_refused = [&](const SineSetup& c, const Settings& s, const char* why) {
        const AccuracyClaim a = claim_at(c, s);
        EXPECT_FALSE(a.inside) << why;
        EXPECT_NE(a.reason.find(why), std::string::npos) << a.reason;
    };
    Settings as_asked;   // the defaults, drawn at grid 128 and map 768
    as_asked.refine_past_focus = false;
    expect_refused(deep, as_asked, "grid >= 512");
    Settings fine;
    fine.grid = kFoldMinGrid;
    fine.map = 3072;
    fine.map_auto = false;
    expect_refused(deep, fine, "map of 12 x grid");
    fine.map = 6144;
    EXPECT_TRUE(claim_at(deep, fine).inside);
    // The gates: the regime was measured with the elliptic splats, bilinear lookups and Newton's estimator.
    Settings gaussian = fine, nearest = fine, approx = fine;
    gaussian.elliptic = false;
    nearest.bilinear = false;
    approx.estimator.kind = EstimatorKind::Approx;
    for (const Settings& gate : {gaussian, nearest, approx}) expect_refused(deep, gate, "elliptic splats");
    // Before the focus (0.25 m: 0.4 x) the fold settings are held to the first regime's 0.05.
    const AccuracyClaim sh = claim_at(sine(0.0, -0.25, 0.2), fine);
    ASSERT_TRUE(sh.inside) << sh.reason;
    EXPECT_DOUBLE_EQ(sh.max_error, kClaimError);
    expect_refused(sine(42.0, -1.2, 0.2), fine, "42.0 deg");
    // sine's focus is 0.64 m down: a floor at 4.2 m is 6.6 x the way.
    expect_refused(sine(0.0, -4.2, 0.2), fine, "beyond the 6.0 x");
    // Just past the focus (0.67 m: 1.05 x) the cusp lies near the receiver: outside, by the lower bound.
    expect_refused(sine(0.0, -0.67, 0.2), fine, "cusp");
}

// refine_past_focus (default on): a frame 1.1 to 6 x past the first focus under light within 40 deg is drawn
// at the fold regime's settings, the same image to the bit as grid 512 with map 6144 asked for, and claimed
// at them. Before the focus, and in the cusp's band just past it (where the fold settings are not claimed
// either), the frame is drawn at grid and map, as it is with the map set by hand or the gates off.
TEST(CausticMappingHard, DrawnAtTheFoldSettingsWhereTheirClaimReaches) {
    const SineSetup deep = sine(20.0, -1.2, 0.2);
    const Scene scene = test_support::make_sine_scene(deep);
    const CausticOutput refined = test_support::render_method("caustic_mapping", scene, {}, deep.bins_x, deep.bins_y);
    const CausticOutput asked = test_support::render_method("caustic_mapping", scene, {{"grid", "512"}, {"map", "6144"}},
                                                             deep.bins_x, deep.bins_y);
    EXPECT_EQ(refined.health.get("refined_past_focus"), 1);
    EXPECT_EQ(asked.health.get("refined_past_focus"), 0);
    ASSERT_EQ(refined.receiver.pixels.size(), asked.receiver.pixels.size());
    EXPECT_EQ(std::memcmp(refined.receiver.pixels.data(), asked.receiver.pixels.data(),
                          asked.receiver.pixels.size() * sizeof(float)), 0);
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const AccuracyClaim c = claim_for(frame, Settings{});
    ASSERT_TRUE(c.inside) << c.reason;
    EXPECT_DOUBLE_EQ(c.max_error, kFoldClaimError);
    bool grid_bound = false;
    for (const RegimeBound& b : c.bounds) grid_bound = grid_bound || (b.quantity == "grid" && b.value == kFoldMinGrid);
    EXPECT_TRUE(grid_bound) << "the claim describes the grid the frame is drawn at";
    // Where the fold regime does not reach, nothing is refined: the frame's settings are the parameters.
    auto drawn_as_asked = [](const SineSetup& c, const Settings& s) {
        const Scene sc = test_support::make_sine_scene(c);
        const Settings f = frame_settings(build_frame_geometry(sc, 0), s);
        return f.grid == s.grid && f.map == s.map;
    };
    const Settings defaults;
    EXPECT_FALSE(drawn_as_asked(deep, defaults));
    EXPECT_TRUE(drawn_as_asked(sine(0.0, -0.25, 0.2), defaults));    // 0.4 x: before the focus
    EXPECT_TRUE(drawn_as_asked(sine(0.0, -0.67, 0.2), defaults));    // 1.05 x: the cusp's band
    EXPECT_TRUE(drawn_as_asked(sine(0.0, -4.2, 0.2), defaults));     // 6.6 x: beyond the measured depths
    EXPECT_TRUE(drawn_as_asked(sine(42.0, -1.2, 0.2), defaults));    // light beyond 40 deg
    Settings fixed_map = defaults, point = defaults, off = defaults, one_step = defaults;
    fixed_map.map_auto = false;
    point.elliptic = false;
    off.refine_past_focus = false;
    one_step.estimator.iterations = 1;   // the fold regime was measured at Newton's 3 iterations
    for (const Settings& s : {fixed_map, point, off, one_step}) EXPECT_TRUE(drawn_as_asked(deep, s));
    const SineSetup cusp = sine(0.0, -0.67, 0.2);
    const AccuracyClaim cc = claim_for(build_frame_geometry(test_support::make_sine_scene(cusp), 0), defaults);
    EXPECT_FALSE(cc.inside);
    EXPECT_NE(cc.reason.find("not refined: between 0.8 and 1.1 x the cusp"), std::string::npos) << cc.reason;
    const AccuracyClaim oc = claim_for(build_frame_geometry(test_support::make_sine_scene(deep), 0), one_step);
    EXPECT_FALSE(oc.inside);
    EXPECT_NE(oc.reason.find("at least 3 iterations"), std::string::npos) << oc.reason;
    // A point light high above the same water: the fold regime was measured under directional light, so it
    // is neither refined nor claimed there, even at the fold settings set by hand.
    Scene lamp = test_support::make_sine_scene(deep);
    lamp.lights[0].type = LightType::Point;
    lamp.lights[0].position = glm::dvec3(0.0, 0.0, 20.0);
    const FrameGeometry lamp_frame = build_frame_geometry(lamp, 0);
    const Settings lamp_drawn = frame_settings(lamp_frame, defaults);
    EXPECT_TRUE(lamp_drawn.grid == defaults.grid && lamp_drawn.map == defaults.map);
    Settings by_hand;
    by_hand.grid = kFoldMinGrid;
    by_hand.map = 6144;
    by_hand.map_auto = false;
    const AccuracyClaim pc = claim_for(lamp_frame, by_hand);
    EXPECT_FALSE(pc.inside);
    EXPECT_NE(pc.reason.find("not refined: the fold regime was measured under directional light"), std::string::npos)
        << pc.reason;
}

// The claim's bound: sine at normal incidence and at 30 deg over a floor 0.25 m down (0.40 and 0.57 of the
// way to the first focus) are inside (and met), and so is flat water (judged by flatness there: the
// baseline is exact); grazing light (80 deg) is outside, with the numbers in the reason.
TEST(CausticMappingHard, AccuracyClaimInsideAndOutside) {
    for (double tilt : {0.0, 30.0}) {
        const Result r = run(sine(tilt, -0.25), {});
        ASSERT_TRUE(r.claim.inside) << tilt;
        EXPECT_DOUBLE_EQ(r.claim.max_error, kClaimError);
        EXPECT_LT(r.nrmse, r.claim.bound(r.baseline)) << tilt;
    }
    const SineSetup grazing = sine(80.0, -0.4);
    const Scene g = test_support::make_sine_scene(grazing);
    const FrameGeometry gf = build_frame_geometry(g, 0);
    const AccuracyClaim gc = claim_for(gf, Settings{});
    EXPECT_FALSE(gc.inside);
    EXPECT_NE(gc.reason.find("80.0 deg"), std::string::npos) << gc.reason;
    SineSetup flat = sine(30.0, -0.4, 0.5);
    flat.amplitude = 1e-6;
    const Scene fs = test_support::make_sine_scene(flat);
    const FrameGeometry ff = build_frame_geometry(fs, 0);
    const AccuracyClaim fc = claim_for(ff, Settings{});
    EXPECT_TRUE(fc.inside) << fc.reason;
    // One step of the paper's approximate iteration under tilted light is not claimed (measured 1.4 x the
    // baseline on sine_oblique), nor measured here: the claim names the bound.
    Settings approx_once;
    approx_once.estimator.kind = EstimatorKind::Approx;
    approx_once.estimator.iterations = 1;
    const Scene os = test_support::make_sine_scene(sine(30.0, -0.25));
    const FrameGeometry of = build_frame_geometry(os, 0);
    const AccuracyClaim ac = claim_for(of, approx_once);
    EXPECT_FALSE(ac.inside);
    EXPECT_NE(ac.reason.find("approximate estimator"), std::string::npos) << ac.reason;
    approx_once.estimator.iterations = kMinApproxIterations;
    EXPECT_TRUE(claim_for(of, approx_once).inside);
    // The caustic map's texels per grid spacing stay where they were measured: 48 (grid 128, map 6144)
    // scored 0.26 before the focus, 3 left sharp lines to the map.
    for (const auto& [map, which] : {std::pair{6144, "above the 16"}, std::pair{384, "below the 6"}}) {
        Settings ratio;
        ratio.map = map;
        ratio.map_auto = false;
        const AccuracyClaim rc = claim_for(of, ratio);
        EXPECT_FALSE(rc.inside) << map;
        EXPECT_NE(rc.reason.find(which), std::string::npos) << rc.reason;
    }
}

// The elliptical splats are drawn by bands of rows with the splats in input order: the same bits for one
// and two threads, and across repeated renders.
TEST(CausticMappingHard, IdenticalForOneAndTwoThreads) {
    const SineSetup c = sine(30.0, -0.4);
    const Scene scene = test_support::make_sine_scene(c);
    auto render = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
        return test_support::render_method("caustic_mapping", scene, {}, c.bins_x, c.bins_y).receiver;
    };
    const Image one = render(1), two = render(2), again = render(2);
    ASSERT_EQ(one.pixels.size(), two.pixels.size());
    EXPECT_EQ(std::memcmp(one.pixels.data(), two.pixels.data(), one.pixels.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(two.pixels.data(), again.pixels.data(), two.pixels.size() * sizeof(float)), 0);
}
