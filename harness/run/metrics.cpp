#include <caustics/run/metrics.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace caustics {
namespace {

constexpr int kWindow = 8;              // SSIM window (Wang et al. 2004 use 11x11; the design says 8x8)
constexpr double kSigma = 1.5;          // Gaussian weights, Wang et al. 2004
constexpr double kK1 = 0.01, kK2 = 0.03;

std::array<double, kWindow> gaussian_weights() {
    std::array<double, kWindow> w{};
    double sum = 0.0;
    const double c = 0.5 * (kWindow - 1);
    for (int i = 0; i < kWindow; ++i) {
        w[i] = std::exp(-0.5 * (i - c) * (i - c) / (kSigma * kSigma));
        sum += w[i];
    }
    for (double& v : w) v /= sum;
    return w;
}

double ssim_from_moments(double mx, double my, double vx, double vy, double cxy, double c1, double c2) {
    return ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
}

// SSIM of x and y (already normalised) over every 8x8 window whose pixels are all valid; Gaussian
// weights are separable, so the windowed moments come from two 1-D passes. When no full window fits
// (tiny or sparse masks) the global statistics of the valid pixels give a single SSIM value.
double ssim(const std::vector<double>& x, const std::vector<double>& y, const std::vector<std::uint8_t>& valid,
            int w, int h, double dynamic_range) {
    const double c1 = (kK1 * dynamic_range) * (kK1 * dynamic_range);
    const double c2 = (kK2 * dynamic_range) * (kK2 * dynamic_range);
    const std::size_t n = static_cast<std::size_t>(w) * h;

    // Prefix sums of invalid pixels: a window is usable when it contains none.
    std::vector<int> bad(static_cast<std::size_t>(w + 1) * (h + 1), 0);
    auto B = [&](int i, int j) -> int& { return bad[static_cast<std::size_t>(j) * (w + 1) + i]; };
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            B(i + 1, j + 1) = B(i, j + 1) + B(i + 1, j) - B(i, j) + (valid[static_cast<std::size_t>(j) * w + i] ? 0 : 1);

    double total = 0.0;
    std::int64_t windows = 0;
    if (w >= kWindow && h >= kWindow) {
        const auto g = gaussian_weights();
        const int ow = w - kWindow + 1, oh = h - kWindow + 1;
        // Horizontal pass of the five moment images, then vertical pass per output window.
        std::array<std::vector<double>, 5> hp;
        for (auto& v : hp) v.assign(static_cast<std::size_t>(ow) * h, 0.0);
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < ow; ++i) {
                double s[5] = {0, 0, 0, 0, 0};
                for (int k = 0; k < kWindow; ++k) {
                    const std::size_t p = static_cast<std::size_t>(j) * w + i + k;
                    const double a = x[p], b = y[p];
                    s[0] += g[k] * a; s[1] += g[k] * b; s[2] += g[k] * a * a;
                    s[3] += g[k] * b * b; s[4] += g[k] * a * b;
                }
                for (int m = 0; m < 5; ++m) hp[m][static_cast<std::size_t>(j) * ow + i] = s[m];
            }
        for (int j = 0; j < oh; ++j)
            for (int i = 0; i < ow; ++i) {
                if (B(i + kWindow, j + kWindow) - B(i, j + kWindow) - B(i + kWindow, j) + B(i, j) != 0) continue;
                double s[5] = {0, 0, 0, 0, 0};
                for (int k = 0; k < kWindow; ++k)
                    for (int m = 0; m < 5; ++m) s[m] += g[k] * hp[m][static_cast<std::size_t>(j + k) * ow + i];
                const double vx = std::max(0.0, s[2] - s[0] * s[0]);
                const double vy = std::max(0.0, s[3] - s[1] * s[1]);
                total += ssim_from_moments(s[0], s[1], vx, vy, s[4] - s[0] * s[1], c1, c2);
                ++windows;
            }
    }
    if (windows > 0) return total / static_cast<double>(windows);

    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    std::int64_t count = 0;
    for (std::size_t p = 0; p < n; ++p) {
        if (!valid[p]) continue;
        sx += x[p]; sy += y[p]; sxx += x[p] * x[p]; syy += y[p] * y[p]; sxy += x[p] * y[p];
        ++count;
    }
    if (count == 0) return std::numeric_limits<double>::quiet_NaN();
    const double k = 1.0 / static_cast<double>(count);
    const double mx = sx * k, my = sy * k;
    return ssim_from_moments(mx, my, std::max(0.0, sxx * k - mx * mx), std::max(0.0, syy * k - my * my),
                             sxy * k - mx * my, c1, c2);
}

}  // namespace

