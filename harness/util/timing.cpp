#include <caustics/util/timing.hpp>

#include <algorithm>
#include <cmath>

#include <caustics/util/statistics.hpp>

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
    double mean = 0.0;
    for (double v : samples) mean += v / static_cast<double>(n);
    double sq = 0.0;
    for (double v : samples) sq += (v - mean) * (v - mean);
    s.stdev = n > 1 ? std::sqrt(sq / static_cast<double>(n - 1)) : 0.0;
    auto quantile = [&](double q) {
        const double pos = q * static_cast<double>(n - 1);
        const std::size_t i = static_cast<std::size_t>(pos);
        const double f = pos - static_cast<double>(i);
        return i + 1 < n ? samples[i] * (1.0 - f) + samples[i + 1] * f : samples[i];
    };
    s.iqr = quantile(0.75) - quantile(0.25);
    const MedianInterval ci = median_interval(samples, 0.95);
    s.has_interval = ci.has_interval;
    s.ci_rel = ci.has_interval && s.median > 0.0 ? 0.5 * (ci.hi - ci.lo) / s.median : 0.0;
    return s;
}

TimingStop timing_stop(const std::vector<double>& samples, double timed_seconds, const TimingPolicy& policy) {
    const int n = static_cast<int>(samples.size());
    if (n < std::max(1, policy.min_repeats)) return TimingStop::Continue;
    const TimingSummary s = summarize_ms(samples);
    if (s.has_interval && s.ci_rel <= policy.precision) return TimingStop::Precise;
    if (timed_seconds >= policy.max_seconds || n >= policy.max_repeats) return TimingStop::Capped;
    return TimingStop::Continue;
}

}  // namespace caustics
