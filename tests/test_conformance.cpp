// The conformance suite: every registered method on every analytic case (tests/conformance_cases.hpp),
// judged against the exact closed form of the case (harness/reference/analytic_truth.hpp), in the manner of
// pbrt-v4's integrator x analytic-scene tests. A method added later is in the suite without editing it.
//
// Per method and case, at the method's default parameters on the scene's receiver (256 x 256; the no-caustic
// baseline is the flat interface's irradiance for water, the best constant for a solid refractor):
//   - capabilities() may refuse the case, with a reason; nothing else is then asked;
//   - the output is finite, and bitwise identical for 1 and 2 threads and across repeated renders;
//   - where the truth is flat (ior = 1, flat water) the map is flat: std/mean < 1 % over the lit bins;
//   - inside the regime accuracy_claim() states: nrmse against the truth (after the least-squares scale
//     fit where the output is not radiometric) <= the claimed factor x the no-caustic baseline's nrmse;
//     a radiometric output carries the truth's flux within 1 %; and the error at twice the default grid
//     is not larger (unless already within 1 % of the baseline's error, where bin sampling dominates);
//   - outside it, the claim names its bound; the error is measured and printed, not asserted.
// Running the binary alone prints the table of every case (ctest runs each case in its own process).
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <caustics/reference/analytic_truth.hpp>
#include <caustics/frame/baseline.hpp>
#include "conformance_cases.hpp"
#include <caustics/run/metrics.hpp>
#include <caustics/api/registry.hpp>
#include <caustics/run/run_errors.hpp>

