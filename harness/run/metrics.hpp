#pragma once
// Error metrics against the reference (docs/design.md section 6).
//   nrmse  = sqrt(mean((m - r)^2)) / mean(r)
//   relmse = mean((m - r)^2 / (r^2 + eps)),  eps = (0.01 mean(r))^2
//   psnr   = 10 log10(max(r)^2 / mean((m - r)^2))
//   ssim   on maps normalised by mean(r) (8x8 windows, Gaussian weights, Wang et al. 2004 constants)
// For non-radiometric methods also nrmse_fit with the least-squares scale fit_scale = <m, r> / <m, m>.
#include <cstdint>
#include <vector>

#include <caustics/util/image.hpp>

namespace caustics {

struct ErrorMetrics {
    double nrmse = 0.0;
    double relmse = 0.0;
    double psnr = 0.0;
    double ssim = 0.0;
    bool fitted = false;        // nrmse_fit / fit_scale are meaningful
    double nrmse_fit = 0.0;
    double fit_scale = 1.0;
    std::int64_t samples = 0;   // pixels compared
    std::int64_t nonfinite = 0; // non-finite method values (never averaged in)
};

// `mask` (optional, same size) selects the pixels to compare. Single-channel images of equal size.
ErrorMetrics compare_images(const Image& method, const Image& reference, bool fit_scale,
                            const std::vector<std::uint8_t>* mask = nullptr);

}  // namespace caustics
