// The conformance suite on randomly drawn hard cases (tests/conformance_drawn.hpp): every registered method at
// its defaults (or the parameters CAUSTICS_CONFORMANCE_PARAMS sets) on CAUSTICS_CONFORMANCE_CASES drawn sine
// and Gaussian cases of seed CAUSTICS_CONFORMANCE_SEED (both printed), judged as on the fixed cases
// (tests/conformance_judge.hpp), and besides:
//   - the regime quantities a claim lists (RegimeBound) agree with the same quantities computed from the
//     closed-form surface (conformance_drawn.hpp), so that a case called outside really lies beyond the
//     stated bound, and a case called inside within it;
//   - the regime is drawn where the method's error is: with the default seed, widening every bound a case
//     fails by 2x (the mutation a loose regime would be) brings in a case whose error exceeds the claim,
//     wherever such cases were drawn (the cases excluded only by bounds within 2x of their limits); further
//     cases of the same draw are examined when the first ones bring in none that misses.
// One test per method, over all drawn cases, which prints the per-case table and a summary: the cases
// inside, the worst error inside and the bound it was held to. With CAUSTICS_CONFORMANCE_CSV_DIR set it also
// writes the cases as <dir>/<method>.csv, which scripts/report/method_table.py turns into the README's
// method table (scripts/studies/method_table.sh: 200 cases of seed 20261205).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/blocks/regime/first_focus.hpp>

#include "conformance_cases.hpp"
#include "conformance_drawn.hpp"
#include "conformance_judge.hpp"

