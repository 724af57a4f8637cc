#include <caustics/util/progress.hpp>

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace caustics {

namespace {
constexpr std::int64_t kShowAfterNs = 1'000'000'000;     // silent for the first second
constexpr std::int64_t kTtyPeriodNs = 100'000'000;       // ~10 redraws a second on a terminal
constexpr std::int64_t kFilePeriodNs = 5'000'000'000;    // one line every 5 s into logs

std::string format_duration(double s) {
    char buf[32];
    if (!(s >= 0.0) || s > 1e7) return "--:--";
    const long total = static_cast<long>(s + 0.5);
    if (total >= 3600) std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", total / 3600, total / 60 % 60, total % 60);
    else std::snprintf(buf, sizeof buf, "%02ld:%02ld", total / 60, total % 60);
    return buf;
}
}  // namespace

std::string format_count(double n) {
    char buf[32];
    if (n >= 1e9) std::snprintf(buf, sizeof buf, "%.2f G", n / 1e9);
    else if (n >= 1e6) std::snprintf(buf, sizeof buf, "%.2f M", n / 1e6);
    else if (n >= 1e3) std::snprintf(buf, sizeof buf, "%.1f k", n / 1e3);
    else std::snprintf(buf, sizeof buf, "%.0f", n);
    return buf;
}

ProgressBar::ProgressBar(std::string label, std::uint64_t total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled), tty_(isatty(STDERR_FILENO) != 0),
      start_(Clock::now()), next_draw_ns_(kShowAfterNs) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::advance(std::uint64_t n) {
    const std::uint64_t done = done_.fetch_add(n, std::memory_order_relaxed) + n;
    if (!enabled_) return;
    const std::int64_t now =
        std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start_).count();
    std::int64_t due = next_draw_ns_.load(std::memory_order_relaxed);
    if (now < due) return;
    // One thread draws; the others carry on without waiting.
    if (!next_draw_ns_.compare_exchange_strong(due, now + (tty_ ? kTtyPeriodNs : kFilePeriodNs))) return;
    std::unique_lock<std::mutex> lock(draw_mutex_, std::try_to_lock);
    if (!lock.owns_lock() || finished_) return;
    draw(done, now * 1e-9, false);
}

void ProgressBar::finish() {
    std::lock_guard<std::mutex> lock(draw_mutex_);
    if (finished_) return;
    finished_ = true;
    if (!shown_) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    draw(done_.load(), elapsed, true);
}

void ProgressBar::draw(std::uint64_t done, double elapsed, bool final) {
    shown_ = true;
    const double fraction = total_ > 0 ? std::min(1.0, static_cast<double>(done) / total_) : 1.0;
    const double rate = elapsed > 0.0 ? done / elapsed : 0.0;
    const double eta = rate > 0.0 && total_ > done ? (total_ - done) / rate : 0.0;
    constexpr int kWidth = 28;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(kWidth, ' ');
    for (int i = 0; i < filled; ++i) bar[i] = '=';
    if (filled < kWidth) bar[filled] = '>';
    std::fprintf(stderr, "%s%s [%s] %s/%s  %s/s  %s %s%s", tty_ ? "\r" : "", label_.c_str(), bar.c_str(),
                 format_count(static_cast<double>(done)).c_str(),
                 format_count(static_cast<double>(total_)).c_str(), format_count(rate).c_str(),
                 final ? "in" : "ETA", format_duration(final ? elapsed : eta).c_str(),
                 (final || !tty_) ? "\n" : "\x1b[K");
    std::fflush(stderr);
}

}  // namespace caustics
