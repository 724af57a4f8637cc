// compare_images against hand-computed values (harness/run/metrics.hpp, docs/design.md section 6).
#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/run/metrics.hpp>

using namespace caustics;

namespace {

Image ramp(int w, int h) {
    Image im(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) im.at(x, y) = 1.0f + 0.1f * static_cast<float>(x) + 0.05f * static_cast<float>(y * y % 7);
    return im;
}

}  // namespace

TEST(Metrics, IdenticalImages) {
    const Image r = ramp(32, 24);
    const ErrorMetrics e = compare_images(r, r, false);
    EXPECT_EQ(e.samples, 32 * 24);
    EXPECT_EQ(e.nonfinite, 0);
    EXPECT_DOUBLE_EQ(e.nrmse, 0.0);
    EXPECT_DOUBLE_EQ(e.relmse, 0.0);
    EXPECT_TRUE(std::isinf(e.psnr) && e.psnr > 0);
    EXPECT_NEAR(e.ssim, 1.0, 1e-12);
    EXPECT_FALSE(e.fitted);
}

TEST(Metrics, KnownOffset) {
    // r = 2 everywhere, m = r + 0.5: mse = 0.25, nrmse = 0.5 / 2, relmse = 0.25 / (4 + (0.02)^2),
    // psnr = 10 log10(4 / 0.25).
    const Image r(16, 16, 1, 2.0f);
    const Image m(16, 16, 1, 2.5f);
    const ErrorMetrics e = compare_images(m, r, false);
    EXPECT_NEAR(e.nrmse, 0.25, 1e-12);
    EXPECT_NEAR(e.relmse, 0.25 / (4.0 + 0.02 * 0.02), 1e-12);
    EXPECT_NEAR(e.psnr, 10.0 * std::log10(16.0), 1e-9);
    // Constant maps normalised by mean(r) = 2: x = 1.25, y = 1, no variance; L = max(r)/mean(r) = 1.
    const double c1 = 0.01 * 0.01;
    EXPECT_NEAR(e.ssim, (2 * 1.25 + c1) / (1.25 * 1.25 + 1.0 + c1), 1e-9);
}

TEST(Metrics, TwoValueHandComputed) {
    // r = {1, 3}, m = {2, 3}: mean r = 2, mse = 0.5, nrmse = sqrt(0.5)/2; eps = 0.02^2;
    // relmse = (1/(1+eps) + 0) / 2; psnr = 10 log10(9 / 0.5).
    Image r(2, 1, 1), m(2, 1, 1);
    r.pixels = {1.0f, 3.0f};
    m.pixels = {2.0f, 3.0f};
    const ErrorMetrics e = compare_images(m, r, false);
    EXPECT_NEAR(e.nrmse, std::sqrt(0.5) / 2.0, 1e-12);
    EXPECT_NEAR(e.relmse, 0.5 / (1.0 + 0.0004), 1e-12);
    EXPECT_NEAR(e.psnr, 10.0 * std::log10(18.0), 1e-9);
}

TEST(Metrics, FitRecoversKnownScale) {
    const Image r = ramp(20, 20);
    Image m = r;
    for (float& v : m.pixels) v *= 0.25f;   // a relative method off by a factor 4
    const ErrorMetrics e = compare_images(m, r, true);
    EXPECT_TRUE(e.fitted);
    EXPECT_NEAR(e.fit_scale, 4.0, 1e-5);
    EXPECT_NEAR(e.nrmse_fit, 0.0, 1e-6);
    EXPECT_GT(e.nrmse, 0.5);   // the unfitted error is still reported
    // Not asked: no fit.
    EXPECT_FALSE(compare_images(m, r, false).fitted);
}

TEST(Metrics, NonFiniteCountedAndExcluded) {
    const Image r(8, 8, 1, 1.0f);
    Image m(8, 8, 1, 1.0f);
    m.at(1, 1) = std::numeric_limits<float>::quiet_NaN();
    m.at(2, 5) = std::numeric_limits<float>::infinity();
    m.at(7, 7) = -std::numeric_limits<float>::infinity();
    const ErrorMetrics e = compare_images(m, r, true);
    EXPECT_EQ(e.nonfinite, 3);
    EXPECT_EQ(e.samples, 64 - 3);
    EXPECT_DOUBLE_EQ(e.nrmse, 0.0);   // the remaining pixels are exact
    EXPECT_TRUE(std::isfinite(e.ssim));
    EXPECT_TRUE(std::isfinite(e.fit_scale));
    EXPECT_NEAR(e.fit_scale, 1.0, 1e-12);
}

TEST(Metrics, MaskSelectsPixels) {
    // Outside the mask the method is wildly wrong; inside it is off by exactly +1 on r = 4.
    const Image r(10, 10, 1, 4.0f);
    Image m(10, 10, 1, 1000.0f);
    std::vector<std::uint8_t> mask(100, 0);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 5; ++x) {
            mask[static_cast<std::size_t>(y) * 10 + x] = 1;
            m.at(x, y) = 5.0f;
        }
    const ErrorMetrics e = compare_images(m, r, false, &mask);
    EXPECT_EQ(e.samples, 50);
    EXPECT_NEAR(e.nrmse, 0.25, 1e-12);
    // A masked-out NaN is not counted: only compared pixels count.
    m.at(9, 9) = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(compare_images(m, r, false, &mask).nonfinite, 0);
}

TEST(Metrics, SsimDropsWithNoise) {
    const Image r = ramp(40, 40);
    Image m = r;
    for (std::size_t i = 0; i < m.pixels.size(); ++i) m.pixels[i] += (i % 2 ? 0.3f : -0.3f);
    const ErrorMetrics e = compare_images(m, r, false);
    EXPECT_LT(e.ssim, 0.9);
    EXPECT_GT(e.ssim, -1.0);
}

TEST(Metrics, SizeMismatchThrows) {
    EXPECT_THROW(compare_images(Image(4, 4), Image(4, 5), false), std::invalid_argument);
    std::vector<std::uint8_t> mask(3, 1);
    EXPECT_THROW(compare_images(Image(4, 4), Image(4, 4), false, &mask), std::invalid_argument);
}
