// "methods": "all" in a sweep spec (every registered method at the sweep values its parameter table
// declares) and `caustics sweep --dry-run`, which lists a plan without running or writing anything.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include <caustics/api/registry.hpp>
#include <caustics/sweep/sweep_spec.hpp>
#include <caustics/util/errors.hpp>
#include "test_support.hpp"

using namespace caustics;
using test_support::quote;
using test_support::run_program;
using test_support::ScopedTempDir;
namespace fs = std::filesystem;

namespace {

fs::path write_spec(const fs::path& dir, const std::string& name, const std::string& text) {
    fs::create_directories(dir);
    const fs::path path = dir / name;
    std::ofstream(path) << text;
    return path;
}

// The axes a method's table declares for "all": parameter -> canonical values.
std::map<std::string, std::vector<std::string>> declared_axes(const MethodInfo& info) {
    std::map<std::string, std::vector<std::string>> axes;
    for (const ParamSpec& p : info.params)
        for (const std::string& v : p.sweep)
            axes[p.name].push_back(ParamSet::resolve(info.name, info.params, {{p.name, v}}).values().at(p.name));
    return axes;
}

}  // namespace

// Every registered method is in the plan, each declared parameter an axis of its declared values (the
// others at their defaults), and the run count is the sum of the products.
TEST(SweepAllMethods, EveryRegisteredMethodAtItsDeclaredSweepValues) {
    const ScopedTempDir d("caustics_test_sweep_all");
    const fs::path path = write_spec(d.path(), "all.json", R"({"scenes": ["sine"], "methods": "all"})");
    const SweepSpec spec = load_sweep_spec(path.string());
    ASSERT_EQ(spec.methods.size(), registered_methods().size());
    std::uint64_t expected_runs = 0;
    for (const SweepMethod& m : spec.methods) {
        SCOPED_TRACE(m.method);
        const auto declared = declared_axes(require_method(m.method));
        std::uint64_t product = 1;
        ASSERT_EQ(m.axes.size(), declared.size());
        for (const SweepAxis& axis : m.axes) {
            ASSERT_TRUE(declared.count(axis.name)) << axis.name;
            EXPECT_EQ(axis.values, declared.at(axis.name)) << axis.name;
            product *= axis.values.size();
        }
        expected_runs += product;
    }
    EXPECT_EQ(count_runs(spec), expected_runs);
    EXPECT_EQ(plan_runs(spec).size(), expected_runs);
    // The manifest records the expansion, not the word: a later reader sees what ran.
    EXPECT_TRUE(spec.as_run["methods"].is_object());
    EXPECT_EQ(spec.as_run["methods"].size(), registered_methods().size());
}

// The methods that declare sweep values put more than one run per scene frame into "all" (the quick
// sweep surveys them), and every declared value is one their own table accepts.
TEST(SweepAllMethods, DeclaredValuesAreValidParameterValues) {
    bool some_axis = false;
    for (const MethodInfo* info : registered_methods())
        for (const ParamSpec& p : info->params) {
            std::set<std::string> seen;
            for (const std::string& v : p.sweep) {
                EXPECT_NO_THROW(ParamSet::resolve(info->name, info->params, {{p.name, v}})) << info->name << "." << p.name;
                EXPECT_TRUE(seen.insert(v).second) << info->name << "." << p.name << ": " << v << " declared twice";
                some_axis = true;
            }
        }
    EXPECT_TRUE(some_axis);
}

// --axis replaces one axis of the expansion; other methods keep theirs.
TEST(SweepAllMethods, AxisOverrideAppliesAfterExpansion) {
    const ScopedTempDir d("caustics_test_sweep_all_axis");
    const fs::path path = write_spec(d.path(), "all.json", R"({"scenes": ["sine"], "methods": "all"})");
    const SweepSpec spec = load_sweep_spec(path.string(), {"caustic_triangles.grid=[16]"});
    bool found = false;
    for (const SweepMethod& m : spec.methods) {
        if (m.method != "caustic_triangles") continue;
        found = true;
        ASSERT_EQ(m.axes.size(), 1u);
        EXPECT_EQ(m.axes[0].name, "grid");
        EXPECT_EQ(m.axes[0].values, std::vector<std::string>{"16"});
    }
    EXPECT_TRUE(found);
    EXPECT_EQ(spec.methods.size(), registered_methods().size());
}

// The shipped quick sweep (scripts/run.sh) says "all", so a new method is in it without an edit.
TEST(SweepAllMethods, QuickSweepRunsEveryRegisteredMethod) {
    const SweepSpec spec = load_sweep_spec(std::string(CAUSTICS_SOURCE_DIR) + "/scripts/sweeps/quick.json");
    std::set<std::string> planned;
    for (const PlannedRun& run : plan_runs(spec)) planned.insert(run.method);
    std::set<std::string> registered;
    for (const MethodInfo* info : registered_methods()) registered.insert(info->name);
    EXPECT_EQ(planned, registered);
}

// Any other string, and any other type, is refused naming the file and the key.
TEST(SweepAllMethods, OtherValuesAreRefused) {
    const ScopedTempDir d("caustics_test_sweep_all_bad");
    for (const std::string value : {R"("every")", R"("ALL")", R"("")", "5", "[\"caustic_triangles\"]", "null"}) {
        const fs::path path = write_spec(d.path(), "bad.json", R"({"scenes": ["sine"], "methods": )" + value + "}");
        try {
            load_sweep_spec(path.string());
            ADD_FAILURE() << value << " accepted";
        } catch (const InputError& e) {
            const std::string msg = e.what();
            EXPECT_NE(msg.find(path.string()), std::string::npos) << msg;
            EXPECT_NE(msg.find("methods"), std::string::npos) << msg;
            EXPECT_NE(msg.find("\"all\""), std::string::npos) << msg;
        }
        // --axis on a spec whose "methods" is malformed is the same error, not a crash.
        EXPECT_THROW(load_sweep_spec(path.string(), {"caustic_triangles.grid=[16]"}), InputError) << value;
    }
}

// The program: --dry-run prints each run id and the count per method, exit 0, and writes nothing; a bad
// "methods" value is exit 2 naming the file and key.
TEST(SweepAllMethods, DryRunListsThePlanAndWritesNothing) {
    const ScopedTempDir d("caustics_test_sweep_dry_run");
    const fs::path spec = write_spec(d.path(), "all.json", R"({"scenes": ["sine", "gaussian"], "methods": "all"})");
    const fs::path out = d.path() / "out";
    const auto r = run_program(CAUSTICS_BINARY, {"sweep", spec.string(), "--dry-run", "--out", out.string()}, d.path());
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_FALSE(fs::exists(out));
    const std::uint64_t runs = count_runs(load_sweep_spec(spec.string()));
    EXPECT_NE(r.out.find("sweep: " + std::to_string(runs) + " runs planned"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("sine-f0-caustic_triangles-grid=64"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("gaussian-f0-"), std::string::npos) << r.out;
    for (const MethodInfo* info : registered_methods()) EXPECT_NE(r.out.find(info->name), std::string::npos) << info->name;

    const fs::path bad = write_spec(d.path(), "bad.json", R"({"scenes": ["sine"], "methods": "some"})");
    const auto b = run_program(CAUSTICS_BINARY, {"sweep", bad.string(), "--dry-run"}, d.path());
    EXPECT_EQ(b.code, 2);
    EXPECT_NE(b.err.find(bad.string()), std::string::npos) << b.err;
    EXPECT_NE(b.err.find("methods"), std::string::npos) << b.err;
}
