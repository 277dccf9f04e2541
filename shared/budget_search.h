// The work count that meets a time budget through noisy timings: Jimenez Kwast 2016, Table 6.2
// (per radius, the photon paths a frame can afford at a fixed frame time).
#pragma once

#include <functional>
#include <vector>

namespace ag {

struct BudgetSearch {
    double budget_ms = 20.0;
    double tolerance = 0.1;          // held: the last probe's time within ±tolerance × budget
    int rounds = 10;                 // probes after the first two, at most
    int first = 250, second = 4000;  // the first two probes
    int min_count = 50, max_count = 100000;
    int step = 25;  // counts are multiples of it (his table's paths are multiples of 25)
};

struct BudgetProbe {
    int count = 0;
    double ms = 0.0;
};

struct BudgetResult {
    int count = 0;                    // the probe nearest the budget (the last one when it held)
    double ms = 0.0;                  // its measured time
    bool held = false;                // |ms − budget| ≤ tolerance × budget
    double ms_per_count = 0.0;        // the fitted line's slope (ms per path at this radius)
    double fixed_ms = 0.0;            // and its intercept (the cost of zero paths)
    std::vector<BudgetProbe> probes;  // in the order measured
};

// `measure(count)` returns a time in ms; it may be noisy (the caller should pass a robust
// statistic such as a median over several frames). The time is taken to be about linear in the
// count: each step goes from the newest probe (the load may have drifted since the older ones)
// along the slope of a least-squares line through all of them (spread over the counts, so one
// noisy probe moves it little); a count whose timing lands within the tolerance is timed again,
// and holds when both timings are in it. After `rounds` probes beyond the first two the search
// gives up and returns the nearest probe, not held.
BudgetResult search_budget(const BudgetSearch& search, const std::function<double(int)>& measure);

}  // namespace ag
