// The reference's sampler and replicas (issue 11): the quasi-Monte Carlo points are stratified as the
// theory says, the standard error from replicas matches the spread between independent seeds, noise
// targets stop at the first round that meets them, and the cache serves or extends (never recomputes)
// references of one key.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include <caustics/reference/photon_sampler.hpp>
#include <caustics/reference/reference.hpp>
#include "reference_support.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace caustics;
using namespace caustics::test_support;

namespace {

// Every elementary interval [i 2^-a, (i+1) 2^-a) x [j 2^-b, (j+1) 2^-b) with a + b = m holds exactly one
// of the 2^m points: the (0,m,2)-net property of the scrambled Sobol' (0,2)-sequence.
void expect_net(const std::vector<std::pair<double, double>>& points, int m, const std::string& what) {
    ASSERT_EQ(points.size(), std::size_t{1} << m);
    for (int a = 0; a <= m; ++a) {
        const int b = m - a;
        std::vector<int> count(std::size_t{1} << m, 0);
        for (const auto& [x, y] : points) {
            const int i = static_cast<int>(x * (1 << a)), j = static_cast<int>(y * (1 << b));
            ++count[static_cast<std::size_t>(i) * (std::size_t{1} << b) + static_cast<std::size_t>(j)];
        }
        EXPECT_EQ(*std::max_element(count.begin(), count.end()), 1) << what << ": intervals 2^-" << a << " x 2^-" << b;
    }
}

std::vector<std::pair<double, double>> sobol_points(std::uint64_t seed, std::uint32_t replica, int pair,
                                                    std::uint64_t first, std::uint64_t count) {
    std::vector<std::pair<double, double>> p;
    for (std::uint64_t i = first; i < first + count; ++i) {
        const PhotonSampler s(SamplerKind::Sobol, seed, replica, i);
        p.emplace_back(s.get(2 * pair), s.get(2 * pair + 1));
    }
    return p;
}

// Sum over bins of (E_a - E_b)^2 against the sum of se_a^2 + se_b^2 over independent seeds' references:
// both estimate 2 var per bin, so their ratio is 1 when the replicas' standard error is right. Returns
// {ratio, terms}.
std::pair<double, double> seed_spread_ratio(const TracedScene& setup, SamplerKind sampler, std::uint64_t photons,
                                            int seeds) {
    double num = 0.0, den = 0.0, terms = 0.0;
    for (int s = 0; s + 1 < seeds; s += 2) {
        ReferenceSettings settings;
        settings.photons = photons;
        settings.sampler = sampler;
        settings.camera_view = false;
        settings.progress = false;
        settings.seed = 100 + static_cast<std::uint64_t>(s);
        const ReferenceResult a = compute_reference(*setup.tracer, *setup.chart, nullptr, settings);
        settings.seed += 1;
        const ReferenceResult b = compute_reference(*setup.tracer, *setup.chart, nullptr, settings);
        for (std::size_t k = 0; k < a.receiver.pixels.size(); ++k) {
            const double va = std::pow(a.receiver_stderr.pixels[k], 2.0), vb = std::pow(b.receiver_stderr.pixels[k], 2.0);
            if (!(va > 0.0 && vb > 0.0)) continue;
            num += std::pow(static_cast<double>(a.receiver.pixels[k]) - b.receiver.pixels[k], 2.0);
            den += va + vb;
            terms += 1.0;
        }
    }
    return {num / den, terms};
}

}  // namespace