namespace caustics {
namespace {

using test_support::ConformanceCase;
using test_support::conformance_cases;

struct Row {
    std::string method, test_case, claim;
    double error = NAN, error_2x = NAN, baseline = NAN, factor = NAN, flat = NAN;
    int grid = 0;
};

std::vector<Row>& table() {
    static std::vector<Row> rows;
    return rows;
}

// "-" where a value was not measured (a refused case; the ratio where the baseline's error is 0).
std::string number(double x) {
    if (!std::isfinite(x)) return "-";
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", x);
    return text;
}

class TablePrinter : public ::testing::Environment {
public:
    void TearDown() override {
        if (table().empty()) return;
        std::printf("\n| method | case | grid | nrmse | at 2x grid | baseline | error / baseline | std/mean (flat truth) | claim |\n"
                    "|---|---|---|---|---|---|---|---|---|\n");
        for (const Row& r : table())
            std::printf("| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", r.method.c_str(), r.test_case.c_str(),
                        r.grid > 0 ? std::to_string(r.grid).c_str() : "-", number(r.error).c_str(),
                        number(r.error_2x).c_str(), number(r.baseline).c_str(),
                        number(std::isfinite(r.flat) || r.baseline <= 0.0 ? NAN : r.error / r.baseline).c_str(),
                        number(r.flat).c_str(),
                        r.claim.c_str());
        std::fflush(stdout);
    }
};
const auto* const kPrinter = ::testing::AddGlobalTestEnvironment(new TablePrinter);

std::vector<std::string> method_names() {
    std::vector<std::string> names;
    for (const MethodInfo* info : registered_methods()) names.push_back(info->name);
    return names;
}

std::vector<std::string> case_names() {
    std::vector<std::string> names;
    for (const ConformanceCase& c : conformance_cases()) names.push_back(c.name);
    return names;
}

ConformanceCase find_case(const std::string& name) {
    for (ConformanceCase& c : conformance_cases())
        if (c.name == name) return c;
    throw std::runtime_error("unknown case " + name);
}

struct Rendered {
    CausticOutput out;
    AccuracyClaim claim;
};

// prepare, update and render frame 0 with `threads` worker threads; `repeat` renders the same frame again.
std::vector<Rendered> render(const MethodInfo& info, const std::map<std::string, std::string>& overrides,
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

bool identical(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && a.channels == b.channels && a.pixels == b.pixels;
}

std::int64_t nonfinite(const Image& img) {
    std::int64_t n = 0;
    for (float v : img.pixels) n += std::isfinite(v) ? 0 : 1;
    return n;
}

// std / mean over the bins where the truth is positive.
double flatness(const Image& m, const Image& truth) {
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

double flux(const Image& e, const ReceiverChart& chart) {
    double total = 0.0;
    for (int j = 0; j < chart.height(); ++j)
        for (int i = 0; i < chart.width(); ++i) total += e.at(i, j) * chart.bin_area(i, j);
    return total;
}

class Conformance : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(Conformance, MeetsItsClaimOnTheAnalyticCase) {
    const auto& [method_name, case_name] = GetParam();
    const MethodInfo& info = require_method(method_name);
    const ConformanceCase tc = find_case(case_name);
    const Scene scene = tc.scene();
    Row row;
    row.method = method_name;
    row.test_case = case_name;

    const ParamSet defaults = ParamSet::resolve(info.name, info.params, {});
    {
        const std::unique_ptr<Method> probe = info.create(defaults);
        const Capability cap = probe->capabilities(scene);
        if (!cap.supported) {
            EXPECT_FALSE(cap.reason.empty()) << method_name << " refuses " << case_name << " without a reason";
            row.claim = "refused: " + cap.reason;
            table().push_back(row);
            GTEST_SKIP() << method_name << " refuses " << case_name << ": " << cap.reason;
        }
    }
    const FrameGeometry frame = build_frame_geometry(scene, 0);
    const ReceiverChart chart(frame, scene.receiver.width, scene.receiver.height);
    const AnalyticTruth truth = analytic_truth(frame, chart);
    ASSERT_TRUE(truth.available) << case_name << ": " << truth.reason;
    if (tc.flat_truth) {
        ASSERT_LT(flatness(truth.receiver, truth.receiver), 1e-3) << "the case's truth is not flat";
    }
    // What drawing no caustic scores: the flat interface's irradiance, or the best constant (solids).
    const Image baseline = make_baseline(flat_interface_baseline(frame, chart), truth.receiver).map;

    // Determinism: two renders with one thread, one with two threads (a fresh instance).
    const std::vector<Rendered> one = render(info, {}, scene, frame, chart, 1, 2);
    const std::vector<Rendered> two = render(info, {}, scene, frame, chart, 2, 1);
    const Image& m = one[0].out.receiver;
    ASSERT_EQ(m.width, chart.width());
    ASSERT_EQ(m.height, chart.height());
    EXPECT_EQ(nonfinite(m), 0) << "non-finite receiver values";
    EXPECT_TRUE(identical(m, one[1].out.receiver)) << "a repeated render of the same frame differs";
    EXPECT_TRUE(identical(m, two[0].out.receiver)) << "the output differs between 1 and 2 threads";
    const AccuracyClaim claim = one[0].claim;

    const bool radiometric = info.radiometric_at(defaults);
    const ErrorMetrics e = compare_images(m, truth.receiver, !radiometric);
    const ErrorMetrics eb = compare_images(baseline, truth.receiver, !radiometric);
    row.error = radiometric ? e.nrmse : e.nrmse_fit;
    row.baseline = radiometric ? eb.nrmse : eb.nrmse_fit;
    row.grid = static_cast<int>(defaults.get_int("grid"));
    row.factor = claim.error_vs_baseline;
    row.claim = claim.inside ? "within " + number(claim.error_vs_baseline) + " x baseline"
                             : "outside: " + claim.reason;

    if (tc.flat_truth) {
        row.flat = flatness(m, truth.receiver);
        EXPECT_LT(row.flat, 0.01) << "the truth is flat, the map is not";
    }
    if (!claim.inside) {
        EXPECT_FALSE(claim.reason.empty()) << "a claim outside the regime must name its bound";
    } else {
        EXPECT_GT(claim.error_vs_baseline, 0.0);
        // A flat truth is what the flat baseline draws (its error is 0 up to float rounding): no multiple of
        // it can be asked for, and those cases are judged by flatness and flux instead.
        if (!tc.flat_truth) {
            EXPECT_LE(row.error, claim.error_vs_baseline * row.baseline)
                << method_name << " on " << case_name << ": nrmse " << row.error << ", baseline " << row.baseline
                << ", claimed factor " << claim.error_vs_baseline;
        }
        if (radiometric) {
            const double f_truth = flux(truth.receiver, chart), f_method = flux(m, chart);
            EXPECT_NEAR(f_method / f_truth, 1.0, 0.01) << "receiver flux " << f_method << ", truth " << f_truth;
        }
        // The error falls as the grid grows.
        const ParamSpec* grid_spec = nullptr;
        for (const ParamSpec& p : info.params)
            if (p.name == "grid") grid_spec = &p;
        const long long grid_2x = 2 * defaults.get_int("grid");
        if (grid_spec && grid_2x <= grid_spec->max) {
            const std::vector<Rendered> finer =
                render(info, {{"grid", std::to_string(grid_2x)}}, scene, frame, chart, 2, 1);
            const ErrorMetrics e2 = compare_images(finer[0].out.receiver, truth.receiver, !radiometric);
            row.error_2x = radiometric ? e2.nrmse : e2.nrmse_fit;
            if (!tc.flat_truth && row.error > 0.01 * row.baseline) {
                EXPECT_LE(row.error_2x, row.error) << "the error grows with the grid: " << row.error << " at grid "
                                                   << row.grid << ", " << row.error_2x << " at " << grid_2x;
            }
        }
    }
    table().push_back(row);
    std::printf("%s on %s (%s): nrmse %.4g (2x grid %.4g), baseline %.4g; %s\n", method_name.c_str(),
                case_name.c_str(), tc.what.c_str(), row.error, row.error_2x, row.baseline, row.claim.c_str());
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, Conformance, ::testing::Combine(::testing::ValuesIn(method_names()),
                                                                      ::testing::ValuesIn(case_names())),
                         [](const auto& info) { return std::get<0>(info.param) + "__" + std::get<1>(info.param); });

}  // namespace
}  // namespace caustics
