// The viewer's progressive reference (harness/view/progressive_reference.hpp): its rounds grow, and the
// final result holds the same integer sums, bit for bit, as one compute_reference with the same photons;
// through a cache folder the rounds are stored and a later one resumes from them.
#include <chrono>
#include <memory>
#include <thread>

#include <gtest/gtest.h>

#include <caustics/reference/reference.hpp>
#include <caustics/run/scene_frame.hpp>
#include <caustics/view/progressive_reference.hpp>

#include "reference_support.hpp"
#include "test_support.hpp"

namespace caustics {
namespace {

Scene small_sine() {
    Scene s = test_support::sine_test_scene(32, 32);
    s.camera.width = 64;
    s.camera.height = 48;
    return s;
}

view::ProgressiveSettings small_settings(const std::string& cache_dir) {
    view::ProgressiveSettings p;
    p.reference.photons = 64'000;
    p.reference.progress = false;
    p.first_round = 4'000;
    p.round_seconds = 1e9;   // pure doubling: 4k, 8k, 16k, 32k, 64k
    p.cache_dir = cache_dir;
    return p;
}

ReferenceResult at_once(const SceneFrame& sf, std::uint64_t photons) {
    ReferenceSettings s;
    s.photons = photons;
    s.progress = false;
    s.camera_view = true;
    return compute_reference(sf.tracer(), sf.chart(), &sf.gbuffer(), s);
}

void expect_same_sums(const ReferenceSums& a, const ReferenceSums& b) {
    EXPECT_EQ(a.per_replica, b.per_replica);
    EXPECT_EQ(a.replicas, b.replicas);
    EXPECT_TRUE(a.bin_sums == b.bin_sums);
    EXPECT_TRUE(a.pixel_sums == b.pixel_sums);
    EXPECT_EQ(a.volume_sums, b.volume_sums);
}

TEST(ViewProgressiveReference, RoundsGrowAndEqualOneComputationWithTheSamePhotons) {
    const SceneFrame sf(small_sine(), 0);
    view::ProgressiveReference progressive(sf, small_settings(""));
    progressive.wait();
    const view::ProgressiveStatus st = progressive.status();
    ASSERT_TRUE(st.error.empty()) << st.error;
    EXPECT_TRUE(st.done);
    const auto rounds = progressive.round_photons();
    ASSERT_GE(rounds.size(), 4u);
    for (std::size_t i = 1; i < rounds.size(); ++i) EXPECT_GT(rounds[i], rounds[i - 1]);
    EXPECT_EQ(rounds.back(), st.target);
    EXPECT_EQ(st.photons, st.target);
    EXPECT_GT(st.photons_per_second, 0.0);
    const auto latest = progressive.latest();
    ASSERT_TRUE(latest && latest->sums);
    const ReferenceResult once = at_once(sf, st.target);
    expect_same_sums(*latest->sums, *once.sums);
    EXPECT_TRUE(latest->receiver.pixels == once.receiver.pixels);
    EXPECT_TRUE(latest->camera.pixels == once.camera.pixels);
}

TEST(ViewProgressiveReference, CachedRoundsAreStoredAndResumed) {
    test_support::ScopedTempDir cache("view_progressive_cache");
    const SceneFrame sf(small_sine(), 0);
    ASSERT_FALSE(sf.scene().source_text.empty());   // loaded from a file: cacheable
    std::uint64_t target = 0;
    {
        view::ProgressiveReference first(sf, small_settings(cache.path().string()));
        first.wait();
        ASSERT_TRUE(first.status().error.empty()) << first.status().error;
        EXPECT_FALSE(first.status().from_cache);
        EXPECT_GE(first.round_photons().size(), 4u);
        target = first.status().target;
        EXPECT_EQ(view::largest_cached_photons(sf, small_settings("").reference, cache.path().string(), target), target);
        expect_same_sums(*first.latest()->sums, *at_once(sf, target).sums);
    }
    view::ProgressiveReference second(sf, small_settings(cache.path().string()));
    second.wait();
    EXPECT_TRUE(second.status().from_cache);
    EXPECT_EQ(second.round_photons(), std::vector<std::uint64_t>{target});
    expect_same_sums(*second.latest()->sums, *at_once(sf, target).sums);
}

TEST(ViewProgressiveReference, StopsAfterTheCurrentRoundWhenAbandoned) {
    const SceneFrame sf(small_sine(), 0);
    view::ProgressiveSettings p = small_settings("");
    p.reference.photons = 4'000'000'000;   // far more than the test waits for
    p.round_seconds = 0.2;
    auto progressive = std::make_unique<view::ProgressiveReference>(sf, p);
    while (progressive->status().rounds < 2 && progressive->status().error.empty())
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ASSERT_TRUE(progressive->status().error.empty()) << progressive->status().error;
    const auto start = std::chrono::steady_clock::now();
    progressive.reset();
    // A round adds at most round_seconds' worth of photons at the measured rate (a few times that on a
    // busy machine); far less than the 4e9 photons asked for.
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
}

}  // namespace
}  // namespace caustics
