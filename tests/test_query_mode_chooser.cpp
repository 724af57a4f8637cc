// The tracer's query-mode chooser (harness/frame/query_mode_chooser.hpp) on made-up timings: it tries
// every mode, then keeps the fastest, tries the others now and then, and follows a change. That every
// mode returns the same hits is tests/test_reference_bits.cpp's RayTracerBatches.
#include <array>
#include <map>

#include <gtest/gtest.h>

#include <caustics/frame/query_mode_chooser.hpp>

using namespace caustics;

namespace {

constexpr std::size_t kRays = 512;

// Seconds per ray of each mode in the made-up machine.
using Costs = std::array<double, kQueryModes>;

// Picks and records `n` batches of `kind` with those costs; returns how often each mode was picked.
std::map<QueryMode, int> run(QueryModeChooser& chooser, int kind, const Costs& costs, int n) {
    std::map<QueryMode, int> picked;
    for (int i = 0; i < n; ++i) {
        const QueryMode mode = chooser.pick(kind, kRays);
        ++picked[mode];
        chooser.record(kind, mode, kRays, costs[static_cast<std::size_t>(mode)] * kRays);
    }
    return picked;
}

}  // namespace

TEST(QueryModeChooser, TriesEveryModeThenKeepsTheFastest) {
    QueryModeChooser chooser;
    const Costs costs = {2e-9, 1e-9, 3e-9};   // 8-ray packets fastest
    const auto warm = run(chooser, 0, costs, kQueryModes * QueryModeChooser::kWarmUp);
    for (int m = 0; m < kQueryModes; ++m) EXPECT_EQ(warm.at(static_cast<QueryMode>(m)), QueryModeChooser::kWarmUp);
    const int n = 2 * static_cast<int>(QueryModeChooser::kExploreEvery) * (kQueryModes - 1);
    const auto later = run(chooser, 0, costs, n);
    // All but one batch in kExploreEvery in the fastest mode; the others each tried.
    EXPECT_EQ(later.at(QueryMode::Packet8), n - n / static_cast<int>(QueryModeChooser::kExploreEvery));
    EXPECT_EQ(later.at(QueryMode::Single), 2);
    EXPECT_EQ(later.at(QueryMode::Packet16), 2);
}

TEST(QueryModeChooser, FollowsAChangeOfTheFastestMode) {
    QueryModeChooser chooser;
    run(chooser, 1, {1e-9, 2e-9, 3e-9}, 100);
    EXPECT_EQ(chooser.pick(1, kRays), QueryMode::Single);
    // Single rays become the slowest: their own average shows it within batches, and the next try of
    // 16-ray packets, now the fastest, moves the choice there (within two rounds of tries).
    const int n = 200, every = static_cast<int>(QueryModeChooser::kExploreEvery);
    const auto after = run(chooser, 1, {5e-9, 2e-9, 1e-9}, n);
    EXPECT_GE(after.at(QueryMode::Packet16), n - 2 * every - 2 - n / every);
    int last = 0;
    for (int i = 0; i < 31; ++i) last += chooser.pick(1, kRays) == QueryMode::Packet16 ? 1 : 0;
    EXPECT_GE(last, 30);
}

TEST(QueryModeChooser, KindsAreTimedApart) {
    QueryModeChooser chooser;
    run(chooser, QueryModeChooser::hit_kind(0), {3e-9, 2e-9, 1e-9}, 50);
    run(chooser, QueryModeChooser::hit_kind(1), {1e-9, 2e-9, 3e-9}, 50);
    run(chooser, QueryModeChooser::kVisibility, {2e-9, 1e-9, 3e-9}, 50);
    EXPECT_EQ(chooser.pick(QueryModeChooser::hit_kind(0), kRays), QueryMode::Packet16);
    EXPECT_EQ(chooser.pick(QueryModeChooser::hit_kind(1), kRays), QueryMode::Single);
    EXPECT_EQ(chooser.pick(QueryModeChooser::kVisibility, kRays), QueryMode::Packet8);
    // Segments from the fourth on share one kind, below the visibility queries'.
    EXPECT_EQ(QueryModeChooser::hit_kind(3), QueryModeChooser::hit_kind(40));
    EXPECT_LT(QueryModeChooser::hit_kind(40), QueryModeChooser::kVisibility);
}

TEST(QueryModeChooser, SmallBatchesUseTheFastestAndAreNotTimed) {
    QueryModeChooser chooser;
    const std::size_t small = QueryModeChooser::kMinRays - 1;
    // Before any timing: 16-ray packets.
    EXPECT_EQ(chooser.pick(2, small), QueryMode::Packet16);
    run(chooser, 2, {1e-9, 2e-9, 3e-9}, 20);
    for (int i = 0; i < 100; ++i) {
        ASSERT_EQ(chooser.pick(2, small), QueryMode::Single);   // no exploration
        chooser.record(2, QueryMode::Single, small, 1.0);      // a huge time that must be ignored
    }
    EXPECT_EQ(chooser.pick(2, kRays), QueryMode::Single);
}

TEST(QueryModeChooser, RunTimesTheQueryItRuns) {
    QueryModeChooser chooser;
    int calls = 0;
    for (int i = 0; i < 10; ++i)
        chooser.run(0, kRays, [&](QueryMode mode) {
            ++calls;
            EXPECT_LE(static_cast<int>(mode), kQueryModes - 1);
        });
    EXPECT_EQ(calls, 10);
}