TEST(PhotonSampler, ScrambledSobolPrefixesAndBlocksAreNets) {
    for (std::uint32_t replica : {0u, 3u}) {
        for (int pair : {0, 1, 4}) {
            const std::string what = "replica " + std::to_string(replica) + " pair " + std::to_string(pair);
            expect_net(sobol_points(7, replica, pair, 0, 256), 8, what + " first 256");
            // An aligned block further on (what a batch of an extended reference reads) is a net too.
            expect_net(sobol_points(7, replica, pair, 1024, 256), 8, what + " block 1024..1279");
        }
    }
    // Independent points are not a net (almost surely): the test can tell the two apart.
    std::vector<std::pair<double, double>> random;
    for (std::uint64_t i = 0; i < 256; ++i) {
        const PhotonSampler s(SamplerKind::Independent, 7, 0, i);
        random.emplace_back(s.get(0), s.get(1));
    }
    std::vector<int> count(256, 0);
    for (const auto& [x, y] : random) ++count[static_cast<std::size_t>(x * 16) * 16 + static_cast<std::size_t>(y * 16)];
    EXPECT_GT(*std::max_element(count.begin(), count.end()), 1);
}

TEST(PhotonSampler, ReplicasAndPairsAreDifferentRandomizations) {
    const auto a = sobol_points(7, 0, 0, 0, 64), b = sobol_points(7, 1, 0, 0, 64), c = sobol_points(7, 0, 1, 0, 64),
               d = sobol_points(8, 0, 0, 0, 64);
    EXPECT_NE(a, b);
    EXPECT_NE(a, c);
    EXPECT_NE(a, d);
    // Each coordinate is uniform: the mean of 2^16 points is 1/2 within a few 1e-4 (a net's mean is
    // within 2^-16 of 1/2 in each coordinate).
    double mx = 0.0, my = 0.0;
    const auto many = sobol_points(11, 2, 1, 0, 65536);
    for (const auto& [x, y] : many) mx += x, my += y;
    EXPECT_NEAR(mx / 65536.0, 0.5, 1e-4);
    EXPECT_NEAR(my / 65536.0, 0.5, 1e-4);
}

