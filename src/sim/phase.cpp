#include "coarsegrain/sim/phase.hpp"

#include <algorithm>
#include <numeric>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::sim {

namespace {

std::vector<double> minus_mean(std::vector<double> x) {
    if (x.empty()) return x;
    const double mean = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
    for (double& v : x) v -= mean;
    return x;
}

/// Mean spacing of at least two crossings.
std::optional<double> period(const std::vector<double>& crossings) {
    if (crossings.size() < 2) return std::nullopt;
    return (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
}

}  // namespace

std::vector<double> upward_crossings(const std::vector<double>& t, const std::vector<double>& x) {
    CG_VERIFY(t.size() == x.size(), "upward_crossings: {} times for {} samples", t.size(),
              x.size());
    std::vector<double> crossings;
    for (std::size_t i = 0; i + 1 < t.size(); ++i) {
        CG_VERIFY(t[i + 1] > t[i], "upward_crossings: times must increase (t[{}] = {}, t[{}] = {})",
                  i, t[i], i + 1, t[i + 1]);
        if (x[i] < 0 && x[i + 1] >= 0)
            crossings.push_back(t[i] + (t[i + 1] - t[i]) * (-x[i]) / (x[i + 1] - x[i]));
    }
    return crossings;
}

PhaseComparison compare_phase(const std::vector<double>& t, const std::vector<double>& fine,
                              const std::vector<double>& coarse) {
    CG_VERIFY(fine.size() == coarse.size(), "compare_phase: {} fine samples for {} coarse",
              fine.size(), coarse.size());
    const std::vector<double> cf = upward_crossings(t, minus_mean(fine));
    const std::vector<double> cc = upward_crossings(t, minus_mean(coarse));
    PhaseComparison p;
    p.crossings_fine = static_cast<int>(cf.size());
    p.crossings = static_cast<int>(cc.size());
    p.period_fine = period(cf);
    p.period = period(cc);
    if (p.period_fine && p.period) {
        p.period_rel = *p.period / *p.period_fine - 1;
        const std::size_t n = std::min(cf.size(), cc.size());
        p.lag = cc[n - 1] - cf[n - 1];
    }
    return p;
}

}  // namespace coarsegrain::sim