namespace caustics {
namespace {

using test_support::DrawnCase;
using test_support::IndependentRegime;
using test_support::JudgedRow;

std::vector<std::string> method_names() {
    std::vector<std::string> names;
    for (const MethodInfo* info : registered_methods()) names.push_back(info->name);
    return names;
}

// The quantity named `name` from the closed form; false for a quantity the suite does not recompute.
bool independent_value(const std::string& name, const IndependentRegime& r, double& value, double& tolerance) {
    if (name == "tilt_deg") {
        value = r.tilt_deg, tolerance = 0.05;
    } else if (name == "depth_over_first_focus") {
        value = r.depth_over_first_focus(), tolerance = 0.02 * std::max(value, 0.05);
    } else if (name == "ior") {
        value = r.ior, tolerance = 1e-9;
    } else {
        return false;
    }
    return true;
}

// Every listed quantity the suite knows is the closed form's, within its tolerance: a case called outside is
// then beyond the stated limit by the independent value too, and a case called inside within it.
void check_regime_quantities(const AccuracyClaim& claim, const DrawnCase& c) {
    for (const RegimeBound& b : claim.bounds) {
        double truth = 0.0, tol = 0.0;
        if (!independent_value(b.quantity, c.regime, truth, tol)) continue;
        EXPECT_NEAR(b.value, truth, tol) << c.name << " (" << c.what << "): the claim measures " << b.quantity << " as "
                                         << b.value << ", the closed form gives " << truth;
        if (!b.holds()) {
            EXPECT_TRUE(b.upper ? truth > b.limit - tol : truth < b.limit + tol)
                << c.name << ": called outside by " << b.quantity << " " << b.value << " against " << b.limit
                << ", but the closed form gives " << truth;
        }
    }
}

// Whether every bound the claim fails would hold with its limit widened 2x (upper limits doubled, lower
// limits halved), and at least one bound fails: a case a 2x looser regime would claim.
bool inside_when_widened(const AccuracyClaim& claim) {
    bool any = false;
    for (const RegimeBound& b : claim.bounds) {
        if (b.holds()) continue;
        any = true;
        const bool widened = b.upper ? (b.limit > 0.0 && b.value <= 2.0 * b.limit) : b.value >= 0.5 * b.limit;
        if (!widened) return false;
    }
    return any;
}

// The drawn cases of one method as CSV (one row per case), written to a temporary name and renamed.
void write_cases_csv(const std::string& dir, const std::string& method, std::uint64_t seed,
                     const std::vector<JudgedRow>& rows, const std::vector<DrawnCase>& cases) {
    namespace fs = std::filesystem;
    fs::create_directories(dir);
    const fs::path path = fs::path(dir) / (method + ".csv");
    const fs::path tmp = fs::path(dir) / (method + ".csv.tmp");
    {
        std::ofstream f(tmp);
        f << "method,seed,case,what,refused,inside,nrmse,baseline,bound\n";
        for (std::size_t i = 0; i < rows.size(); ++i) {
            const JudgedRow& r = rows[i];
            auto num = [](double x) { return std::isfinite(x) ? test_support::number(x) : std::string(); };
            char error[32];
            std::snprintf(error, sizeof error, "%.6g", r.error);
            f << method << "," << seed << "," << cases[i].name << ",\"" << cases[i].what << "\"," << r.refused << ","
              << r.inside << "," << (std::isfinite(r.error) ? error : "") << "," << num(r.baseline) << ","
              << num(r.bound) << "\n";
        }
        ASSERT_TRUE(f.good()) << "could not write " << tmp;
    }
    fs::rename(tmp, path);
    std::printf("cases written to %s\n", path.string().c_str());
}

// How many further cases of the default seed the mutation check may examine beyond the drawn ones: only the
// cases the widened regime brings in are rendered, and the search stops at the first that misses. 400, because
// the default seed's first miss for wave_optics' widened eps bound is its case 390 (seeds 1 and 3 show
// misses among their first 200). The first kMutationFirstExtraCases are always examined; beyond them only
// for a method whose claim takes at most kSlowClaimSeconds a case (wave_pde's takes about 1.4 s, wave_optics'
// a few hundredths): otherwise the check is reported as inconclusive and not asserted (as it was when no case
// was brought in at all). That is decided once, after the first 48, from the claims' mean time; a miss found
// among the first 48 is asserted on any machine.
constexpr int kMutationExtraCases = 400;
constexpr int kMutationFirstExtraCases = 48;
constexpr double kSlowClaimSeconds = 0.5;

class ConformanceDrawn : public ::testing::TestWithParam<std::string> {};

TEST_P(ConformanceDrawn, MeetsItsClaimOnDrawnHardCases) {
    const MethodInfo& info = require_method(GetParam());
    const std::uint64_t seed = test_support::conformance_seed();
    const int count = test_support::conformance_case_count();
    // A key no registered method declares is a typing error, not a setting to ignore.
    for (const auto& [key, value] : test_support::conformance_params()) {
        bool declared = false;
        for (const MethodInfo* m : registered_methods())
            for (const ParamSpec& p : m->params) declared = declared || p.name == key;
        ASSERT_TRUE(declared) << "CAUSTICS_CONFORMANCE_PARAMS names '" << key << "', which no registered method declares";
    }
    std::string params;
    for (const auto& [k, v] : test_support::conformance_overrides(info)) params += (params.empty() ? "" : ",") + k + "=" + v;
    std::printf("CAUSTICS_CONFORMANCE_SEED=%llu CAUSTICS_CONFORMANCE_CASES=%d CAUSTICS_CONFORMANCE_PARAMS=%s (%s)\n",
                static_cast<unsigned long long>(seed), count, params.c_str(), info.name.c_str());
    std::vector<JudgedRow> rows;
    std::vector<DrawnCase> cases;
    double render_s = 0.0;
    std::vector<int> indices;
    std::string only_error;
    ASSERT_TRUE(test_support::conformance_only_cases(indices, only_error)) << only_error;
    const bool subset = !indices.empty();
    if (!subset)
        for (int i = 0; i < count; ++i) indices.push_back(i);
    else
        std::printf("CAUSTICS_CONFORMANCE_ONLY=%s: %zu chosen cases\n", std::getenv("CAUSTICS_CONFORMANCE_ONLY"), indices.size());
    for (const int i : indices) {
        DrawnCase c = test_support::drawn_case(seed, i);
        SCOPED_TRACE(c.name + ": " + c.what);
        const auto t0 = std::chrono::steady_clock::now();
        JudgedRow row = test_support::judge_case(info, c.name, c.scene, false, false);
        render_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        row.test_case = c.name;
        if (!row.refused) check_regime_quantities(row.stated, c);
        std::string bounds;
        for (const RegimeBound& b : row.stated.bounds)
            bounds += " " + b.quantity + "=" + test_support::number(b.value) + (b.upper ? "<=" : ">=") + test_support::number(b.limit);
        std::printf("%s on %s (%s): nrmse %.4g, baseline %.4g, held to %s; %s; bounds:%s\n", info.name.c_str(),
                    c.name.c_str(), c.what.c_str(), row.error, row.baseline, test_support::number(row.bound).c_str(),
                    row.claim.c_str(), bounds.c_str());
        rows.push_back(row);
        cases.push_back(std::move(c));
    }
    test_support::print_rows(rows);
    if (const char* dir = std::getenv("CAUSTICS_CONFORMANCE_CSV_DIR"); dir && *dir)
        write_cases_csv(dir, info.name, seed, rows, cases);

    int inside = 0, refused = 0;
    double worst = 0.0, worst_bound = NAN, claimed = 0.0;
    std::string worst_case = "-";
    for (const JudgedRow& r : rows) {
        refused += r.refused;
        if (r.refused || !r.inside) continue;
        ++inside;
        claimed = std::max(claimed, r.max_error);
        if (r.error > worst) worst = r.error, worst_bound = r.bound, worst_case = r.test_case;
    }
    std::printf("summary: %s inside its claim on %d of %d drawn cases (%d refused); worst nrmse inside %.4g on %s "
                "(held to %s); %.1f s judging\n",
                info.name.c_str(), inside, static_cast<int>(rows.size()), refused, worst, worst_case.c_str(),
                test_support::number(worst_bound).c_str(), render_s);

    // The mutation a loose regime would be: every failed bound widened 2x. Where that brings cases in, one of
    // them must miss the claim the method states inside (else the regime is narrower than its model). Checked
    // with the default seed; where the drawn cases bring in none that misses, further cases of the same draw
    // (indices count, count + 1, ...) are examined, rendering only those the widened regime brings in.
    if (claimed == 0.0) claimed = kDefaultClaimError;
    int brought_in = 0, missed = 0, extra = 0;
    for (const JudgedRow& r : rows) {
        if (r.refused || r.inside || !std::isfinite(r.error) || !inside_when_widened(r.stated)) continue;
        ++brought_in;
        missed += r.error > std::min(claimed, 0.5 * r.baseline);
    }
    double claim_s = 0.0;
    int claims = 0;
    bool cut = false;
    // A chosen subset (CAUSTICS_CONFORMANCE_ONLY) is a measurement, not the check: the search and the
    // assertion below run on the first N cases only.
    if (subset) {
        std::printf("mutation: not checked on a chosen subset of cases (CAUSTICS_CONFORMANCE_ONLY)\n");
        return;
    }
    if (seed == test_support::kDefaultConformanceSeed) {
        for (int i = count; missed == 0 && i < count + kMutationExtraCases; ++i) {
            if (i == count + kMutationFirstExtraCases && claim_s > kSlowClaimSeconds * claims) {
                cut = true;
                break;
            }
            const DrawnCase c = test_support::drawn_case(seed, i);
            const auto t0 = std::chrono::steady_clock::now();
            const bool in = inside_when_widened(test_support::claim_only(info, c.scene));
            claim_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            ++claims;
            if (!in) continue;
            const JudgedRow r = test_support::judge_case(info, c.name, c.scene, false, false);
            ++brought_in, ++extra;
            missed += std::isfinite(r.error) && r.error > std::min(claimed, 0.5 * r.baseline);
            std::printf("mutation: %s (%s) brought in by the widened regime: nrmse %.4g, baseline %.4g\n", c.name.c_str(),
                        c.what.c_str(), r.error, r.baseline);
        }
    }
    std::printf("mutation: a 2x wider regime brings in %d case(s) (%d beyond the first %d), %d of which miss the "
                "claimed nrmse %.3g\n",
                brought_in, extra, count, missed, claimed);
    if (cut) {
        std::printf("mutation: %s: its claim takes %.2f s a case, so the search stopped after %d further cases with "
                    "none missing so far: inconclusive, not asserted\n",
                    info.name.c_str(), claim_s / std::max(claims, 1), claims);
        RecordProperty("mutation", "inconclusive");
    }
    if (seed == test_support::kDefaultConformanceSeed && brought_in > 0 && !cut) {
        EXPECT_GT(missed, 0) << info.name << ": its regime widened 2x still holds on the " << brought_in
                             << " drawn case(s) it brings in: the regime is narrower than the method";
    }
}

// The per-frame form of the regime (RegimeParts::FocusOnly, which a render may compute every frame to decide
// its resolution) gives the full regime's first focus to the bit, on drawn cases, on the 2-D pool and on a
// flat surface (no focus), so that such a render and the claim decide alike.
TEST(WaterRegime, FocusOnlyGivesTheFullRegimesFirstFocus) {
    std::vector<Scene> scenes;
    for (int i = 0; i < 24; ++i) scenes.push_back(test_support::drawn_case(test_support::kDefaultConformanceSeed, i).scene);
    scenes.push_back(test_support::shipped_scene("pool"));
    scenes.push_back(test_support::shipped_scene("flat_oblique"));
    for (const Scene& scene : scenes) {
        const FrameGeometry frame = build_frame_geometry(scene, 0);
        const regime::WaterRegime all = regime::water_regime(frame);
        const regime::WaterRegime focus = regime::water_regime(frame, regime::RegimeParts::FocusOnly);
        ASSERT_TRUE(all.valid) << scene.name;
        EXPECT_TRUE(focus.valid) << scene.name;
        EXPECT_EQ(focus.focus.first_focus_depth, all.focus.first_focus_depth) << scene.name;
        EXPECT_EQ(focus.depth_over_first_focus(), all.depth_over_first_focus()) << scene.name;
    }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, ConformanceDrawn, ::testing::ValuesIn(method_names()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace caustics
