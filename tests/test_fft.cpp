// Tests of the FFTW wrapper (harness/fft): fast sizes, transforms against a naive DFT, fused passes.
#include <cmath>
#include <complex>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/blocks/fft/fft.hpp>
#include "naive_dft.hpp"

namespace caustics {
namespace {

using test_support::naive_dft;

TEST(Fft, FastSizes) {
    EXPECT_TRUE(is_fast_fft_size(1024));
    EXPECT_TRUE(is_fast_fft_size(1000));
    EXPECT_TRUE(is_fast_fft_size(2 * 3 * 5 * 7 * 7));
    EXPECT_FALSE(is_fast_fft_size(1031));
    EXPECT_FALSE(is_fast_fft_size(22));
    EXPECT_EQ(next_fast_fft_size(1025), 1029);
    EXPECT_EQ(next_fast_fft_size(11), 12);
    const std::vector<int> s = fast_fft_sizes(10, 16);
    EXPECT_EQ(s, (std::vector<int>{10, 12, 14, 15, 16}));
}


class FftSizes : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(FftSizes, MatchesNaiveDftBothWays) {
    const auto [nx, ny] = GetParam();
    std::mt19937 rng(7);
    std::normal_distribution<double> g;
    std::vector<std::complex<double>> a(static_cast<std::size_t>(nx) * ny);
    ComplexBuffer buf(a.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
        a[k] = {g(rng), g(rng)};
        buf[k] = ComplexF(static_cast<float>(a[k].real()), static_cast<float>(a[k].imag()));
        a[k] = {buf[k].real(), buf[k].imag()};
    }
    Fft2D fft(nx, ny, FftRigor::Estimate);
    fft.forward(buf.data());
    const auto expect = naive_dft(a, nx, ny, -1);
    double err = 0.0, norm = 0.0;
    for (std::size_t k = 0; k < a.size(); ++k) {
        err = std::max(err, std::abs(std::complex<double>(buf[k].real(), buf[k].imag()) - expect[k]));
        norm = std::max(norm, std::abs(expect[k]));
    }
    EXPECT_LT(err / norm, 1e-5);
    fft.inverse(buf.data());
    double back = 0.0;
    for (std::size_t k = 0; k < a.size(); ++k)
        back = std::max(back, std::abs(std::complex<double>(buf[k].real(), buf[k].imag()) / double(a.size()) - a[k]));
    EXPECT_LT(back, 1e-5);
}

// 24 x 20: one serial 2-D plan; 160 x 128 and 135 x 125: batched rows and columns, odd sizes with
// tail batches.
INSTANTIATE_TEST_SUITE_P(Sizes, FftSizes,
                         ::testing::Values(std::make_pair(24, 20), std::make_pair(160, 128),
                                           std::make_pair(135, 125)));

// The fused entry points run the same plans as forward() / inverse(): bit-identical results, whether
// the input is written by the row hook and the result read by the column hook or not.
TEST_P(FftSizes, FusedPassesMatchPlainTransforms) {
    const auto [nx, ny] = GetParam();
    const std::size_t n = static_cast<std::size_t>(nx) * ny;
    std::mt19937 rng(11);
    std::normal_distribution<float> g;
    std::vector<ComplexF> input(n);
    for (ComplexF& v : input) v = {g(rng), g(rng)};
    Fft2D fft(nx, ny, FftRigor::Estimate);
    ComplexBuffer plain(n), fused(n);
    std::copy(input.begin(), input.end(), plain.data());
    fft.forward(plain.data());
    fft.forward_fused(fused.data(), [&](int y0, int y1, ComplexF* rows) {
        std::copy_n(input.data() + static_cast<std::size_t>(y0) * nx, static_cast<std::size_t>(y1 - y0) * nx, rows);
    });
    for (std::size_t k = 0; k < n; ++k) ASSERT_EQ(plain[k], fused[k]) << k;
    std::copy(input.begin(), input.end(), plain.data());
    fft.inverse(plain.data());
    std::vector<ComplexF> collected(n, ComplexF(-1.0f, -1.0f));
    std::vector<int> seen(static_cast<std::size_t>(nx), 0);
    fft.inverse_fused(
        fused.data(),
        [&](int y0, int y1, ComplexF* rows) {
            std::copy_n(input.data() + static_cast<std::size_t>(y0) * nx, static_cast<std::size_t>(y1 - y0) * nx, rows);
        },
        [&](int x0, int width, const ComplexF* block) {
            for (int y = 0; y < ny; ++y)
                for (int i = 0; i < width; ++i) collected[static_cast<std::size_t>(y) * nx + x0 + i] = block[y * width + i];
            for (int i = 0; i < width; ++i) ++seen[static_cast<std::size_t>(x0 + i)];
        });
    for (int s : seen) ASSERT_EQ(s, 1);
    for (std::size_t k = 0; k < n; ++k) ASSERT_EQ(plain[k], collected[k]) << k;
}

}  // namespace
}  // namespace caustics
