#pragma once
// A progress bar on stderr for long computations (reference, sweeps). Silent for work that finishes
// within a second; then "label [=====>    ] done/total  rate/s  ETA", redrawn at most ~10 times a
// second on a terminal (every few seconds, one line each, when stderr is a file or pipe).
// advance() may be called from any thread.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace caustics {

class ProgressBar {
public:
    ProgressBar(std::string label, std::uint64_t total, bool enabled = true);
    ~ProgressBar();   // calls finish()
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;

    void advance(std::uint64_t n = 1);
    // Prints the final state (only if the bar was shown) and ends the line. Idempotent.
    void finish();

    std::uint64_t done() const { return done_.load(std::memory_order_relaxed); }

private:
    using Clock = std::chrono::steady_clock;
    void draw(std::uint64_t done, double elapsed, bool final);

    std::string label_;
    std::uint64_t total_;
    bool enabled_;
    bool tty_;
    Clock::time_point start_;
    std::atomic<std::uint64_t> done_{0};
    std::atomic<std::int64_t> next_draw_ns_;   // no redraw before this (since start)
    std::mutex draw_mutex_;
    bool shown_ = false;
    bool finished_ = false;
};

// "1.23 M", "456 k": compact counts for progress lines and logs.
std::string format_count(double n);

}  // namespace caustics
