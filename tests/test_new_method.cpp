// scripts/new_method.sh: the files it stamps out into a standalone project folder (--dir), and its refusals
// (exit 2, one message, nothing written). Building and running a stamped method is the round trip of the
// installed-package tests.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace fs = std::filesystem;
using caustics::test_support::ProgramResult;
using caustics::test_support::run_program;
using caustics::test_support::ScopedTempDir;
using caustics::test_support::slurp;

namespace {

const std::string kScript = std::string(CAUSTICS_SOURCE_DIR) + "/scripts/new_method.sh";

// The script with `args`, and CAUSTICS_BIN set to `program` (whose `list --json` names the registered
// methods); its output files go to `scratch`.
ProgramResult new_method(const std::vector<std::string>& args, const fs::path& scratch,
                         const std::string& program = CAUSTICS_BINARY) {
    std::vector<std::string> all = {"CAUSTICS_BIN=" + program, kScript};
    all.insert(all.end(), args.begin(), args.end());
    return run_program("/usr/bin/env", all, scratch);
}

// Every path under `dir`, relative, with its size: a snapshot that shows whether anything was written.
std::set<std::string> listing(const fs::path& dir) {
    std::set<std::string> out;
    if (!fs::exists(dir)) return out;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
        std::string entry = fs::relative(e.path(), dir).string();
        if (e.is_regular_file()) entry.append(" ").append(std::to_string(e.file_size()));
        out.insert(entry);
    }
    return out;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST(NewMethod, StampsAStandaloneProject) {
    const ScopedTempDir scratch("caustics_test_new_method");
    fs::create_directories(scratch.path());
    const fs::path project = scratch.path() / "project";
    const ProgramResult r = new_method({"scaffold_probe", "--dir", project.string()}, scratch.path());
    ASSERT_EQ(r.code, 0) << r.err;

    const fs::path method = project / "scaffold_probe";
    // CMakeLists.txt, the method folder and its five entries (tests/ counted), and no temporaries.
    EXPECT_EQ(listing(project).size(), 7u);
    // The method's CMakeLists.txt is the one line that works in the repository and against an install.
    EXPECT_EQ(slurp(method / "CMakeLists.txt"), "caustics_add_method(scaffold_probe)\n");

    const std::string source = slurp(method / "scaffold_probe.cpp");
    const std::string test = slurp(method / "tests" / "test_scaffold_probe.cpp");
    const std::string readme = slurp(method / "README.md");
    for (const std::string* text : {&source, &test, &readme}) {
        EXPECT_FALSE(text->empty());
        EXPECT_FALSE(contains(*text, "@NAME@") || contains(*text, "@CLASS@") || contains(*text, "@SUITE@")) << "a placeholder is left";
    }
    EXPECT_TRUE(contains(source, "info.name = \"scaffold_probe\";"));
    EXPECT_TRUE(contains(source, "namespace scaffold_probe {"));
    EXPECT_TRUE(contains(source, "class ScaffoldProbeMethod final : public Method"));
    EXPECT_TRUE(contains(source, "CAUSTICS_REGISTER_METHOD(scaffold_probe::method_info);"));
    for (const char* part : {"{\"grid\", ParamType::Int", "{\"iterations\", ParamType::Int", "capabilities(", "prepare(",
                             "update(", "render(", "accuracy_claim(", "info.radiometric = true", "health.add("})
        EXPECT_TRUE(contains(source, part)) << part;
    EXPECT_TRUE(contains(test, "constexpr const char* kMethod = \"scaffold_probe\";"));
    EXPECT_TRUE(contains(test, "TEST(ScaffoldProbe, ReceiverCarriesTheBaselineFlux)"));
    for (const char* heading : {"# scaffold_probe", "## Paper", "## Equations followed", "## Parameters",
                                "## Regime of validity", "## Departures from the paper and the settings that restore it",
                                "## Measured speed and error", "## Health counters"})
        EXPECT_TRUE(contains(readme, std::string("\n") + heading + "\n") || readme.rfind(std::string(heading) + "\n", 0) == 0)
            << heading;

    const std::string cmake = slurp(project / "CMakeLists.txt");
    for (const char* line : {"cmake_minimum_required(VERSION", "project(", "find_package(caustics REQUIRED)",
                             "enable_testing()", "add_subdirectory(scaffold_probe)"})
        EXPECT_TRUE(contains(cmake, line)) << line;

    // A second method in the same project is added to its CMakeLists.txt; the first stays.
    const ProgramResult second = new_method({"scaffold_probe_two", "--dir", project.string()}, scratch.path());
    ASSERT_EQ(second.code, 0) << second.err;
    const std::string both = slurp(project / "CMakeLists.txt");
    EXPECT_TRUE(contains(both, "add_subdirectory(scaffold_probe)\n"));
    EXPECT_TRUE(contains(both, "add_subdirectory(scaffold_probe_two)\n"));
    EXPECT_EQ(both.substr(0, cmake.size()), cmake);
    EXPECT_TRUE(fs::is_regular_file(project / "scaffold_probe_two" / "tests" / "test_scaffold_probe_two.cpp"));
}

// A bad name or usage: exit 2, one message naming the name and what would be valid, nothing written in the
// project folder or in the repository's methods/.
TEST(NewMethod, RefusesBadNamesAndWritesNothing) {
    const ScopedTempDir scratch("caustics_test_new_method_bad");
    const fs::path project = scratch.path() / "project";
    fs::create_directories(project / "taken");
    // A stand-in program that registers a method called "ghost" (the script asks `caustics list --json`).
    const fs::path fake = scratch.path() / "fake_caustics";
    std::ofstream(fake) << "#!/bin/sh\necho '{\"methods\": [{\"name\": \"ghost\"}], \"scenes\": []}'\n";
    fs::permissions(fake, fs::perms::owner_all);

    const fs::path methods = fs::path(CAUSTICS_SOURCE_DIR) / "methods";
    const std::set<std::string> project_before = listing(project), methods_before = listing(methods);
    const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
        {{"Upper"}, "not a lower-case identifier"},
        {{"1st"}, "not a lower-case identifier"},
        {{"has-dash"}, "not a lower-case identifier"},
        {{"two\nlines"}, "$'two\\nlines'"},          // shown escaped: the message stays one line
        {{"a__b"}, "'__'"},
        {{"class"}, "keyword"},
        {{"caustic_triangles"}, "already exists"},   // a method of the repository
        {{"taken"}, "already exists"},               // a folder of the project
        {{"ghost"}, "registers a method of that name"},
        {{"sweep"}, "test_sweep"},                   // its test program would clash with tests/test_sweep
        {{}, "NAME is missing"},
        {{"one", "two"}, "a second NAME"},
        {{"fine", "--dir"}, "--dir"},
        {{"fine", "--bogus"}, "unknown option"},
    };
    for (const auto& [args, message] : cases) {
        std::vector<std::string> with_dir = args;
        if (!(args.size() == 2 && args[1].rfind("--", 0) == 0)) with_dir.insert(with_dir.end(), {"--dir", project.string()});
        const ProgramResult r = new_method(with_dir, scratch.path(), fake.string());
        const std::string shown = args.empty() ? "(no arguments)" : args[0];
        EXPECT_EQ(r.code, 2) << shown << ": " << r.err;
        EXPECT_TRUE(contains(r.err, "new_method.sh: error: ")) << shown << ": " << r.err;
        EXPECT_TRUE(contains(r.err, message)) << shown << ": " << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << shown << ": one line\n" << r.err;
        EXPECT_TRUE(r.out.empty()) << shown << ": " << r.out;
    }
    // The same refusal without --dir, where the method would go to the repository's methods/.
    EXPECT_EQ(new_method({"Upper"}, scratch.path(), fake.string()).code, 2);
    EXPECT_EQ(new_method({"wave_pde"}, scratch.path(), fake.string()).code, 2);
    EXPECT_EQ(listing(project), project_before);
    EXPECT_EQ(listing(methods), methods_before);
}
