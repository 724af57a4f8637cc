#pragma once
// How the conformance suite judges one method on one analytic case (tests/test_conformance.cpp for the
// fixed cases, tests/test_conformance_drawn.cpp for the randomly drawn ones), at the method's default
// parameters (or those CAUSTICS_CONFORMANCE_PARAMS sets) on the scene's receiver; the no-caustic
// baseline is the flat interface's irradiance for
// water, the best constant for a solid refractor:
//   - capabilities() (decide_capability, as runs decide) may refuse the case, with a reason; nothing else is then asked;
//   - the output is finite (and, with `full`, bitwise identical for 1 and 2 threads and across renders);
//   - where the truth is flat (ior = 1, flat water) the map is flat: std/mean < 1 % over the lit bins;
//   - inside the regime accuracy_claim() states: nrmse against the truth (after the least-squares scale
//     fit where the output is not radiometric) <= the claim's bound: its stated absolute error, and half
//     the no-caustic baseline's, whichever is smaller; a radiometric output carries the truth's flux
//     within 1 %; with `full`, the error at twice the default grid is not larger (unless already within
//     1 % of the baseline's error, where bin sampling dominates);
//   - outside it, the claim names its bound and lists a regime bound the frame does not meet; the error
//     is measured and printed, not asserted.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <caustics/api/registry.hpp>
#include <caustics/frame/baseline.hpp>
#include <caustics/reference/analytic_truth.hpp>
#include <caustics/run/metrics.hpp>
#include <caustics/run/run_errors.hpp>
#include <caustics/run/run_record.hpp>
#include <caustics/run/view_table.hpp>

