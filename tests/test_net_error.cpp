// Errors net of reference noise (issue 11): on synthetic maps with a known error and a noisy reference
// of known variance, the net estimate recovers the error and its interval covers it at the nominal
// rate; the per-bin consistency test; the statistics behind both.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/run/net_error.hpp>
#include <caustics/util/statistics.hpp>

using namespace caustics;

namespace {

constexpr int kSize = 48;

// A structured truth (caustic-like bands) and a method with a known error pattern.
Image truth_map() {
    Image t(kSize, kSize, 1);
    for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i)
            t.at(i, j) = static_cast<float>(1.0 + 0.6 * std::sin(2.0 * std::numbers::pi * i / 12.0) * std::cos(0.3 * j));
    return t;
}

Image with_error(const Image& t, double amplitude) {
    Image m = t;
    for (int j = 0; j < kSize; ++j)
        for (int i = 0; i < kSize; ++i) m.at(i, j) += static_cast<float>(amplitude * std::cos(2.0 * std::numbers::pi * (i + 2 * j) / 16.0));
    return m;
}

double true_nrmse(const Image& m, const Image& t) {
    double sq = 0.0, sum = 0.0;
    for (std::size_t k = 0; k < t.pixels.size(); ++k) {
        sq += std::pow(static_cast<double>(m.pixels[k]) - t.pixels[k], 2.0);
        sum += t.pixels[k];
    }
    const double n = static_cast<double>(t.pixels.size());
    return std::sqrt(sq / n) / (sum / n);
}

// R replicas of t with per-replica noise sd `sigma_replica` (so the mean has sd sigma_replica / sqrt(R)),
// their mean and standard error.
struct NoisyReference {
    std::vector<Image> replicas;
    Image mean, se;
    TruthMaps maps() const { return {&mean, &replicas, &se}; }
};

NoisyReference noisy_reference(const Image& t, int replicas, double sigma_replica, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    NoisyReference r;
    r.replicas.assign(static_cast<std::size_t>(replicas), t);
    for (Image& rep : r.replicas)
        for (float& v : rep.pixels) v += static_cast<float>(sigma_replica * normal(rng));
    r.mean = Image(kSize, kSize, 1);
    r.se = Image(kSize, kSize, 1);
    const double R = replicas;
    for (std::size_t k = 0; k < t.pixels.size(); ++k) {
        double s = 0.0, q = 0.0;
        for (const Image& rep : r.replicas) s += rep.pixels[k], q += static_cast<double>(rep.pixels[k]) * rep.pixels[k];
        const double m = s / R;
        r.mean.pixels[k] = static_cast<float>(m);
        r.se.pixels[k] = static_cast<float>(std::sqrt(std::max(0.0, (q - R * m * m) / (R - 1.0)) / R));
    }
    return r;
}

}  // namespace

TEST(Statistics, StudentTQuantilesAndMedianInterval) {
    EXPECT_NEAR(student_t_critical(0.05, 7.0), 2.364624, 1e-5);    // tables
    EXPECT_NEAR(student_t_critical(0.05, 1.0), 12.7062, 1e-3);
    EXPECT_NEAR(student_t_critical(0.01, 30.0), 2.749996, 1e-5);
    EXPECT_NEAR(student_t_critical(0.05, 1e9), 1.959964, 1e-5);
    EXPECT_NEAR(student_t_two_sided_p(2.364624, 7.0), 0.05, 1e-6);
    EXPECT_NEAR(sidak_level(0.05, 10), 1.0 - std::pow(0.95, 0.1), 1e-12);
    std::vector<double> x;
    for (int i = 1; i <= 20; ++i) x.push_back(i);
    const MedianInterval m = median_interval(x, 0.95);
    EXPECT_TRUE(m.has_interval);
    EXPECT_DOUBLE_EQ(m.median, 10.5);
    // n = 20: P(B <= 5) = 0.0207 <= 0.025 < P(B <= 6) = 0.0577, so [x_(6), x_(15)].
    EXPECT_DOUBLE_EQ(m.lo, 6.0);
    EXPECT_DOUBLE_EQ(m.hi, 15.0);
    EXPECT_FALSE(median_interval({1, 2, 3}, 0.95).has_interval);
}

