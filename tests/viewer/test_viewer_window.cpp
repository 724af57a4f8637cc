// The viewer's window (harness/cli/viewer), through the program: without a display it exits 2 with one
// message naming xvfb-run, before any other work; under xvfb-run (registered only where xvfb-run exists)
// its screenshot's method pane shows the receiver map `caustics render` writes for the same settings,
// through the same colour map, pixel for pixel within 8-bit quantisation, and playing advances the
// animation one scene frame per window frame.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <caustics/util/image_io.hpp>
#include <caustics/view/colormap.hpp>

#include "test_support.hpp"

namespace caustics {
namespace {

using test_support::ProgramResult;
using test_support::ScopedTempDir;

ProgramResult run_without_display(const std::vector<std::string>& args, const std::filesystem::path& scratch) {
    std::vector<std::string> all = {"-u", "DISPLAY", "-u", "WAYLAND_DISPLAY", CAUSTICS_BINARY};
    all.insert(all.end(), args.begin(), args.end());
    return test_support::run_program("/usr/bin/env", all, scratch);
}

TEST(ViewerWindow, NoDisplayExitsTwoWithOneMessageBeforeAnyWork) {
    ScopedTempDir dir("viewer_no_display");
    std::filesystem::create_directories(dir.path());
    const ProgramResult r = run_without_display({"view", "sine", "--no-reference"}, dir.path());
    EXPECT_EQ(r.code, 2);
    EXPECT_NE(r.err.find("no display"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("xvfb-run"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    // Before any work: a scene that does not exist is not even looked at.
    const ProgramResult missing = run_without_display({"view", "no_such_scene_anywhere"}, dir.path());
    EXPECT_EQ(missing.code, 2);
    EXPECT_NE(missing.err.find("xvfb-run"), std::string::npos) << missing.err;
}

#ifdef CAUSTICS_XVFB_RUN
// The window's pixels (PNG, 8 bits) as RGBA bytes.
std::vector<int> png_rgba(const std::string& path, int& w, int& h) {
    const Image im = read_image(path);
    w = im.width;
    h = im.height;
    std::vector<int> out(static_cast<std::size_t>(w) * h * 4, 255);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < std::min(im.channels, 4); ++c)
                out[(static_cast<std::size_t>(y) * w + x) * 4 + c] = static_cast<int>(std::lround(im.at(x, y, c) * 255.0));
    return out;
}

TEST(ViewerWindow, ScreenshotMethodPaneMatchesTheRenderedReceiverMap) {
    ScopedTempDir dir("viewer_screenshot");
    std::filesystem::create_directories(dir.path());
    const std::string shot = (dir.path() / "out.png").string();
    const ProgramResult v = test_support::run_program(
        CAUSTICS_XVFB_RUN, {"-a", CAUSTICS_BINARY, "view", "sine", "--method", "caustic_triangles", "--screenshot", shot,
                            "--frames", "3", "--no-reference"},
        dir.path());
    ASSERT_EQ(v.code, 0) << v.err;
    const ProgramResult r = test_support::run_program(
        CAUSTICS_BINARY, {"render", "sine", "--method", "caustic_triangles", "--no-reference", "--warmup", "0", "--repeats", "1",
                          "--out", (dir.path() / "render").string()},
        dir.path());
    ASSERT_EQ(r.code, 0) << r.err;

    const nlohmann::json side = nlohmann::json::parse(test_support::slurp(shot + ".json"));
    const nlohmann::json* pane = nullptr;
    for (const auto& p : side["panes"])
        if (p["view"] == "method receiver") pane = &p;
    ASSERT_NE(pane, nullptr) << side.dump(2);
    const Image map = read_image((dir.path() / "render" / "receiver.exr").string());
    ASSERT_EQ(map.width, (*pane)["image_width"].get<int>());
    ASSERT_EQ(map.height, (*pane)["image_height"].get<int>());
    view::Mapping m;
    m.exposure = (*pane)["exposure"] == "log" ? view::Exposure::Log : view::Exposure::Linear;
    m.colormap = view::ColorMap::Inferno;
    ASSERT_EQ((*pane)["colormap"], "inferno");
    m.scale = (*pane)["scale"].get<double>();
    m.decades = (*pane)["decades"].get<double>();
    const std::vector<std::uint8_t> expected = view::map_to_rgba8(map, m);

    int w = 0, h = 0;
    const std::vector<int> shot_px = png_rgba(shot, w, h);
    const int x0 = (*pane)["x"].get<int>(), y0 = (*pane)["y"].get<int>();
    const int pw = (*pane)["width"].get<int>(), ph = (*pane)["height"].get<int>();
    ASSERT_EQ(pw % map.width, 0);   // a whole zoom: every bin is a block of whole pixels
    ASSERT_EQ(ph, pw / map.width * map.height);
    ASSERT_LE(x0 + pw, w);
    ASSERT_LE(y0 + ph, h);
    const int zoom = pw / map.width;
    int worst = 0;
    std::set<int> colours;
    for (int y = 0; y < ph; ++y)
        for (int x = 0; x < pw; ++x) {
            const std::size_t s = (static_cast<std::size_t>(y0 + y) * w + (x0 + x)) * 4;
            const std::size_t e = (static_cast<std::size_t>(y / zoom) * map.width + x / zoom) * 4;
            for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(shot_px[s + c] - static_cast<int>(expected[e + c])));
            colours.insert(shot_px[s] << 16 | shot_px[s + 1] << 8 | shot_px[s + 2]);
        }
    EXPECT_LE(worst, 1) << "pane pixels differ from the rendered receiver map";
    EXPECT_GT(colours.size(), 32u) << "the method pane is blank";
}

// Play: each window frame moves to the next scene frame and runs update + render there.
TEST(ViewerWindow, PlayAdvancesOneSceneFramePerWindowFrame) {
    ScopedTempDir dir("viewer_play");
    std::filesystem::create_directories(dir.path());
    const std::string shot = (dir.path() / "play.png").string();
    const ProgramResult v = test_support::run_program(
        CAUSTICS_XVFB_RUN, {"-a", CAUSTICS_BINARY, "view", "pool", "--method", "caustic_triangles", "--frame", "3", "--play",
                            "--screenshot", shot, "--frames", "4", "--no-reference"},
        dir.path());
    ASSERT_EQ(v.code, 0) << v.err;
    const nlohmann::json side = nlohmann::json::parse(test_support::slurp(shot + ".json"));
    EXPECT_EQ(side["frame"], 7);
    EXPECT_EQ(side["frames"], 4);
}
#endif

}  // namespace
}  // namespace caustics
