// The bad-input catalog (issue 12), command-line part: every malformed option is refused up front with
// exit 2 and one line "caustics: error: <option or file>: <what is wrong>; valid: <what would be valid>",
// nothing written under --out and no cache entry (tests/catalog_support.hpp). Integer options state
// human ranges, --photons is bounded like a sweep spec's reference.photons, --out and --cache are checked
// before any work, and unknown flags, commands, scenes and methods list the valid choices.
#include <algorithm>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "catalog_support.hpp"

namespace {

namespace fs = std::filesystem;
using caustics::test_support::CaseDir;
using caustics::test_support::check_refused;

// What one case runs and what its message must mention; built in the case's own folder.
struct Probe {
    std::vector<std::string> args;
    std::vector<std::string> expect;
};

struct CatalogCase {
    std::string name;
    std::function<Probe(const CaseDir&)> make;
};
// ctest lists the case by its name, not by a byte dump of the struct.
inline void PrintTo(const CatalogCase& c, std::ostream* os) { *os << c.name; }

std::string small_scene(const CaseDir& d) {
    const nlohmann::json camera = {{"position", {0, -1.3, 1.4}}, {"look_at", {0, 0, -0.4}}, {"up", {0, 0, 1}},
                                   {"fov_y", 45}, {"width", 16}, {"height", 12}};
    return d.write("catalog_scene.json", caustics::test_support::small_sine_scene(2.0, 16, camera).dump(2));
}

// `base` with the options of `extra` appended; an option of `base` that `extra` gives again takes
// extra's value instead (so a case states only what it is about; a repeat is made on purpose).
std::vector<std::string> with(std::vector<std::string> base, const std::vector<std::string>& extra) {
    const std::size_t own = base.size();   // only base's own options are replaced, never one appended here
    for (std::size_t i = 0; i < extra.size(); ++i) {
        const bool option = extra[i].rfind("--", 0) == 0 && i + 1 < extra.size() && extra[i + 1].rfind("--", 0) != 0;
        const auto end = base.begin() + static_cast<std::ptrdiff_t>(own);
        const auto at = option ? std::find(base.begin(), end, extra[i]) : end;
        if (at != end && at + 1 != end) {
            *(at + 1) = extra[++i];
            continue;
        }
        base.push_back(extra[i]);
    }
    return base;
}

// `reference` of the small scene with few photons, --out and --cache in the case folder.
std::vector<std::string> reference_args(const CaseDir& d, const std::vector<std::string>& extra) {
    return with({"reference", small_scene(d), "--photons", "1000", "--out", d.out(), "--cache", d.cache()}, extra);
}

// `render` of the small scene, --out and --cache in the case folder.
std::vector<std::string> render_args(const CaseDir& d, const std::vector<std::string>& extra) {
    return with({"render", small_scene(d), "--method", "caustic_triangles", "--repeats", "1", "--warmup", "0", "--out",
                 d.out(), "--cache", d.cache()},
                extra);
}


const std::vector<CatalogCase>& cases() {
    static const std::vector<CatalogCase> table = {
        // Integer options: explicit human ranges, no wrap-around, no silent clamping.
        {"PhotonsZero", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--photons", "0"}),
                          {"--photons", "0 is out of range", "valid: an integer from 1000 to 100000000000"}};
         }},
        {"PhotonsNotANumber", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--photons", "many"}),
                          {"--photons", "'many' is not an integer", "valid: an integer from 1000 to 100000000000"}};
         }},
        {"PhotonsPast64Bits", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--photons", "18446744073709551616"}),
                          {"--photons", "18446744073709551616 is out of range", "100000000000"}};
         }},
        {"PhotonsAboveSpecBound", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--photons", "100000000001"}), {"--photons", "valid: an integer from 1000"}};
         }},
        {"RenderPhotonsBelowSpecBound", [](const CaseDir& d) {
             return Probe{render_args(d, {"--photons", "999"}), {"--photons", "999 is out of range", "1000"}};
         }},
        {"PhotonCapBelowPhotons", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--photons", "20000", "--photon-cap", "10000"}),
                          {"--photon-cap", "10000 is below --photons 20000", "at least the first round's"}};
         }},
        {"PhotonCapBelowPhotonsGivenFirst", [](const CaseDir& d) {
             return Probe{with({"reference", small_scene(d), "--photon-cap", "10000", "--photons", "20000", "--out", d.out(),
                                "--cache", d.cache()},
                               {}),
                          {"--photon-cap", "below --photons 20000"}};
         }},
        {"SeedNegative", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--seed", "-1"}),
                          {"--seed", "-1 is out of range", "valid: an integer from 0 to 4611686018427387904"}};
         }},
        {"WarmupPastInt", [](const CaseDir& d) {
             return Probe{render_args(d, {"--warmup", "99999999999"}),
                          {"--warmup", "99999999999 is out of range", "valid: an integer from 0 to 10000"}};
         }},
        {"RepeatsZero", [](const CaseDir& d) {
             return Probe{render_args(d, {"--repeats", "0"}), {"--repeats", "valid: an integer from 1 to 100000"}};
         }},
        {"FrameNegative", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--frame", "-1"}), {"--frame", "valid: an integer from 0 to 1000000"}};
         }},
        {"ThreadsNotANumber", [](const CaseDir& d) {
             return Probe{render_args(d, {"--threads", "all"}),
                          {"--threads", "'all' is not an integer", "valid: an integer from 0"}};
         }},
        {"SynthFramesZero", [](const CaseDir& d) {
             return Probe{{"synth", "ocean_tile", "--method", "caustic_triangles", "--frames", "0", "--out", d.out()},
                          {"--frames", "valid: an integer from 1 to 10000"}};
         }},
        {"NoiseTargetNaN", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--noise-target", "nan"}),
                          {"--noise-target", "not a finite number", "valid: a number from 0 to 10"}};
         }},
        {"SamplerUnknown", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--sampler", "halton"}),
                          {"--sampler", "'halton'", "valid: sobol, independent"}};
         }},
        {"OptionGivenTwice", [](const CaseDir& d) {
             std::vector<std::string> args = reference_args(d, {});
             args.insert(args.end(), {"--photons", "2000"});
             return Probe{args, {"--photons", "given 2 times", "valid: once"}};
         }},
        // --set: a repeated key is an error naming the key.
        {"SetKeyTwice", [](const CaseDir& d) {
             return Probe{render_args(d, {"--no-reference", "--set", "grid=32", "--set", "grid=64"}),
                          {"--set", "'grid' given twice", "grid=32", "grid=64", "valid:"}};
         }},
        // --cache must be a folder.
        {"CacheIsAFile", [](const CaseDir& d) {
             const std::string file = d.write("cache_file", "not a folder");
             return Probe{{"reference", small_scene(d), "--photons", "1000", "--out", d.out(), "--cache", file},
                          {"--cache", file, "is a file", "valid:"}};
         }},
        // --out: checked before any work.
        {"OutEmpty", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--out", ""}), {"--out", "empty path", "valid:"}};
         }},
        {"OutIsAFile", [](const CaseDir& d) {
             const std::string file = d.write("out_file", "not a folder");
             return Probe{reference_args(d, {"--out", file}), {"--out", file, "is a file", "valid:"}};
         }},
        {"OutUnderAFile", [](const CaseDir& d) {
             const std::string file = d.write("out_file", "not a folder");
             return Probe{reference_args(d, {"--out", file + "/sub"}), {"--out", file + "/sub", "under", file}};
         }},
        {"OutUnderProc", [](const CaseDir& d) {
             return Probe{reference_args(d, {"--out", "/proc/caustics_catalog_out"}),
                          {"--out", "/proc/caustics_catalog_out", "/proc", "valid:"}};
         }},
        {"OutThroughSymlinkLoop", [](const CaseDir& d) {
             fs::create_symlink("loop_b", d.path() / "loop_a");
             fs::create_symlink("loop_a", d.path() / "loop_b");
             return Probe{reference_args(d, {"--out", d.file("loop_a") + "/out"}), {"--out", "loop_a", "symbolic link loop"}};
         }},
        // caustics report on a results.csv that is not a sweep's (a pandas traceback, or a message not in the
        // "caustics: error:" form).
        {"ReportEmptyResults", [](const CaseDir& d) {
             fs::create_directories(d.path() / "sweep");
             d.write("sweep/results.csv", "");
             return Probe{{"report", d.file("sweep")}, {"results.csv", "is empty"}};
         }},
        {"ReportGarbageResults", [](const CaseDir& d) {
             fs::create_directories(d.path() / "sweep");
             d.write("sweep/results.csv", std::string("\x89PNG\r\n\x1a\n\0\0garbage", 17));
             return Probe{{"report", d.file("sweep")}, {"results.csv", "has no column run_id"}};
         }},
        {"ReportHeaderOnlyResults", [](const CaseDir& d) {
             fs::create_directories(d.path() / "sweep");
             d.write("sweep/results.csv", "run_id,scene,method,status,time_ms_median,nrmse,radiometric\n");
             return Probe{{"report", d.file("sweep")}, {"results.csv", "a header and no run"}};
         }},
        // sweep merge / status: the folder is named, with what a sweep folder holds.
        {"SweepMergeEmpty", [](const CaseDir&) {
             return Probe{{"sweep", "merge", ""}, {"sweep merge", "empty path", "valid: a sweep folder"}};
         }},
        {"SweepMergeOfAFile", [](const CaseDir& d) {
             const std::string file = d.write("not_a_sweep.txt", "text");
             return Probe{{"sweep", "merge", file}, {file, "is not a folder", "valid: a sweep folder"}};
         }},
        {"SweepStatusOfAFolderWithoutASweep", [](const CaseDir& d) {
             fs::create_directories(d.path() / "empty");
             return Probe{{"sweep", "status", d.file("empty")}, {d.file("empty"), "holds no sweep", "valid: a sweep folder"}};
         }},
        {"SweepStatusMissing", [](const CaseDir& d) {
             return Probe{{"sweep", "status", d.file("missing")}, {d.file("missing"), "does not exist"}};
         }},
        {"OutDanglingSymlink", [](const CaseDir& d) {   // was accepted: the reference was computed and cached first
             fs::create_symlink("nowhere", d.path() / "dangling");
             return Probe{reference_args(d, {"--out", d.file("dangling")}), {"--out", "dangling", "nowhere", "does not exist"}};
         }},
        // view --screenshot: checked before a window opens (an empty name opened one that never exited).
        {"ScreenshotEmpty", [](const CaseDir& d) {
             return Probe{{"view", small_scene(d), "--screenshot", "", "--cache", d.cache()}, {"--screenshot", "empty path"}};
         }},
        {"ScreenshotInMissingFolder", [](const CaseDir& d) {
             return Probe{{"view", small_scene(d), "--screenshot", d.file("missing") + "/shot.png", "--cache", d.cache()},
                          {"--screenshot", "missing", "does not exist"}};
         }},
        {"ScreenshotIsAFolder", [](const CaseDir& d) {
             fs::create_directories(d.path() / "shots");
             return Probe{{"view", small_scene(d), "--screenshot", d.file("shots"), "--cache", d.cache()},
                          {"--screenshot", "shots", "is a folder"}};
         }},
        {"ScreenshotUnderAFile", [](const CaseDir& d) {
             const std::string file = d.write("shot_file", "not a folder");
             return Probe{{"view", small_scene(d), "--screenshot", file + "/shot.png", "--cache", d.cache()},
                          {"--screenshot", "shot_file"}};
         }},
        {"ScreenshotInProc", [](const CaseDir& d) {
             return Probe{{"view", small_scene(d), "--screenshot", "/proc/caustics_shot.png", "--cache", d.cache()},
                          {"--screenshot", "/proc"}};
         }},
        {"RenderOutIsAFile", [](const CaseDir& d) {
             const std::string file = d.write("out_file", "not a folder");
             return Probe{{"render", small_scene(d), "--method", "caustic_triangles", "--no-reference", "--repeats", "1",
                           "--warmup", "0", "--out", file},
                          {"--out", file, "is a file"}};
         }},
        {"SweepOutIsAFile", [](const CaseDir& d) {
             const std::string file = d.write("out_file", "not a folder");
             const std::string spec = d.write("spec.json", R"({"scenes": ["sine"], "methods": {"caustic_triangles": {"grid": [16]}}})");
             return Probe{{"sweep", spec, "--cache", d.cache(), "--out", file}, {"--out", file, "is a file"}};
         }},
        // Valid choices are listed.
        {"UnknownFlagListsOptions", [](const CaseDir& d) {
             return Probe{render_args(d, {"--photns", "2000"}),
                          {"--photns", "unknown option", "valid:", "--photons", "--method", "--set", "--no-reference"}};
         }},
        {"MissingCommandListsCommands", [](const CaseDir&) {
             return Probe{{}, {"COMMAND", "missing", "valid:", "list", "reference", "render", "sweep", "report", "synth"}};
         }},
        {"UnknownSceneNameListsScenes", [](const CaseDir& d) {
             return Probe{{"render", "no_such_scene_name", "--method", "caustic_triangles", "--out", d.out()},
                          {"no_such_scene_name", "valid:", "sine", "pool", "bunny"}};
         }},
        {"MissingSceneListsScenes", [](const CaseDir& d) {
             return Probe{{"render", "--method", "caustic_triangles", "--out", d.out()}, {"SCENE", "missing", "valid:", "sine"}};
         }},
        {"UnknownMethodListsMethods", [](const CaseDir& d) {
             return Probe{render_args(d, {"--method", "caustic_trangles"}),
                          {"--method", "caustic_trangles", "valid:", "caustic_triangles", "wave_optics", "eikonal_fmm"}};
         }},
        {"SceneSymlinkLoop", [](const CaseDir& d) {
             fs::create_symlink("scene_b.json", d.path() / "scene_a.json");
             fs::create_symlink("scene_a.json", d.path() / "scene_b.json");
             return Probe{{"render", d.file("scene_a.json"), "--method", "caustic_triangles", "--out", d.out()},
                          {"scene_a.json", "symbolic link loop"}};
         }},
    };
    return table;
}

class CatalogCli : public ::testing::TestWithParam<CatalogCase> {};

TEST_P(CatalogCli, RefusedUpFront) {
    const CatalogCase& c = GetParam();
    const CaseDir dir("cli_" + c.name);
    const Probe p = c.make(dir);
    // A refusal is immediate: the limit is far below what computing a reference would take.
    caustics::test_support::RefusalLimits limits;
    limits.seconds = 30;
    check_refused(dir, p.args, p.expect, limits);
}

INSTANTIATE_TEST_SUITE_P(Catalog, CatalogCli, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<CatalogCase>& info) { return info.param.name; });

}  // namespace