// The raw nrmse against a noisy reference is inflated by the noise; the net one is not, and its 95 %
// interval covers the true error in about 95 % of independent references (binomial sd over 400 trials
// is 1.1 %; the bound allows 3.3 sd). Two regimes: reference noise twice the method's error (the
// degenerate part of the estimate dominates) and a third of it (the linear part dominates).
TEST(NetError, RecoversKnownErrorAndCoversAtTheNominalRate) {
    const Image t = truth_map();
    const Image m = with_error(t, 0.02);
    const double truth_error = true_nrmse(m, t);
    ASSERT_NEAR(truth_error, 0.0141, 1e-3);
    constexpr int kTrials = 400, kReplicas = 8;
    for (const double noise_ratio : {2.0, 1.0 / 3.0}) {
        const double sigma_replica = noise_ratio * truth_error * std::sqrt(static_cast<double>(kReplicas));
        int covered = 0;
        double mean_net = 0.0, mean_raw = 0.0;
        for (int trial = 0; trial < kTrials; ++trial) {
            const NoisyReference ref = noisy_reference(t, kReplicas, sigma_replica, 1000 + trial);
            const NetError e = net_error(m, ref.maps(), nullptr);
            ASSERT_TRUE(e.valid);
            covered += e.lo <= truth_error && truth_error <= e.hi;
            mean_net += e.value / kTrials;
            const NetError raw = net_error(m, TruthMaps{&ref.mean, nullptr, nullptr}, nullptr);
            mean_raw += raw.value / kTrials;
        }
        const double rate = covered / static_cast<double>(kTrials);
        EXPECT_NEAR(rate, 0.95, 0.036) << "coverage of the 95 % interval, noise ratio " << noise_ratio;
        EXPECT_NEAR(mean_net, truth_error, 0.05 * truth_error) << "noise ratio " << noise_ratio;
        // What the net estimate corrects: the raw error is sqrt(1 + ratio^2) times the truth.
        EXPECT_NEAR(mean_raw / truth_error, std::sqrt(1.0 + noise_ratio * noise_ratio), 0.05) << "noise ratio " << noise_ratio;
        RecordProperty("coverage_at_noise_ratio_" + std::to_string(noise_ratio), std::to_string(rate));
    }
}

TEST(NetError, PerfectMethodIsWithinNoiseAndExactTruthGivesThePlainError) {
    const Image t = truth_map();
    const NoisyReference ref = noisy_reference(t, 8, 0.05, 7);
    const NetError perfect = net_error(t, ref.maps(), nullptr);
    EXPECT_TRUE(perfect.includes_zero);
    EXPECT_LT(perfect.lo, 1e-12);
    // Against an exact truth the net error is the plain nrmse and the interval is a point.
    const Image m = with_error(t, 0.05);
    const NetError exact = net_error(m, TruthMaps{&t, nullptr, nullptr}, nullptr);
    EXPECT_NEAR(exact.value, true_nrmse(m, t), 1e-6);
    EXPECT_EQ(exact.lo, exact.value);
    EXPECT_EQ(exact.hi, exact.value);
    EXPECT_FALSE(exact.includes_zero);
    // A scale is applied to the method before comparing.
    Image half = t;
    for (float& v : half.pixels) v *= 0.5f;
    EXPECT_NEAR(net_error(half, TruthMaps{&t, nullptr, nullptr}, nullptr, 2.0).value, 0.0, 1e-6);
    EXPECT_NEAR(least_squares_scale(half, t, nullptr), 2.0, 1e-6);
}

TEST(NetError, ConsistencyTestPassesTheTruthAndFailsAnOffsetBin) {
    const Image t = truth_map();
    const NoisyReference ref = noisy_reference(t, 8, 0.05, 11);
    const ConsistencyTest same = consistency_test(t, ref.maps(), nullptr);
    EXPECT_TRUE(same.tested);
    EXPECT_TRUE(same.consistent) << "worst t " << same.worst_t << " threshold " << same.threshold;
    EXPECT_EQ(same.bins_tested, kSize * kSize);
    Image off = t;
    off.at(10, 10) += 1.0f;   // 1.0 against se ~ 0.05 / sqrt(8): t ~ 57
    const ConsistencyTest bad = consistency_test(off, ref.maps(), nullptr);
    EXPECT_FALSE(bad.consistent);
    EXPECT_EQ(bad.bins_failed, 1);
    EXPECT_FALSE(consistency_test(t, TruthMaps{&t, nullptr, nullptr}, nullptr).tested);
}
