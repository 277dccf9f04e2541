// The budget search of Table 6.2 (bench gpu_pm --budget) on cost curves with a known answer:
// exact lines, a curve, an unreachable budget, and timings spoilt by a loaded machine.
#include "shared/budget_search.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace ag {

namespace {

// A frame's time on a loaded machine: the true cost × a load that drifts between probes (1 to
// 1.3), ±10% jitter, and in one frame of five a stall of up to the cost again (another process
// had the core). The bench passes the median of
// its frames, so this does too.
struct LoadedClock {
    std::mt19937 rng;
    double unit() { return double(rng() >> 8) * 0x1p-24; }
    double median_of(int frames, double cost) {
        std::vector<double> t;
        const double load = 1.0 + 0.3 * unit();  // the load drifts between probes
        for (int f = 0; f < frames; ++f) {
            double ms = load * cost * (1.0 + 0.2 * (unit() - 0.5));
            if (unit() < 0.2) ms += cost * unit();
            t.push_back(ms);
        }
        std::sort(t.begin(), t.end());
        return t[t.size() / 2];
    }
};

}  // namespace

TEST(BudgetSearch, ExactLineIsHitOnTheThirdProbeAndConfirmed) {
    BudgetSearch s;
    s.budget_ms = 20.0;
    const BudgetResult r = search_budget(s, [](int n) { return 5.0 + 0.01 * n; });
    EXPECT_TRUE(r.held);
    EXPECT_EQ(r.count, 1500);
    EXPECT_EQ(r.probes.size(), 4u);  // 250, 4000, 1500 and 1500 again
    EXPECT_NEAR(r.ms_per_count, 0.01, 1e-9);
    EXPECT_NEAR(r.fixed_ms, 5.0, 1e-6);
}

// Curvature (a cost that grows faster than the paths, e.g. tile lists that lengthen) moves the
// first line's answer off; the later probes near the budget correct it.
TEST(BudgetSearch, CurvedCostIsHeldWithinTheTolerance) {
    BudgetSearch s;
    s.budget_ms = 20.0;
    s.tolerance = 0.02;
    auto cost = [](int n) { return 2.0 + 0.004 * n + 2e-6 * double(n) * n; };
    const BudgetResult r = search_budget(s, cost);
    EXPECT_TRUE(r.held);
    EXPECT_NEAR(cost(r.count), 20.0, 0.4);  // the root is n ≈ 2162
    EXPECT_EQ(r.count % 25, 0);
    EXPECT_LE(r.probes.size(), 2u + size_t(s.rounds));
}

// Over 200 runs on a loaded machine (the load drifting between probes by up to 30%, stalls
// within them) 179 searches time one count twice within ±10% of the budget (the other 21 give up
// after 12 probes and report it), and the true cost of the count lies where that load allows
// (20 ms / 1.3 − 10% … 20 ms + 10%). One line through the first two probes (as bench gpu_pm
// --budget did before) misses the ±10% on 76 of these 200 when its answer is timed.
TEST(BudgetSearch, HoldsThroughALoadedMachinesTimings) {
    BudgetSearch s;
    s.budget_ms = 20.0;
    auto cost = [](int n) { return 5.0 + 0.01 * n; };
    int held = 0, plausible = 0, one_line_misses = 0;
    for (uint32_t seed = 1; seed <= 200; ++seed) {
        LoadedClock clock{std::mt19937(seed)};
        const BudgetResult r = search_budget(s, [&](int n) { return clock.median_of(9, cost(n)); });
        held += r.held;
        plausible += cost(r.count) >= 0.9 * 20.0 / 1.3 && cost(r.count) <= 1.1 * 20.0;
        EXPECT_EQ(r.count % 25, 0);
        EXPECT_LE(r.probes.size(), 12u);
        // The one-line search on the same first two probes.
        const double slope = (r.probes[1].ms - r.probes[0].ms) / (r.probes[1].count - 250);
        const double one_line = 250 + (20.0 - r.probes[0].ms) / slope;
        one_line_misses += std::abs(clock.median_of(9, cost(int(one_line))) - 20.0) > 2.0;
    }
    EXPECT_GE(held, 170);  // 179: the rest give up after 12 probes and say so
    EXPECT_GE(plausible, 195);
    EXPECT_GE(one_line_misses, 40);
}

TEST(BudgetSearch, AnUnreachableBudgetIsReportedNotHeld) {
    BudgetSearch s;
    s.budget_ms = 20.0;
    int probes = 0;
    const BudgetResult r = search_budget(s, [&](int n) {
        ++probes;
        return 30.0 + 0.01 * n;  // the fixed cost alone is over the budget
    });
    EXPECT_FALSE(r.held);
    EXPECT_EQ(r.count, s.min_count);
    EXPECT_NEAR(r.ms, 30.5, 1e-9);
    EXPECT_LE(probes, 4);  // stops at the clamp instead of probing it again and again
}

}  // namespace ag
