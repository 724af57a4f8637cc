// The data folder is found at run time (util/resources.hpp), never through a compiled-in source path:
// beside the program in a build tree (build/<preset>/share/caustics, linking to the source folders), or
// where CAUSTICS_DATA_DIR says; scene names resolve in its scenes/ (scene/scene_catalog.hpp).
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include <caustics/run/run_context.hpp>
#include <caustics/scene/scene_catalog.hpp>
#include <caustics/util/errors.hpp>
#include <caustics/util/resources.hpp>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace caustics {
namespace {

// Sets CAUSTICS_DATA_DIR for its lifetime (unset: nullopt), restoring what was there.
class DataDirOverride {
public:
    explicit DataDirOverride(const std::optional<std::string>& value) {
        if (const char* old = std::getenv("CAUSTICS_DATA_DIR")) old_ = old;
        if (value) ::setenv("CAUSTICS_DATA_DIR", value->c_str(), 1);
        else ::unsetenv("CAUSTICS_DATA_DIR");
    }
    ~DataDirOverride() {
        if (old_) ::setenv("CAUSTICS_DATA_DIR", old_->c_str(), 1);
        else ::unsetenv("CAUSTICS_DATA_DIR");
    }

private:
    std::optional<std::string> old_;
};

TEST(Resources, BuildTreeDataFolderLinksToTheSourceTree) {
    const DataDirOverride unset(std::nullopt);
    const fs::path data = data_directory();
    EXPECT_EQ(data.filename(), "caustics");
    EXPECT_EQ(data.parent_path().filename(), "share");
    EXPECT_TRUE(fs::equivalent(data / "scenes" / "sine.json", fs::path(CAUSTICS_SOURCE_DIR) / "scenes" / "sine.json"));
    EXPECT_TRUE(fs::is_regular_file(data / "scripts" / "report" / "report.py"));
    EXPECT_TRUE(fs::equivalent(build_description().value("source_dir", ""), CAUSTICS_SOURCE_DIR));
    EXPECT_EQ(run_context()["git_commit_from"], "source tree");

    const auto sine = find_named_scene("sine");
    ASSERT_TRUE(sine);
    EXPECT_EQ(*sine, data / "scenes" / "sine.json");
    EXPECT_EQ(resolve_scene_path("sine.json"), (data / "scenes" / "sine.json").string());
    EXPECT_FALSE(find_named_scene("scenes/sine"));
    EXPECT_FALSE(find_named_scene("README.md")) << "only scene files are scene names";
}

TEST(Resources, EnvironmentNamesTheDataFolder) {
    const test_support::ScopedTempDir dir("caustics_resources_data");
    fs::create_directories(dir.path() / "scenes");
    std::ofstream(dir.path() / "scenes" / "mine.json") << "{}";
    const DataDirOverride data(dir.path().string());
    EXPECT_EQ(data_directory(), dir.path());
    EXPECT_EQ(scene_names(), std::vector<std::string>{"mine"});
    EXPECT_EQ(resolve_scene_path("mine"), (dir.path() / "scenes" / "mine.json").string());
    EXPECT_TRUE(build_description().empty()) << "no build.json: nothing known";
    EXPECT_EQ(run_context()["git_commit"], "unknown");
    try {
        resolve_scene_path("sine");
        FAIL() << "a scene outside the data folder was found";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("a scene name in " + (dir.path() / "scenes").string() + ": mine"),
                  std::string::npos)
            << e.what();
    }
}

TEST(Resources, DataFolderWithoutScenesIsRefusedNamingTheVariable) {
    const test_support::ScopedTempDir dir("caustics_resources_empty");
    fs::create_directories(dir.path());
    const DataDirOverride data(dir.path().string());
    try {
        data_directory();
        FAIL() << "a folder without scenes/ was accepted";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(what.rfind("CAUSTICS_DATA_DIR: '" + dir.path().string() + "' has no scenes/ folder", 0), 0u) << what;
    }
    EXPECT_TRUE(build_description().empty()) << "describing the build never throws";

    const test_support::ProgramResult r = test_support::run_program(CAUSTICS_BINARY, {"list"}, dir.path());
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(r.err.rfind("caustics: error: CAUSTICS_DATA_DIR: ", 0), 0u) << r.err;
}

}  // namespace
}  // namespace caustics