namespace caustics::test_support {

struct JudgedRow {
    std::string method, test_case, claim;
    bool refused = false, inside = false, flat_truth = false;
    double error = NAN, error_2x = NAN, baseline = NAN, bound = NAN, max_error = NAN, flat = NAN;
    std::map<std::string, ViewErrors> views;   // every view the output holds a truth for (run/view_table.hpp)
    int grid = 0;
    AccuracyClaim stated;
};

// "-" where a value was not measured (a refused case; the ratio where the baseline's error is 0).
inline std::string number(double x) {
    if (!std::isfinite(x)) return "-";
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", x);
    return text;
}

inline void print_rows(const std::vector<JudgedRow>& rows) {
    if (rows.empty()) return;
    std::printf("\n| method | case | grid | nrmse | at 2x grid | baseline | bound held to | std/mean (flat truth) | claim |\n"
                "|---|---|---|---|---|---|---|---|---|\n");
    for (const JudgedRow& r : rows)
        std::printf("| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", r.method.c_str(), r.test_case.c_str(),
                    r.grid > 0 ? std::to_string(r.grid).c_str() : "-", number(r.error).c_str(), number(r.error_2x).c_str(),
                    number(r.baseline).c_str(), number(r.bound).c_str(), number(r.flat).c_str(), r.claim.c_str());
    std::fflush(stdout);
}

struct Rendered {
    CausticOutput out;
    AccuracyClaim claim;
};

// The parameter overrides CAUSTICS_CONFORMANCE_PARAMS sets ("key=value,key=value"), kept where `info` declares
// the key: the suite then judges each method's claim at those parameters instead of its defaults (the claim
// is a function of the parameters, so it must hold at any of them). Unset: the defaults.
// Every "key=value" item of CAUSTICS_CONFORMANCE_PARAMS (spaces around items and '=' ignored).
inline std::map<std::string, std::string> conformance_params() {
    std::map<std::string, std::string> out;
    const char* env = std::getenv("CAUSTICS_CONFORMANCE_PARAMS");
    if (!env) return out;
    const std::string text = env;
    auto trim = [](const std::string& t) {
        const std::size_t a = t.find_first_not_of(" \t"), b = t.find_last_not_of(" \t");
        return a == std::string::npos ? std::string() : t.substr(a, b - a + 1);
    };
    std::size_t at = 0;
    while (at <= text.size()) {
        const std::size_t comma = std::min(text.find(',', at), text.size());
        const std::string item = text.substr(at, comma - at);
        const std::size_t eq = item.find('=');
        if (eq != std::string::npos) out[trim(item.substr(0, eq))] = trim(item.substr(eq + 1));
        at = comma + 1;
    }
    return out;
}

inline std::map<std::string, std::string> conformance_overrides(const MethodInfo& info) {
    std::map<std::string, std::string> out;
    for (const auto& [key, value] : conformance_params())
        for (const ParamSpec& p : info.params)
            if (p.name == key) out[p.name] = value;
    return out;
}

// prepare, update and render frame 0 with `threads` worker threads; `renders` renders of the same frame.
inline std::vector<Rendered> render_case(const MethodInfo& info, const std::map<std::string, std::string>& overrides,
                                         const Scene& scene, const FrameGeometry& frame, const ReceiverChart& chart,
                                         int threads, int renders) {
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::unique_ptr<Method> method = info.create(ParamSet::resolve(info.name, info.params, overrides));
    method->prepare(scene);
    method->update(frame);
    RenderRequest request;
    request.receiver = &chart;
    std::vector<Rendered> out;
    for (int i = 0; i < renders; ++i) out.push_back({method->render(frame, request), method->accuracy_claim(frame)});
    return out;
}

// The claim `info` states at its defaults (or CAUSTICS_CONFORMANCE_PARAMS) on frame 0 of `scene` (prepare
// and update, no render); a refused scene gives an outside claim with the refusal as its reason.
inline AccuracyClaim claim_only(const MethodInfo& info, const Scene& scene) {
    std::unique_ptr<Method> method = info.create(ParamSet::resolve(info.name, info.params, conformance_overrides(info)));
    const Capability cap = decide_capability(*method, scene);
    if (!cap.supported) return AccuracyClaim::outside("refused: " + cap.reason);
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    method->prepare(scene);
    method->update(frame);
    return method->accuracy_claim(frame);
}

inline bool identical(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && a.channels == b.channels && a.pixels == b.pixels;
}

inline std::int64_t nonfinite(const Image& img) {
    std::int64_t n = 0;
    for (float v : img.pixels) n += std::isfinite(v) ? 0 : 1;
    return n;
}

// std / mean over the bins where the truth is positive.
inline double flatness(const Image& m, const Image& truth) {
    double s = 0.0, s2 = 0.0;
    std::int64_t n = 0;
    for (std::size_t i = 0; i < m.pixels.size(); ++i)
        if (truth.pixels[i] > 0.0f) {
            s += m.pixels[i];
            s2 += static_cast<double>(m.pixels[i]) * m.pixels[i];
            ++n;
        }
    if (n == 0) return NAN;
    const double mean = s / n;
    return std::sqrt(std::max(0.0, s2 / n - mean * mean)) / std::fabs(mean);
}

inline double chart_flux(const Image& e, const ReceiverChart& chart) {
    double total = 0.0;
    for (int j = 0; j < chart.height(); ++j)
        for (int i = 0; i < chart.width(); ++i) total += e.at(i, j) * chart.bin_area(i, j);
    return total;
}

// Judges `info` at its defaults (or CAUSTICS_CONFORMANCE_PARAMS) on `scene` (frame 0) against the scene's
// closed form, with gtest expectations; `full` adds the determinism and twice-the-grid checks. Returns the row it measured.
inline JudgedRow judge_case(const MethodInfo& info, const std::string& case_name, const Scene& scene, bool flat_truth,
                            bool full) {
    JudgedRow row;
    row.method = info.name;
    row.test_case = case_name;
    row.flat_truth = flat_truth;
    const std::map<std::string, std::string> overrides = conformance_overrides(info);
    const ParamSet defaults = ParamSet::resolve(info.name, info.params, overrides);
    {
        const std::unique_ptr<Method> probe = info.create(defaults);
        const Capability cap = decide_capability(*probe, scene);
        if (!cap.supported) {
            EXPECT_FALSE(cap.reason.empty()) << info.name << " refuses " << case_name << " without a reason";
            row.refused = true;
            row.claim = "refused: " + cap.reason;
            return row;
        }
    }
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
    const AnalyticTruth truth = analytic_truth(frame, chart);
    EXPECT_TRUE(truth.available) << case_name << ": " << truth.reason;
    if (!truth.available) return row;
    if (flat_truth) {
        EXPECT_LT(flatness(truth.receiver, truth.receiver), 1e-3) << "the case's truth is not flat";
    }
    // What drawing no caustic scores: the flat interface's irradiance, or the best constant (solids).
    const Image flat = flat_interface_baseline(frame, chart);
    const Image baseline = make_baseline(flat, truth.receiver).map;

    const std::vector<Rendered> two = render_case(info, overrides, scene, frame, chart, 2, 1);
    const Image& m = two[0].out.receiver;
    EXPECT_EQ(m.width, chart.width());
    EXPECT_EQ(m.height, chart.height());
    if (m.width != chart.width() || m.height != chart.height()) return row;
    EXPECT_EQ(nonfinite(m), 0) << "non-finite receiver values";
    if (full) {
        // Determinism: two renders with one thread (a fresh instance) against the render with two.
        const std::vector<Rendered> one = render_case(info, overrides, scene, frame, chart, 1, 2);
        EXPECT_TRUE(identical(one[0].out.receiver, one[1].out.receiver)) << "a repeated render of the same frame differs";
        EXPECT_TRUE(identical(m, one[0].out.receiver)) << "the output differs between 1 and 2 threads";
    }
    const AccuracyClaim claim = two[0].claim;
    row.stated = claim;

    const bool radiometric = info.radiometric_at(defaults);
    // Every view the output holds, measured as runs measure them (a further registered view included).
    const ViewSources sources{&scene, &frame, &chart, nullptr, nullptr, &truth, &flat};
    EXPECT_EQ(check_views(two[0].out, sources, info.name), 0) << "non-finite values in a view";
    for (EvaluatedView& v : evaluate_views(two[0].out, sources, radiometric)) row.views[v.spec->name] = std::move(v.errors);
    const ErrorMetrics e = compare_images(m, truth.receiver, !radiometric);
    const ErrorMetrics eb = compare_images(baseline, truth.receiver, !radiometric);
    row.error = radiometric ? e.nrmse : e.nrmse_fit;
    row.baseline = radiometric ? eb.nrmse : eb.nrmse_fit;
    row.grid = static_cast<int>(defaults.get_int("grid"));
    row.inside = claim.inside;
    row.max_error = claim.inside ? claim.max_error : NAN;
    row.bound = claim.inside && !flat_truth ? claim.bound(row.baseline) : NAN;
    row.claim = claim.inside ? "within nrmse " + number(claim.max_error) + " (and 0.5 x baseline)"
                             : "outside: " + claim.reason;

    if (flat_truth) {
        row.flat = flatness(m, truth.receiver);
        EXPECT_LT(row.flat, 0.01) << "the truth is flat, the map is not";
    }
    if (!claim.inside) {
        EXPECT_FALSE(claim.reason.empty()) << "a claim outside the regime must name its bound";
        bool some_bound_fails = false;
        for (const RegimeBound& b : claim.bounds) some_bound_fails |= !b.holds();
        EXPECT_TRUE(some_bound_fails) << "outside, but every listed regime bound holds: " << claim.reason;
        return row;
    }
    for (const RegimeBound& b : claim.bounds)
        EXPECT_TRUE(b.holds()) << "inside, but the bound on " << b.quantity << " fails: " << b.value << " vs " << b.limit;
    const bool relative_ok = radiometric ? claim.max_error <= kDefaultClaimError + 1e-12 : claim.max_error <= 0.25 + 1e-12;
    EXPECT_TRUE(relative_ok) << info.name << " claims nrmse " << claim.max_error << ": at most "
                             << (radiometric ? kDefaultClaimError : 0.25) << " may be claimed at the defaults";
    // A flat truth is what the flat baseline draws (its error is 0 up to float rounding): no multiple of it
    // can be asked for, and those cases are judged by flatness and flux instead.
    if (!flat_truth) {
        EXPECT_TRUE(judge_claim(claim, row.error, row.baseline).met) << info.name << " on " << case_name << ": nrmse " << row.error << ", baseline "
                                        << row.baseline << ", claimed nrmse " << claim.max_error;
    }
    if (radiometric) {
        const double f_truth = chart_flux(truth.receiver, chart), f_method = chart_flux(m, chart);
        EXPECT_NEAR(f_method / f_truth, 1.0, 0.01) << "receiver flux " << f_method << ", truth " << f_truth;
    }
    if (!full) return row;
    // The error falls as the grid grows.
    const ParamSpec* grid_spec = nullptr;
    for (const ParamSpec& p : info.params)
        if (p.name == "grid") grid_spec = &p;
    const long long grid_2x = 2 * defaults.get_int("grid");
    if (grid_spec && grid_2x <= grid_spec->max) {
        std::map<std::string, std::string> finer_params = overrides;
        finer_params["grid"] = std::to_string(grid_2x);
        const std::vector<Rendered> finer = render_case(info, finer_params, scene, frame, chart, 2, 1);
        const ErrorMetrics e2 = compare_images(finer[0].out.receiver, truth.receiver, !radiometric);
        row.error_2x = radiometric ? e2.nrmse : e2.nrmse_fit;
        if (!flat_truth && row.error > 0.01 * row.baseline) {
            EXPECT_LE(row.error_2x, row.error) << "the error grows with the grid: " << row.error << " at grid " << row.grid
                                               << ", " << row.error_2x << " at " << grid_2x;
        }
    }
    return row;
}

}  // namespace caustics::test_support
