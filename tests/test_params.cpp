#include <gtest/gtest.h>

#include <caustics/util/errors.hpp>
#include <caustics/api/params.hpp>
#include <caustics/util/timing.hpp>

using namespace caustics;

namespace {
std::vector<ParamSpec> table() {
    return {
        {"grid", ParamType::Int, "256", 2, 4096, {}, "grid resolution"},
        {"eps", ParamType::Float, "0.5", 0.0, 1.0, {}, "step"},
        {"estimator", ParamType::Enum, "approx", 0, 0, {"approx", "newton"}, "estimator"},
        {"clamp", ParamType::Bool, "false", 0, 0, {}, "clamp"},
    };
}
}  // namespace

TEST(Params, DefaultsResolve) {
    ParamSet p = ParamSet::resolve("m", table(), {});
    EXPECT_EQ(p.get_int("grid"), 256);
    EXPECT_DOUBLE_EQ(p.get_float("eps"), 0.5);
    EXPECT_EQ(p.get_enum("estimator"), "approx");
    EXPECT_FALSE(p.get_bool("clamp"));
}

TEST(Params, OverridesAreCanonicalised) {
    ParamSet p = ParamSet::resolve("m", table(), {{"grid", "64.0"}, {"clamp", "on"}, {"estimator", "newton"}});
    EXPECT_EQ(p.get_int("grid"), 64);
    EXPECT_EQ(p.values().at("grid"), "64");
    EXPECT_TRUE(p.get_bool("clamp"));
    EXPECT_EQ(p.get_enum("estimator"), "newton");
}

TEST(Params, UnknownKeyNamesKeyAndValidKeys) {
    try {
        ParamSet::resolve("m", table(), {{"gird", "3"}});
        FAIL() << "no error";
    } catch (const InputError& e) {
        std::string msg = e.what();
        EXPECT_NE(msg.find("gird"), std::string::npos);
        EXPECT_NE(msg.find("grid"), std::string::npos);
    }
}

TEST(Params, OutOfRangeNamesRange) {
    for (auto [key, value] : std::vector<std::pair<std::string, std::string>>{
             {"grid", "1"}, {"grid", "5000"}, {"grid", "abc"}, {"eps", "nan"}, {"eps", "1.5"},
             {"estimator", "bisect"}, {"clamp", "maybe"}}) {
        try {
            ParamSet::resolve("m", table(), {{key, value}});
            FAIL() << key << "=" << value << " accepted";
        } catch (const InputError& e) {
            std::string msg = e.what();
            EXPECT_NE(msg.find(key), std::string::npos) << msg;
            EXPECT_NE(msg.find("valid"), std::string::npos) << msg;
        }
    }
}

TEST(Params, AssignmentParsing) {
    auto [k, v] = parse_assignment("grid=128", "--set");
    EXPECT_EQ(k, "grid");
    EXPECT_EQ(v, "128");
    EXPECT_THROW(parse_assignment("grid", "--set"), InputError);
}

TEST(Timing, MedianMinP90) {
    TimingSummary s = summarize_ms({5, 1, 4, 2, 3, 10, 9, 8, 7, 6});
    EXPECT_DOUBLE_EQ(s.min, 1);
    EXPECT_DOUBLE_EQ(s.median, 5.5);
    EXPECT_DOUBLE_EQ(s.p90, 9);
}
