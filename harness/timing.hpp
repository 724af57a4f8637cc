#pragma once
// Timing helpers (DESIGN.md section 6): monotonic clock, median / min / p90 of repeats.
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
    int samples = 0;
};

TimingSummary summarize_ms(std::vector<double> samples);

}  // namespace caustics
