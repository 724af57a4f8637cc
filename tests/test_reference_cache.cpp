// Reference cache tests: the key changes with every input, damaged entries are rebuilt, and a scene
// built in code (no file bytes to key on) is never cached. Noise targets and extension: test_reference_rqmc.cpp.
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <gtest/gtest.h>

#include <caustics/reference/reference.hpp>
#include "reference_support.hpp"
#include <caustics/scene/scene.hpp>
#include "test_support.hpp"
#include <caustics/scene/water_scene.hpp>

namespace fs = std::filesystem;
using namespace caustics;
using namespace caustics::test_support;

TEST(ReferenceCache, KeyChangesWithEveryInput) {
    const ScopedTempDir temp("caustics_refkey");
    const fs::path& dir = temp.path();
    fs::create_directories(dir);
    const fs::path asset = dir / "asset.bin";
    std::ofstream(asset, std::ios::binary) << "abcdef";
    Scene s = load_scene(scene_path("sine.json"));
    s.assets.push_back(asset.string());
    ReferenceSettings settings;
    settings.photons = 1000;
    const std::string base = reference_cache_key(s, 0, settings);
    EXPECT_EQ(base.size(), 32u);
    EXPECT_EQ(base, reference_cache_key(s, 0, settings));

    Scene text = s;
    text.source_text[text.source_text.size() / 2] ^= 1;
    EXPECT_NE(base, reference_cache_key(text, 0, settings));
    EXPECT_NE(base, reference_cache_key(s, 1, settings));
    // Photons are not in the key: entries of one key differ in photons (file name), and a larger
    // one extends a smaller one.
    ReferenceSettings more = settings;
    more.photons += 1;
    EXPECT_EQ(base, reference_cache_key(s, 0, more));
    ReferenceSettings sampler = settings;
    sampler.sampler = SamplerKind::Independent;
    EXPECT_NE(base, reference_cache_key(s, 0, sampler));
    ReferenceSettings replicas = settings;
    replicas.replicas += 1;
    EXPECT_NE(base, reference_cache_key(s, 0, replicas));
    ReferenceSettings seed = settings;
    seed.seed += 1;
    EXPECT_NE(base, reference_cache_key(s, 0, seed));
    ReferenceSettings nocam = settings;
    nocam.camera_view = !nocam.camera_view;
    EXPECT_NE(base, reference_cache_key(s, 0, nocam));
    std::ofstream(asset, std::ios::binary) << "abcdeg";   // one asset byte
    EXPECT_NE(base, reference_cache_key(s, 0, settings));
    std::ofstream(asset, std::ios::binary) << "abcdef";
    EXPECT_EQ(base, reference_cache_key(s, 0, settings));
}

TEST(ReferenceCache, DamagedEntriesAreRebuilt) {
    const ScopedTempDir temp("caustics_refcache");
    const fs::path& dir = temp.path();
    TracedScene setup(sine_test_scene(16, 16));
    ReferenceSettings settings;
    settings.photons = 100'000;
    settings.camera_view = false;
    settings.progress = false;
    auto load = [&] { return load_or_compute_reference(*setup.frame, *setup.tracer, *setup.chart, nullptr, settings, dir.string()); };
    auto same = [](const ReferenceResult& a, const ReferenceResult& b) {
        return a.receiver.pixels == b.receiver.pixels && a.receiver_stderr.pixels == b.receiver_stderr.pixels &&
               std::memcmp(&a.ledger, &b.ledger, sizeof(FluxLedger)) == 0 && a.noise_nrmse == b.noise_nrmse &&
               a.cache_key == b.cache_key;
    };
    const ReferenceResult fresh = load();
    EXPECT_FALSE(fresh.from_cache);
    const fs::path file = dir / (fresh.cache_key + ".ref");
    ASSERT_TRUE(fs::exists(file));
    const ReferenceResult cached = load();
    EXPECT_TRUE(cached.from_cache);
    EXPECT_TRUE(same(fresh, cached));

    const auto size = fs::file_size(file);
    fs::resize_file(file, size / 2);   // truncated
    const ReferenceResult rebuilt = load();
    EXPECT_FALSE(rebuilt.from_cache);
    EXPECT_TRUE(same(fresh, rebuilt));
    EXPECT_EQ(fs::file_size(file), size);

    {   // one flipped bit in the payload
        std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
        f.seekg(static_cast<std::streamoff>(size / 2));
        char c;
        f.read(&c, 1);
        c ^= 0x10;
        f.seekp(static_cast<std::streamoff>(size / 2));
        f.write(&c, 1);
    }
    const ReferenceResult rebuilt2 = load();
    EXPECT_FALSE(rebuilt2.from_cache);
    EXPECT_TRUE(same(fresh, rebuilt2));
    EXPECT_TRUE(load().from_cache);

    std::ofstream(file, std::ios::binary | std::ios::trunc) << "garbage";
    EXPECT_FALSE(load().from_cache);
    for (const auto& entry : fs::directory_iterator(dir))   // no temporary files left behind
        EXPECT_EQ(entry.path().extension(), ".ref") << entry.path();
}

TEST(ReferenceCache, SceneBuiltInCodeIsNeverCached) {
    // Two different scenes built in code have the same (empty) file bytes, so a key could not tell
    // them apart: both are computed, and nothing is written.
    const ScopedTempDir temp("caustics_refcode");
    const fs::path& dir = temp.path();
    WaterOverFloor d;
    d.generator = HeightGenerator::Sine;
    d.amplitude = 0.01;
    d.receiver_resolution = 16;
    ReferenceSettings settings;
    settings.photons = 50'000;
    settings.camera_view = false;
    settings.progress = false;
    TracedScene sine(make_water_scene(d));
    d.amplitude = 0.02;
    TracedScene steeper(make_water_scene(d));
    auto load = [&](const TracedScene& t) {
        return load_or_compute_reference(*t.frame, *t.tracer, *t.chart, nullptr, settings, dir.string());
    };
    const ReferenceResult a = load(sine);
    const ReferenceResult b = load(steeper);
    EXPECT_FALSE(a.from_cache);
    EXPECT_FALSE(b.from_cache);
    EXPECT_NE(a.receiver.pixels, b.receiver.pixels);
    EXPECT_FALSE(load(sine).from_cache);
    EXPECT_TRUE(!fs::exists(dir) || fs::is_empty(dir));
}