ErrorMetrics compare_images(const Image& method, const Image& reference, bool fit_scale,
                            const std::vector<std::uint8_t>* mask) {
    if (method.width != reference.width || method.height != reference.height || method.channels != 1 ||
        reference.channels != 1)
        throw std::invalid_argument("compare_images: expected single-channel images of equal size (method " +
                                    std::to_string(method.width) + "x" + std::to_string(method.height) + "x" +
                                    std::to_string(method.channels) + ", reference " +
                                    std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                                    "x" + std::to_string(reference.channels) + ")");
    const int w = reference.width, h = reference.height;
    const std::size_t n = static_cast<std::size_t>(w) * h;
    if (mask && mask->size() != n) throw std::invalid_argument("compare_images: mask size differs from the images");

    ErrorMetrics e;
    std::vector<std::uint8_t> valid(n, 0);
    double sum_r = 0.0, max_r = 0.0;
    for (std::size_t p = 0; p < n; ++p) {
        if (mask && !(*mask)[p]) continue;
        const double r = reference.pixels[p];
        if (!std::isfinite(r)) continue;   // a reference never holds these; skip rather than poison the sums
        if (!std::isfinite(static_cast<double>(method.pixels[p]))) {
            ++e.nonfinite;
            continue;
        }
        valid[p] = 1;
        ++e.samples;
        sum_r += r;
        max_r = std::max(max_r, r);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    if (e.samples == 0) {
        e.nrmse = e.relmse = e.psnr = e.ssim = nan;
        e.fitted = fit_scale;
        e.nrmse_fit = fit_scale ? nan : 0.0;
        return e;
    }
    const double count = static_cast<double>(e.samples);
    const double mean_r = sum_r / count;
    // eps keeps relmse finite where the reference is dark; the floor only matters for an all-zero reference.
    const double eps = std::max((0.01 * mean_r) * (0.01 * mean_r), std::numeric_limits<double>::min());

    double sse = 0.0, rel = 0.0, mm = 0.0, mr = 0.0;
    for (std::size_t p = 0; p < n; ++p) {
        if (!valid[p]) continue;
        const double m = method.pixels[p], r = reference.pixels[p];
        const double d = m - r;
        sse += d * d;
        rel += d * d / (r * r + eps);
        mm += m * m;
        mr += m * r;
    }
    const double mse = sse / count;
    e.nrmse = mean_r > 0.0 ? std::sqrt(mse) / mean_r : (mse == 0.0 ? 0.0 : std::numeric_limits<double>::infinity());
    e.relmse = rel / count;
    e.psnr = mse > 0.0 ? 10.0 * std::log10(max_r * max_r / mse) : std::numeric_limits<double>::infinity();

    // SSIM on maps normalised by mean(r); the dynamic range is the normalised reference peak.
    const double norm = mean_r > 0.0 ? 1.0 / mean_r : 1.0;
    std::vector<double> x(n, 0.0), y(n, 0.0);
    for (std::size_t p = 0; p < n; ++p)
        if (valid[p]) {
            x[p] = method.pixels[p] * norm;
            y[p] = reference.pixels[p] * norm;
        }
    const double range = max_r > 0.0 ? max_r * norm : 1.0;
    e.ssim = ssim(x, y, valid, w, h, range);

    if (fit_scale) {
        e.fitted = true;
        // Least squares: argmin_s sum (s m - r)^2 = <m, r> / <m, m>; an all-zero method keeps scale 1.
        e.fit_scale = mm > 0.0 ? mr / mm : 1.0;
        double sse_fit = 0.0;
        for (std::size_t p = 0; p < n; ++p) {
            if (!valid[p]) continue;
            const double d = e.fit_scale * method.pixels[p] - reference.pixels[p];
            sse_fit += d * d;
        }
        const double mse_fit = sse_fit / count;
        e.nrmse_fit = mean_r > 0.0 ? std::sqrt(mse_fit) / mean_r
                                   : (mse_fit == 0.0 ? 0.0 : std::numeric_limits<double>::infinity());
    }
    return e;
}

}  // namespace caustics
