#include "shared/budget_search.h"

#include <algorithm>
#include <cmath>

namespace ag {

namespace {

// Least-squares line t = fixed + slope · count through every probe: its slope, from probes
// spread over the counts, is robust to one probe's noise.
void fit_line(const std::vector<BudgetProbe>& probes, double& fixed, double& slope) {
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const BudgetProbe& p : probes) {
        const double x = p.count;
        n += 1, sx += x, sy += p.ms, sxx += x * x, sxy += x * p.ms;
    }
    const double det = n * sxx - sx * sx;
    slope = det > 0 ? (n * sxy - sx * sy) / det : 0.0;
    fixed = (sy - slope * sx) / n;
}

}  // namespace

BudgetResult search_budget(const BudgetSearch& search, const std::function<double(int)>& measure) {
    BudgetResult r;
    const double budget = search.budget_ms, band = search.tolerance * budget;
    const int step = std::max(1, search.step);
    auto snap = [&](double count) {
        const double c = std::clamp(count, double(search.min_count), double(search.max_count));
        return std::max(search.min_count, int(std::lround(c / step)) * step);
    };
    auto probe = [&](int count) {
        r.probes.push_back({count, measure(count)});
        return r.probes.back();
    };
    auto in_band = [&](const BudgetProbe& p) { return std::abs(p.ms - budget) <= band; };
    probe(snap(search.first));
    probe(snap(search.second));
    bool held = false;
    for (int round = 0; round < search.rounds; ++round) {
        const BudgetProbe last = r.probes.back();
        int next;
        if (in_band(last)) {
            // One timing in the band may be luck (a stall in the other probes, a warm-up): the
            // count is timed again, and holds when that lands in the band too.
            const bool again = std::any_of(r.probes.begin(), r.probes.end() - 1, [&](auto& p) {
                return p.count == last.count && in_band(p);
            });
            if (again) {
                held = true;
                break;
            }
            next = last.count;
        } else {
            // A Newton step from the newest probe (the load may have drifted since the older
            // ones) along the slope of all of them.
            double fixed = 0, slope = 0;
            fit_line(r.probes, fixed, slope);
            if (!(slope > 0)) slope = std::max(last.ms, 1e-9) / std::max(last.count, 1);
            next = snap(last.count + (budget - last.ms) / slope);
            if (next == last.count)  // rounding undid the step: take one step of `step`
                next = snap(last.count + (last.ms < budget ? step : -step));
            // At a clamp that is already over (or under) the budget there is nothing to gain.
            const bool stuck_low =
                next == search.min_count && last.count == next && last.ms > budget;
            const bool stuck_high =
                next == search.max_count && last.count == next && last.ms < budget;
            if (stuck_low || stuck_high) break;
        }
        probe(next);
    }
    double fixed = 0, slope = 0;
    fit_line(r.probes, fixed, slope);
    r.fixed_ms = fixed, r.ms_per_count = slope;
    // The answer: the held count (its timings in the band averaged), else the nearest probe.
    if (held) {
        const int count = r.probes.back().count;
        double sum = 0;
        int n = 0;
        for (const BudgetProbe& p : r.probes)
            if (p.count == count && in_band(p)) sum += p.ms, ++n;
        r.count = count;
        r.ms = sum / n;
    } else {
        const BudgetProbe* best = &r.probes.front();
        for (const BudgetProbe& p : r.probes)
            if (std::abs(p.ms - budget) < std::abs(best->ms - budget)) best = &p;
        r.count = best->count;
        r.ms = best->ms;
    }
    r.held = held;
    return r;
}

}  // namespace ag
