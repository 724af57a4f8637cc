#include "timing.hpp"

#include <algorithm>
#include <cmath>

namespace caustics {

TimingSummary summarize_ms(std::vector<double> samples) {
    TimingSummary s;
    s.samples = static_cast<int>(samples.size());
    if (samples.empty()) return s;
    std::sort(samples.begin(), samples.end());
    const std::size_t n = samples.size();
    s.min = samples.front();
    s.median = n % 2 ? samples[n / 2] : 0.5 * (samples[n / 2 - 1] + samples[n / 2]);
    // Nearest-rank 90th percentile.
    std::size_t rank = static_cast<std::size_t>(std::ceil(0.9 * static_cast<double>(n)));
    s.p90 = samples[std::min(n, std::max<std::size_t>(rank, 1)) - 1];
    return s;
}

}  // namespace caustics
