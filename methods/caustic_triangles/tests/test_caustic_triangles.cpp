// caustic_triangles: closed form on flat water, convergence to the Embree reference on the analytic
// scenes, capabilities.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "../plane_refraction.hpp"
#include <caustics/frame/frame.hpp>
#include "method_support.hpp"
#include <caustics/run/metrics.hpp>
#include <caustics/frame/ray_tracer.hpp>
#include <caustics/frame/receiver_chart.hpp>
#include <caustics/reference/reference.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/scene/water_scene.hpp>
#include <caustics/blocks/regime/first_focus.hpp>

using namespace caustics;

namespace {

constexpr double caustic_triangles_claim_error = 0.07;   // the claim inside its regime (README)

const MethodInfo& info() { return require_method("caustic_triangles"); }

CausticOutput render(const Scene& scene, const std::map<std::string, std::string>& overrides, int width,
                     int height) {
    return test_support::render_method("caustic_triangles", scene, overrides, width, height);
}

// Flat water 2 m x 2 m at z = 0 over a 1 m x 1 m floor 0.4 m below (plane or flat height field).
Scene flat_water_scene(glm::dvec3 light_dir, bool fresnel, double absorption, double dispersion, bool heightfield_floor) {
    WaterOverFloor d;
    d.name = "flat";
    d.light_direction = light_dir;
    d.irradiance = 2.0;
    d.absorption = absorption;
    d.dispersion = dispersion;
    Scene s = make_water_scene(d);
    if (heightfield_floor) {
        Object& floor = s.objects[1];
        floor.shape = ShapeType::HeightField;
        floor.heightfield.size = {1.0, 1.0};
        floor.heightfield.resolution = {32, 32};
        floor.heightfield.base_height = -0.4;
        floor.heightfield.generator = HeightGenerator::Flat;
    }
    s.fresnel = fresnel;
    return s;
}

double fresnel_transmittance(double cos_i, double n) {
    const double cos_t = std::sqrt(1.0 - (1.0 - cos_i * cos_i) / (n * n));
    const double rs = (cos_i - n * cos_t) / (cos_i + n * cos_t), rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

// Every bin at least `border` bins from the map edge equals `expected` within `rel`.
void expect_uniform(const Image& img, double expected, double rel, int border = 2) {
    for (int y = border; y < img.height - border; ++y)
        for (int x = border; x < img.width - border; ++x)
            ASSERT_NEAR(img.at(x, y), expected, rel * expected) << "bin " << x << "," << y;
}

}  // namespace

TEST(CausticTriangles, RegisteredWithDocumentedParameters) {
    const MethodInfo& m = info();
    EXPECT_TRUE(m.radiometric);
    for (const char* name : {"grid", "fold_refine", "iterations", "dispersion_samples", "absorption", "coverage"}) {
        bool found = false;
        for (const ParamSpec& p : m.params)
            if (p.name == name) {
                found = true;
                EXPECT_FALSE(p.doc.empty()) << name;
            }
        EXPECT_TRUE(found) << name;
    }
    EXPECT_THROW(ParamSet::resolve(m.name, m.params, {{"iterations", "2"}}), std::exception);
}

TEST(CausticTriangles, FlatWaterNormalIncidence) {
    // E = E0 * T * exp(-Ka * depth): no Fresnel (T = 1), then with Fresnel, then absorption switched off.
    const double e0 = 2.0, ka = 0.5, depth = 0.4, n = 1.33;
    Scene plain = flat_water_scene({0, 0, -1}, false, ka, 0.0, false);
    expect_uniform(render(plain, {{"grid", "64"}}, 64, 64).receiver, e0 * std::exp(-ka * depth), 1e-3);
    Scene fresnel = flat_water_scene({0, 0, -1}, true, ka, 0.0, false);
    const double t0 = 1.0 - std::pow((n - 1) / (n + 1), 2);
    expect_uniform(render(fresnel, {{"grid", "64"}}, 64, 64).receiver, e0 * t0 * std::exp(-ka * depth), 1e-3);
    expect_uniform(render(fresnel, {{"grid", "64"}, {"absorption", "false"}}, 64, 64).receiver, e0 * t0, 1e-3);
}

TEST(CausticTriangles, FlatWaterObliqueLight) {
    // A flat interface keeps the flux per horizontal area: E = E0 cos(theta_i) T(theta_i) exp(-Ka depth /
    // cos(theta_t)). Also on a height-field floor (secant intersection) and with pixel-centre coverage.
    const glm::dvec3 dir = glm::normalize(glm::dvec3(0.3, -0.2, -1.0));
    const double e0 = 2.0, ka = 0.3, depth = 0.4, n = 1.33;
    const double cos_i = -dir.z, cos_t = std::sqrt(1.0 - (1.0 - cos_i * cos_i) / (n * n));
    const double expected = e0 * cos_i * fresnel_transmittance(cos_i, n) * std::exp(-ka * depth / cos_t);
    for (bool hf_floor : {false, true}) {
        Scene s = flat_water_scene(dir, true, ka, 0.0, hf_floor);
        CausticOutput out = render(s, {{"grid", "96"}}, 64, 64);
        SCOPED_TRACE(hf_floor ? "height-field floor" : "plane floor");
        expect_uniform(out.receiver, expected, 1e-3);
        EXPECT_EQ(out.health.get("nonfinite"), 0);
        EXPECT_EQ(out.health.get("folded_triangles"), 0);
        EXPECT_EQ(out.health.get("not_converged"), 0);
    }
    // Centre sampling: a 2 m grid of 128 over a 1 m map of 32 bins: triangles cover several centres.
    Scene s = flat_water_scene(dir, true, ka, 0.0, false);
    expect_uniform(render(s, {{"grid", "128"}, {"coverage", "center"}}, 32, 32).receiver, expected, 1e-3);
}

TEST(CausticTriangles, FloatRefractionMatchesDoubleSnell) {
    // The plane path refracts in single precision (plane_refraction.hpp). Against the same physics in
    // double (Snell in vector form, unpolarised Fresnel, Beer-Lambert, ray-plane intersection) over slopes
    // up to 45 degrees, oblique light and vertices across a 2 m pool 1 m above its floor: the image point
    // agrees to 2.5e-7 of the map (0.26 milli-bin on a 1024 map; float operands of order 1 m carry a
    // relative error of a few float epsilons, 6e-8 each) and the weight to 2e-6 relative (Fresnel's
    // quotients lose a few more epsilons near grazing incidence).
    namespace ct = caustic_triangles;
    const double n = 1.33, ka = 0.3, map_size = 1024.0;
    const glm::dvec3 origin(-1.0, -1.0, -1.0);   // floor corner; map spans 2 m x 2 m
    double worst_image = 0.0, worst_weight = 0.0;
    int compared = 0;
    for (const glm::dvec3 light : {glm::dvec3(0, 0, -1), glm::normalize(glm::dvec3(0.25, -0.15, -1.0)),
                                   glm::normalize(glm::dvec3(-0.6, 0.4, -1.0))})
        for (bool fresnel : {false, true}) {
            ct::PlaneRefraction c;
            c.light = glm::vec3(light);
            c.eta = static_cast<float>(1.0 / n);
            c.ior = static_cast<float>(n);
            c.fresnel = fresnel;
            c.absorption = static_cast<float>(ka);
            c.dual_s = {0.5f, 0.0f, 0.0f};
            c.dual_t = {0.0f, 0.5f, 0.0f};
            c.width = c.height = static_cast<float>(map_size);
            for (double gx = -1.0; gx <= 1.0; gx += 0.125)
                for (double gy = -1.0; gy <= 1.0; gy += 0.125)
                    for (const glm::dvec3 p : {glm::dvec3(-0.93, 0.41, 0.012), glm::dvec3(0.77, -0.66, -0.008),
                                               glm::dvec3(0.05, 0.95, 0.0)}) {
                        const glm::vec2 grad_f(static_cast<float>(gx), static_cast<float>(gy));
                        const glm::vec3 r_f(p - origin);
                        const ct::RefractedVertex f = ct::refract_to_plane(c, grad_f, r_f);
                        // Double precision on the same (float) inputs.
                        const glm::dvec3 nrm = glm::normalize(glm::dvec3(-double(grad_f.x), -double(grad_f.y), 1.0));
                        const glm::dvec3 L(c.light);
                        const double cos_i = -glm::dot(L, nrm);
                        if (!(cos_i > 1e-6)) {   // faces away (or grazes, where float and double may disagree)
                            if (cos_i < -1e-6) {
                                EXPECT_TRUE(f.lost);
                            }
                            continue;
                        }
                        const double eta = 1.0 / n;
                        const double cos_t = std::sqrt(1.0 - eta * eta * (1.0 - cos_i * cos_i));
                        const glm::dvec3 d = eta * L + (eta * cos_i - cos_t) * nrm;
                        const glm::dvec3 r(r_f);
                        const double t = -r.z / d.z;
                        if (!(t > 0.0)) {   // refracted upwards off a steep facet: never reaches the floor
                            EXPECT_TRUE(f.lost);
                            continue;
                        }
                        const glm::dvec3 q = r + t * d;
                        const glm::dvec2 image(0.5 * q.x * map_size, 0.5 * q.y * map_size);
                        const double weight = (fresnel ? fresnel_transmittance(cos_i, n) : 1.0) * std::exp(-ka * t);
                        ASSERT_FALSE(f.lost);
                        worst_image = std::max({worst_image, std::abs(f.image.x - image.x), std::abs(f.image.y - image.y)});
                        worst_weight = std::max(worst_weight, std::abs(f.weight - weight) / weight);
                        ++compared;
                    }
        }
    std::printf("float refraction: %d vertices, worst image error %.3g bins of %g, worst weight error %.3g\n",
                compared, worst_image, map_size, worst_weight);
    EXPECT_GT(compared, 1000);
    EXPECT_LT(worst_image, 2.5e-7 * map_size);
    EXPECT_LT(worst_weight, 2e-6);
}

TEST(CausticTriangles, FluxConservedOnWavyWater) {
    // Light at normal incidence, no Fresnel, no absorption, a floor (3 m x 3 m) wide enough to catch every
    // refracted ray: the flux through a height field's triangles is E0 times their horizontal projections,
    // which tile the 2 m x 2 m water exactly, so the map integrates to E0 * 4 m^2 whatever the waves do
    // (caustics, folds). Bound: the raster's own flux bound, 1e-5 relative.
    WaterOverFloor d;
    d.name = "wavy";
    d.irradiance = 2.0;
    d.generator = HeightGenerator::Sine;
    d.amplitude = 0.02;
    d.wavelength = 0.5;
    d.floor_z = -0.6;
    d.floor_u = {3.0, 0.0, 0.0};
    d.floor_v = {0.0, 3.0, 0.0};
    Scene s = make_water_scene(d);
    s.fresnel = false;
    const int res = 96;
    for (const char* grid : {"64", "101"}) {
        CausticOutput out = render(s, {{"grid", grid}}, res, res);
        EXPECT_EQ(out.health.get("lost_samples"), 0) << grid;
        EXPECT_EQ(out.health.get("nonfinite"), 0) << grid;
        double total = 0.0;
        for (float v : out.receiver.pixels) total += v;
        const double bin_area = (3.0 / res) * (3.0 / res);
        EXPECT_NEAR(total * bin_area, d.irradiance * 4.0, 1e-5 * d.irradiance * 4.0) << "grid " << grid;
    }
}

TEST(CausticTriangles, DispersionKeepsWhiteLightWhite) {
    // Flat water: every index gives the same irradiance, so the RGB ramp must give grey = the scalar map.
    Scene s = flat_water_scene({0, 0, -1}, false, 0.0, 0.05, false);
    CausticOutput out = render(s, {{"grid", "64"}, {"dispersion_samples", "5"}}, 32, 32);
    ASSERT_EQ(out.receiver_rgb.channels, 3);
    expect_uniform(out.receiver, 2.0, 1e-3);
    for (int y = 2; y < 30; ++y)
        for (int x = 2; x < 30; ++x)
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(out.receiver_rgb.at(x, y, c), out.receiver.at(x, y), 2e-3);
}

TEST(CausticTriangles, RejectsSphereAndPointLights) {
    const MethodInfo& m = info();
    auto method = m.create(ParamSet::resolve(m.name, m.params, {}));
    Scene sphere = load_scene("scenes/sphere.json");
    const Capability c = method->capabilities(sphere);
    EXPECT_FALSE(c.supported);
    EXPECT_NE(c.reason.find("height-field water surface and a directional light"), std::string::npos) << c.reason;
    Scene point = flat_water_scene({0, 0, -1}, false, 0.0, 0.0, false);
    point.lights[0].type = LightType::Point;
    EXPECT_FALSE(method->capabilities(point).supported);
}

// Against the Embree reference on the analytic scenes: nrmse below 5 % at grid 256 and decreasing as the
// grid grows 32 -> 64 -> 128 -> 256. The water (2 m x 2 m) is four times the floor, so only a quarter of
// the photons reach the receiver; at a 64 x 64 map and 6e6 photons the reference's own noise is ~5 %.
// That noise is independent of the method, so the measured mean squared error is the method's error
// squared plus noise_nrmse^2: the 5 % bound applies to sqrt(nrmse^2 - noise_nrmse^2), the method's error
// against the truth. The error must decrease from each grid to the next (up to the reference noise's
// cross term, 3 sigma, computed from its standard error) and every grid must beat grid 32 outright.
class AgainstReference : public ::testing::TestWithParam<const char*> {};

TEST_P(AgainstReference, ConvergesWithGrid) {
    Scene scene = load_scene(std::string("scenes/") + GetParam() + ".json");
    const int res = 64;
    scene.receiver.width = scene.receiver.height = res;
    FrameGeometry frame = build_frame_geometry(scene, 0);
    RayTracer tracer(frame);
    ReceiverChart chart(frame, res, res);
    ReferenceSettings settings;
    settings.photons = 6'000'000;
    settings.camera_view = false;
    settings.progress = false;
    const ReferenceResult ref = compute_reference(tracer, chart, nullptr, settings);
    std::printf("%s: reference %llu photons on %dx%d, noise_nrmse %.4f\n", GetParam(),
                static_cast<unsigned long long>(ref.photons), res, res, ref.noise_nrmse);
    ASSERT_LT(ref.noise_nrmse, 0.06);
    double mean_ref = 0.0;
    for (float v : ref.receiver.pixels) mean_ref += v;
    mean_ref /= static_cast<double>(ref.receiver.pixels.size());
    double previous = 1e30, first = 0.0;
    Image previous_map;
    for (int grid : {32, 64, 128, 256}) {
        CausticOutput out = render(scene, {{"grid", std::to_string(grid)}}, res, res);
        const ErrorMetrics e = compare_images(out.receiver, ref.receiver, false);
        const double corrected = std::sqrt(std::max(0.0, e.nrmse * e.nrmse - ref.noise_nrmse * ref.noise_nrmse));
        std::printf("%s: grid %4d nrmse %.4f (noise-corrected %.4f) lost %lld folded %lld\n", GetParam(), grid,
                    e.nrmse, corrected, static_cast<long long>(out.health.get("lost_samples")),
                    static_cast<long long>(out.health.get("folded_triangles")));
        EXPECT_EQ(e.nonfinite, 0);
        // Two maps m_a, m_b measured against the same noisy reference r = truth + n: the difference of
        // their squared errors carries the cross term -2 mean((m_a - m_b) n), whose standard deviation
        // follows from the reference's per-bin standard error. Once both grids are below the noise floor
        // the ordering is only meaningful up to that term (3 sigma).
        double cross_sigma = 0.0;
        if (!previous_map.empty()) {
            double acc = 0.0;
            for (std::size_t k = 0; k < out.receiver.pixels.size(); ++k) {
                const double d = double(out.receiver.pixels[k]) - previous_map.pixels[k];
                acc += d * d * double(ref.receiver_stderr.pixels[k]) * ref.receiver_stderr.pixels[k];
            }
            cross_sigma = 2.0 * std::sqrt(acc) / static_cast<double>(out.receiver.pixels.size()) / (mean_ref * mean_ref);
        }
        EXPECT_LT(e.nrmse * e.nrmse, previous * previous + 3.0 * cross_sigma) << "grid " << grid;
        if (grid == 32) {
            first = e.nrmse;
        } else {
            EXPECT_LT(e.nrmse, first) << "grid " << grid;
        }
        previous = e.nrmse;
        previous_map = out.receiver;
        if (grid == 256) {
            EXPECT_LT(corrected, 0.05);
        }
    }
}

INSTANTIATE_TEST_SUITE_P(AnalyticScenes, AgainstReference, ::testing::Values("sine", "gaussian"));

// The claim's visibility bound: crests shadow the surface once tan(tilt) max|grad h| >= 1 (sine_grazing:
// tan 80 deg x A k = 5.67 x 0.251 = 1.43), which the method does not model; at 30 deg (0.145) it claims.
TEST(CausticTriangles, ClaimsUpToTheShadowingBound) {
    const MethodInfo& info = require_method("caustic_triangles");
    for (const auto& [name, inside] : std::map<std::string, bool>{{"sine_oblique", true}, {"sine_grazing", false}}) {
        const Scene scene = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/" + name + ".json");
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        std::unique_ptr<Method> m = info.create(ParamSet::resolve(info.name, info.params, {}));
        m->prepare(scene);
        m->update(frame);
        const AccuracyClaim claim = m->accuracy_claim(frame);
        EXPECT_EQ(claim.inside, inside) << name << ": " << claim.reason;
        if (inside) {
            EXPECT_DOUBLE_EQ(claim.max_error, caustic_triangles_claim_error);
        } else {
            EXPECT_NE(claim.reason.find("shadow"), std::string::npos) << claim.reason;
        }
    }
}

// Past the first focus (sine_deep: the grid-256 map folds) the receiver is drawn at twice the grid, exactly as
// a render at that grid would draw it; before it (sine) nothing changes. The same instance alternates
// between the two grids' topologies.
TEST(CausticTriangles, DrawsPastTheFocusAtTheFoldGrid) {
    const Scene deep = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine_deep.json");
    const CausticOutput regridded = render(deep, {}, 256, 256);
    EXPECT_EQ(regridded.health.get("drawn_refined"), 1);
    EXPECT_GT(regridded.health.get("folded_triangles"), 0);
    const CausticOutput at512 = render(deep, {{"grid", "512"}, {"fold_refine", "1"}}, 256, 256);
    const CausticOutput at256 = render(deep, {{"fold_refine", "1"}}, 256, 256);
    EXPECT_EQ(at256.health.get("drawn_refined"), 0);
    EXPECT_EQ(regridded.receiver.pixels, at512.receiver.pixels);
    EXPECT_NE(regridded.receiver.pixels, at256.receiver.pixels);
    EXPECT_EQ(regridded.health.get("folded_triangles"), at512.health.get("folded_triangles"));

    // One instance, three frames: probe at 256, draw at 512, and again.
    const FrameGeometry frame = build_frame_geometry(deep, 0);
    const ReceiverChart chart(frame, 256, 256);
    std::unique_ptr<Method> m = info().create(ParamSet::resolve(info().name, info().params, {}));
    m->prepare(deep);
    m->update(frame);
    RenderRequest request;
    request.receiver = &chart;
    for (int i = 0; i < 3; ++i) EXPECT_EQ(m->render(frame, request).receiver.pixels, at512.receiver.pixels) << i;

    const Scene before = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine.json");
    const CausticOutput plain = render(before, {}, 256, 256);
    EXPECT_EQ(plain.health.get("drawn_refined"), 0);
    EXPECT_EQ(plain.receiver.pixels, render(before, {{"fold_refine", "1"}}, 256, 256).receiver.pixels);
}

// Past the first focus the claim holds only where the receiver is drawn at grid 512 or finer there
// (fold_refine x grid).
TEST(CausticTriangles, ClaimsPastTheFocusOnlyAtTheFoldGrid) {
    const Scene deep = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine_deep.json");
    const FrameGeometry frame = build_frame_geometry(deep, 0);
    auto claim_with = [&](const std::map<std::string, std::string>& overrides) {
        std::unique_ptr<Method> m = info().create(ParamSet::resolve(info().name, info().params, overrides));
        m->prepare(deep);
        m->update(frame);
        return m->accuracy_claim(frame);
    };
    const AccuracyClaim by_default = claim_with({});
    EXPECT_TRUE(by_default.inside) << by_default.reason;
    EXPECT_DOUBLE_EQ(by_default.max_error, caustic_triangles_claim_error);
    const AccuracyClaim unrefined = claim_with({{"fold_refine", "1"}});
    EXPECT_FALSE(unrefined.inside);
    EXPECT_NE(unrefined.reason.find("fold_refine"), std::string::npos) << unrefined.reason;
    EXPECT_TRUE(claim_with({{"grid", "512"}, {"fold_refine", "1"}}).inside);
    // Before the focus the fold grid is not needed.
    const Scene before = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine.json");
    const FrameGeometry f2 = build_frame_geometry(before, 0);
    std::unique_ptr<Method> m = info().create(ParamSet::resolve(info().name, info().params, {{"fold_refine", "1"}}));
    m->prepare(before);
    m->update(f2);
    EXPECT_TRUE(m->accuracy_claim(f2).inside);
}

// The claim asks for the refined grid wherever the floor lies past the first focus; render() refines where
// the grid's map folds. The two agree just either side of the focus: at 1.01 x its depth the grid-256 map
// of `sine` folds already, at 0.99 x it does not.
TEST(CausticTriangles, RefinesJustPastTheFocusWhereTheClaimAsksForIt) {
    Scene scene = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine.json");
    const regime::WaterRegime w = regime::water_regime(build_frame_geometry(scene, 0));
    ASSERT_TRUE(w.valid);
    ASSERT_LT(w.focus.first_focus_depth, 1e299);
    for (const double fraction : {0.99, 1.01}) {
        scene.objects[1].center.z = w.surface_z - fraction * w.focus.first_focus_depth;
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        const regime::WaterRegime at = regime::water_regime(frame);
        EXPECT_NEAR(at.depth_over_first_focus(), fraction, 1e-6);
        const CausticOutput out = render(scene, {}, 256, 256);
        EXPECT_EQ(out.health.get("drawn_refined"), fraction > 1.0 ? 1 : 0) << fraction;
        std::unique_ptr<Method> m = info().create(ParamSet::resolve(info().name, info().params, {}));
        m->prepare(scene);
        m->update(frame);
        const AccuracyClaim claim = m->accuracy_claim(frame);
        EXPECT_TRUE(claim.inside) << claim.reason;
        bool asks = false;
        for (const RegimeBound& b : claim.bounds) asks = asks || b.quantity == "grid_past_focus";
        EXPECT_EQ(asks, fraction > 1.0) << fraction;
    }
}

// With dispersion the highest index focuses first: the probe looks at every sample, and a refined frame
// equals a render at the refined grid (nothing of the probe's samples is left in the images).
TEST(CausticTriangles, DispersiveFramePastTheFocusIsDrawnAtTheRefinedGrid) {
    Scene scene = load_scene(std::string(CAUSTICS_SOURCE_DIR) + "/scenes/sine_deep.json");
    scene.objects[0].material.dispersion = 0.05;
    const CausticOutput refined = render(scene, {{"dispersion_samples", "4"}}, 128, 128);
    EXPECT_EQ(refined.health.get("drawn_refined"), 1);
    const CausticOutput at512 = render(scene, {{"dispersion_samples", "4"}, {"grid", "512"}, {"fold_refine", "1"}}, 128, 128);
    EXPECT_EQ(refined.receiver.pixels, at512.receiver.pixels);
    EXPECT_EQ(refined.receiver_rgb.pixels, at512.receiver_rgb.pixels);
}
