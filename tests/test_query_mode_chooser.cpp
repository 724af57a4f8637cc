// The tracer's query-mode chooser (harness/frame/query_mode_chooser.hpp) on made-up timings: it tries
// every mode, then keeps the fastest, tries the others now and then, and follows a change. That every
// mode returns the same hits is tests/test_reference_bits.cpp's RayTracerBatches.
#include <array>
#include <map>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include <caustics/frame/query_mode_chooser.hpp>

using namespace caustics;

namespace {

constexpr std::size_t kRays = 512;

// Seconds per ray of each mode in the made-up machine.
using Costs = std::array<double, kQueryModes>;

// Picks and records `n` batches of `kind` with those costs; returns how often each mode was picked.
std::map<QueryMode, int> feed(QueryModeChooser& chooser, int kind, const Costs& costs, int n) {
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
    const auto warm = feed(chooser, 0, costs, kQueryModes * QueryModeChooser::kWarmUp);
    for (int m = 0; m < kQueryModes; ++m) EXPECT_EQ(warm.at(static_cast<QueryMode>(m)), QueryModeChooser::kWarmUp);
    const int n = 2 * static_cast<int>(QueryModeChooser::kExploreEvery) * (kQueryModes - 1);
    const auto later = feed(chooser, 0, costs, n);
    // All but one batch in kExploreEvery in the fastest mode; the others each tried.
    EXPECT_EQ(later.at(QueryMode::Packet8), n - n / static_cast<int>(QueryModeChooser::kExploreEvery));
    EXPECT_EQ(later.at(QueryMode::Single), 2);
    EXPECT_EQ(later.at(QueryMode::Packet16), 2);
}

TEST(QueryModeChooser, FollowsAChangeOfTheFastestMode) {
    QueryModeChooser chooser;
    feed(chooser, 1, {1e-9, 2e-9, 3e-9}, 100);
    EXPECT_EQ(chooser.current(1), QueryMode::Single);
    // Single rays become the slowest: their own average shows it within batches, and the next try of
    // 16-ray packets, now the fastest, moves the choice there (within two rounds of tries).
    const int n = 200, every = static_cast<int>(QueryModeChooser::kExploreEvery);
    const auto after = feed(chooser, 1, {5e-9, 2e-9, 1e-9}, n);
    EXPECT_GE(after.at(QueryMode::Packet16), n - 2 * every - 2 - n / every);
    EXPECT_EQ(chooser.current(1), QueryMode::Packet16);
}

TEST(QueryModeChooser, KindsAreTimedApart) {
    QueryModeChooser chooser;
    feed(chooser, QueryModeChooser::hit_kind(0), {3e-9, 2e-9, 1e-9}, 50);
    feed(chooser, QueryModeChooser::hit_kind(1), {1e-9, 2e-9, 3e-9}, 50);
    feed(chooser, QueryModeChooser::kVisibility, {2e-9, 1e-9, 3e-9}, 50);
    EXPECT_EQ(chooser.current(QueryModeChooser::hit_kind(0)), QueryMode::Packet16);
    EXPECT_EQ(chooser.current(QueryModeChooser::hit_kind(1)), QueryMode::Single);
    EXPECT_EQ(chooser.current(QueryModeChooser::kVisibility), QueryMode::Packet8);
    // Segments from the fourth on share one kind, below the visibility queries'.
    EXPECT_EQ(QueryModeChooser::hit_kind(3), QueryModeChooser::hit_kind(40));
    EXPECT_LT(QueryModeChooser::hit_kind(40), QueryModeChooser::kVisibility);
}

TEST(QueryModeChooser, SmallBatchesUseTheFastestAndAreNotTimed) {
    QueryModeChooser chooser;
    const std::size_t small = QueryModeChooser::kMinRays - 1;
    // Before any timing: 16-ray packets.
    EXPECT_EQ(chooser.pick(2, small), QueryMode::Packet16);
    feed(chooser, 2, {1e-9, 2e-9, 3e-9}, 20);
    for (int i = 0; i < 100; ++i) {
        ASSERT_EQ(chooser.pick(2, small), QueryMode::Single);   // no exploration
        chooser.record(2, QueryMode::Single, small, 1.0);      // a huge time that must be ignored
    }
    EXPECT_EQ(chooser.current(2), QueryMode::Single);
}

TEST(QueryModeChooser, TriesEveryOtherModeWhileTheFastestChanges) {
    // 8- and 16-ray packets take turns at being the fastest (each try of the other is faster than the
    // mode in use): single rays must still get their tries.
    QueryModeChooser chooser;
    feed(chooser, 0, {3e-9, 2e-9, 2e-9}, kQueryModes * QueryModeChooser::kWarmUp);
    int single = 0;
    double packets = 2e-9;
    for (int i = 0; i < 8 * static_cast<int>(QueryModeChooser::kExploreEvery); ++i) {
        const QueryMode mode = chooser.pick(0, kRays);
        if (mode == QueryMode::Single) ++single;
        const bool tried = mode != chooser.current(0);
        if (tried && mode != QueryMode::Single) packets *= 0.9;   // the other packet width, a little faster
        chooser.record(0, mode, kRays, (mode == QueryMode::Single ? 3e-9 : tried ? packets : packets / 0.9) * kRays);
    }
    EXPECT_GE(single, 3);
}

TEST(QueryModeChooser, OneSlowBatchDoesNotMoveTheChoice) {
    QueryModeChooser chooser;
    feed(chooser, 0, {1e-9, 2e-9, 3e-9}, 20);
    ASSERT_EQ(chooser.current(0), QueryMode::Single);
    // A batch of the mode in use at 2.5x its time (the machine busy elsewhere): averaged, not taken.
    chooser.record(0, QueryMode::Single, kRays, 2.5e-9 * kRays);
    EXPECT_EQ(chooser.current(0), QueryMode::Single);
    // A tried mode is judged by its latest batch alone.
    chooser.record(0, QueryMode::Packet16, kRays, 0.5e-9 * kRays);
    EXPECT_EQ(chooser.current(0), QueryMode::Packet16);
}

TEST(QueryModeChooser, RunUsesThePinnedModeOrTimesItsChoice) {
    QueryModeChooser chooser;
    std::vector<QueryMode> modes;
    auto query = [&](QueryMode mode) { modes.push_back(mode); };
    for (int i = 0; i < 6; ++i) chooser.run(0, kRays, std::nullopt, query);
    // Each mode twice, in order: run() recorded every batch (without it, the warm-up never ends).
    const std::vector<QueryMode> warm = {QueryMode::Single,  QueryMode::Single,   QueryMode::Packet8,
                                         QueryMode::Packet8, QueryMode::Packet16, QueryMode::Packet16};
    EXPECT_EQ(modes, warm);
    modes.clear();
    for (int i = 0; i < 100; ++i) chooser.run(1, kRays, QueryMode::Packet8, query);
    EXPECT_EQ(modes, std::vector<QueryMode>(100, QueryMode::Packet8));
    EXPECT_EQ(chooser.current(1), QueryMode::Packet16);   // pinned batches are not timed
}
