// The conformance suite: every registered method on every fixed analytic case (tests/conformance_cases.hpp),
// judged against the exact closed form of the case (harness/reference/analytic_truth.hpp), in the manner of
// pbrt-v4's integrator x analytic-scene tests. A method added later is in the suite without editing it.
// What is checked per method and case: tests/conformance_judge.hpp (with the determinism and twice-the-grid
// checks); the randomly drawn hard cases are tests/test_conformance_drawn.cpp.
// Running the binary alone prints the table of every case (ctest runs each case in its own process).
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "conformance_cases.hpp"
#include "conformance_judge.hpp"

namespace caustics {
namespace {

using test_support::ConformanceCase;
using test_support::conformance_cases;
using test_support::JudgedRow;

std::vector<JudgedRow>& table() {
    static std::vector<JudgedRow> rows;
    return rows;
}

class TablePrinter : public ::testing::Environment {
public:
    void TearDown() override { test_support::print_rows(table()); }
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

class Conformance : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(Conformance, MeetsItsClaimOnTheAnalyticCase) {
    const auto& [method_name, case_name] = GetParam();
    const ConformanceCase tc = find_case(case_name);
    const JudgedRow row = test_support::judge_case(require_method(method_name), case_name, tc.scene(), tc.flat_truth, true);
    table().push_back(row);
    if (row.refused) GTEST_SKIP() << method_name << " " << row.claim;
    std::printf("%s on %s (%s): nrmse %.4g (2x grid %.4g), baseline %.4g, held to %.4g; %s\n", method_name.c_str(),
                case_name.c_str(), tc.what.c_str(), row.error, row.error_2x, row.baseline, row.bound, row.claim.c_str());
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, Conformance, ::testing::Combine(::testing::ValuesIn(method_names()),
                                                                      ::testing::ValuesIn(case_names())),
                         [](const auto& info) { return std::get<0>(info.param) + "__" + std::get<1>(info.param); });

}  // namespace
}  // namespace caustics
