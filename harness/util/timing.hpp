#pragma once
// Timing helpers (docs/design.md section 6): monotonic clock, median / min / p90 and dispersion of repeats,
// and the rule that decides when enough repeats have been timed (nvbench's --max-noise / --min-time idea:
// repeat until the median is known to a relative precision, or a time cap).
#include <chrono>
#include <vector>

namespace caustics {

class Stopwatch {
public:
    Stopwatch() : start_(std::chrono::steady_clock::now()) {}
    double ms() const {
        return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
    }
    void reset() { start_ = std::chrono::steady_clock::now(); }

private:
    std::chrono::steady_clock::time_point start_;
};

struct TimingSummary {
    double median = 0.0, min = 0.0, p90 = 0.0;
    double stdev = 0.0;          // sample standard deviation
    double iqr = 0.0;            // interquartile range (linear interpolation of the quartiles)
    double ci_rel = 0.0;         // half-width of the median's 95 % order-statistic interval / median
    bool has_interval = false;   // enough samples (>= 6) for that interval
    int samples = 0;
};

TimingSummary summarize_ms(std::vector<double> samples);

// When to stop timing: at least `min_repeats`, then until the median's relative 95 % half-width is at
// most `precision`, or `max_seconds` of timed work, or `max_repeats`.
struct TimingPolicy {
    int min_repeats = 10;
    double precision = 0.05;
    double max_seconds = 3.0;
    int max_repeats = 10000;
};
enum class TimingStop { Continue, Precise, Capped };
TimingStop timing_stop(const std::vector<double>& samples, double timed_seconds, const TimingPolicy& policy);

}  // namespace caustics