// The replicas' standard error is what independent seeds actually scatter by, for both samplers and on
// a static and an animated scene. The ratio's sampling error is about sqrt(2 / terms) for Gaussian bin
// estimates; the bound allows 4 of those plus 5 % for the heavier tails of bins with few photons.
TEST(ReferenceReplicas, StandardErrorMatchesSpreadAcrossSeeds) {
    struct Case {
        std::string scene;
        int frame;
        SamplerKind sampler;
    };
    for (const Case& c : {Case{"sine.json", 0, SamplerKind::Sobol}, Case{"pool.json", 30, SamplerKind::Sobol},
                          Case{"sine.json", 0, SamplerKind::Independent}}) {
        Scene scene = load_scene(scene_path(c.scene));
        scene.receiver.width = scene.receiver.height = 48;
        TracedScene setup(std::move(scene), c.frame);
        const auto [ratio, terms] = seed_spread_ratio(setup, c.sampler, 400'000, 6);
        const double bound = 4.0 * std::sqrt(2.0 / terms) + 0.05;
        EXPECT_NEAR(ratio, 1.0, bound) << c.scene << " " << sampler_name(c.sampler) << " over " << terms << " bins";
        RecordProperty(c.scene + "_" + sampler_name(c.sampler) + "_ratio", std::to_string(ratio));
    }
}

TEST(ReferenceReplicas, ExtendingGivesTheSameBitsAsComputingAtOnce) {
    TracedScene setup(sine_test_scene(32, 8));
    ReferenceSettings settings;
    settings.camera_view = false;
    settings.progress = false;
    settings.photons = 160'000;
    const ReferenceResult small = compute_reference(*setup.tracer, *setup.chart, nullptr, settings);
    settings.photons = 480'000;
    const ReferenceResult extended = compute_reference(*setup.tracer, *setup.chart, nullptr, settings, small.sums.get());
    const ReferenceResult direct = compute_reference(*setup.tracer, *setup.chart, nullptr, settings);
    EXPECT_EQ(extended.photons_traced, direct.photons - small.photons);
    EXPECT_EQ(extended.sums->bin_sums, direct.sums->bin_sums);
    EXPECT_EQ(extended.receiver.pixels, direct.receiver.pixels);
    EXPECT_NEAR(extended.ledger.emitted, direct.ledger.emitted, 1e-9 * direct.ledger.emitted);
    EXPECT_NE(small.receiver.pixels, direct.receiver.pixels);
}

// A noise target adds rounds until it is met and stops at the first round that meets it.
TEST(ReferenceNoiseTarget, StopsAtTheFirstRoundThatMeetsIt) {
    TracedScene setup(sine_test_scene(64, 64));
    ReferenceSettings settings;
    settings.camera_view = false;
    settings.progress = false;
    settings.photons = 40'000;
    settings.noise_target = 0.05;
    const ReferenceResult r = compute_reference(*setup.tracer, *setup.chart, nullptr, settings);
    ASSERT_GE(r.round_noise.size(), 2u) << "the first round should not meet the target";
    EXPECT_TRUE(r.noise_target_met);
    EXPECT_LE(r.noise_nrmse, settings.noise_target);
    EXPECT_EQ(r.round_noise.back(), r.noise_nrmse);
    for (std::size_t k = 0; k + 1 < r.round_noise.size(); ++k) EXPECT_GT(r.round_noise[k], settings.noise_target);
    // The round before the last, recomputed on its own with that many photons, still misses it.
    ReferenceSettings before = settings;
    before.noise_target = 0.0;
    before.photons = r.round_photons[r.round_photons.size() - 2];
    const ReferenceResult prev = compute_reference(*setup.tracer, *setup.chart, nullptr, before);
    EXPECT_EQ(prev.noise_nrmse, r.round_noise[r.round_noise.size() - 2]);
    EXPECT_GT(prev.noise_nrmse, settings.noise_target);

    // A cap below what the target needs stops there and says so.
    ReferenceSettings capped = settings;
    capped.photon_cap = 80'000;
    const ReferenceResult c = compute_reference(*setup.tracer, *setup.chart, nullptr, capped);
    EXPECT_FALSE(c.noise_target_met);
    EXPECT_EQ(c.photons, 80'000u);
}

TEST(ReferenceNoiseTarget, CacheServesLooserTargetsAndExtendsForStricterOnes) {
    const ScopedTempDir dir("caustics_noise_target");
    Scene scene = load_scene(scene_path("sine.json"));
    scene.receiver.width = scene.receiver.height = 32;
    TracedScene setup(std::move(scene));
    ReferenceSettings settings;
    settings.camera_view = false;
    settings.progress = false;
    settings.photons = 50'000;
    settings.noise_target = 0.06;
    auto load = [&](const ReferenceSettings& s) {
        return load_or_compute_reference(*setup.frame, *setup.tracer, *setup.chart, nullptr, s, dir.path().string());
    };
    const ReferenceResult first = load(settings);
    EXPECT_FALSE(first.from_cache);
    EXPECT_TRUE(first.noise_target_met);

    ReferenceSettings looser = settings;
    looser.noise_target = 0.1;
    const ReferenceResult served = load(looser);
    EXPECT_TRUE(served.from_cache);
    EXPECT_EQ(served.photons, first.photons);
    EXPECT_EQ(served.receiver.pixels, first.receiver.pixels);

    ReferenceSettings stricter = settings;
    stricter.noise_target = 0.03;
    const ReferenceResult extended = load(stricter);
    EXPECT_FALSE(extended.from_cache);
    EXPECT_TRUE(extended.noise_target_met);
    EXPECT_GT(extended.photons, first.photons);
    // Extended, not recomputed: only the photons beyond the cached entry's were traced.
    EXPECT_EQ(extended.photons_traced, extended.photons - first.photons);
    // One entry per key is kept: the extended one holds every photon of the smaller.
    int entries = 0;
    for (const auto& e : fs::directory_iterator(dir.path())) entries += e.path().extension() == ".ref";
    EXPECT_EQ(entries, 1);
    // An explicit photon count is served exactly by that entry.
    ReferenceSettings exact = settings;
    exact.noise_target = 0.0;
    exact.photons = extended.photons;
    EXPECT_TRUE(load(exact).from_cache);
}
