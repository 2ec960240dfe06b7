// Periods and lags from upward zero crossings (sim/phase.hpp), against signals whose crossings
// are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/sim/phase.hpp"

using namespace coarsegrain;

namespace {

constexpr double kPi = std::numbers::pi;

std::vector<double> phase_times(double dt, double duration) {
    std::vector<double> t;
    const int n = static_cast<int>(std::lround(duration / dt));
    for (int i = 0; i <= n; ++i) t.push_back(i * dt);
    return t;
}

/// sin(2π (t - t0) / T) at the times t.
std::vector<double> phase_sine(const std::vector<double>& t, double t0, double T) {
    std::vector<double> x;
    for (const double ti : t) x.push_back(std::sin(2 * kPi * (ti - t0) / T));
    return x;
}

double phase_mean(const std::vector<double>& x) {
    double s = 0;
    for (const double v : x) s += v;
    return s / static_cast<double>(x.size());
}

/// The upward crossings of sin(2π (t - t0) / T) - c inside (a, b): t0 + T (asin(c) / 2π + k).
std::vector<double> phase_exact_crossings(double t0, double T, double c, double a, double b) {
    std::vector<double> out;
    const double first = t0 + T * std::asin(c) / (2 * kPi);
    for (int k = static_cast<int>(std::floor((a - first) / T)); first + k * T < b; ++k)
        if (first + k * T > a) out.push_back(first + k * T);
    return out;
}

}  // namespace

// Linear interpolation is exact for a signal that is linear between its samples.
TEST(Phase, UpwardCrossingsOfAPiecewiseLinearSignalAreExact) {
    const std::vector<double> t = {0, 1, 2, 3, 4, 5, 6};
    const std::vector<double> x = {-1, 1, 2, -3, 1, 0, -2};
    const std::vector<double> c = sim::upward_crossings(t, x);
    ASSERT_EQ(c.size(), 2u);
    EXPECT_DOUBLE_EQ(c[0], 0.5);   // -1 -> 1
    EXPECT_DOUBLE_EQ(c[1], 3.75);  // -3 -> 1; 1 -> 0 -> -2 goes down
    // A sample exactly at zero ends a crossing once: -1, 0, 1 crosses at the zero sample.
    const std::vector<double> at_zero = sim::upward_crossings({0, 1, 2}, {-1, 0, 1});
    ASSERT_EQ(at_zero.size(), 1u);
    EXPECT_DOUBLE_EQ(at_zero[0], 1.0);
}

// sin(2πt/T) against sin(2π(t − τ)/T'), both sampled at dt. Each signal, minus its sample mean
// c, crosses zero upward at t0 + T (asin(c)/2π + k); linear interpolation misplaces a crossing
// by at most (|y''| + |y'''| dt) dt² / (8 |y'|) = [(π/4)|c| + (π²/2) dt/T] dt²/T / √(1 − c²),
// here (|c| < 0.08, dt <= T/20) below 0.31 dt²/T. A period or a lag is the difference of two
// crossings (the period divided by n − 1 >= 1): within 0.62 dt²/T, so the tolerance dt²/T holds
// at every dt and shrinks with dt² (O(dt²/T)).
TEST(Phase, PeriodsAndLagOfTwoSinesAreWithinTheSamplingResolution) {
    const double T = 0.5, T_coarse = 0.52, t0 = 0.11, tau = 0.03, duration = 2.2;
    for (const double steps_per_period : {20.0, 50.0, 200.0}) {
        SCOPED_TRACE(steps_per_period);
        const double dt = T / steps_per_period;
        const std::vector<double> t = phase_times(dt, duration);
        const std::vector<double> fine = phase_sine(t, t0, T);
        const std::vector<double> coarse = phase_sine(t, t0 + tau, T_coarse);
        const double c_fine = phase_mean(fine), c_coarse = phase_mean(coarse);
        ASSERT_LT(std::abs(c_fine), 0.08);
        ASSERT_LT(std::abs(c_coarse), 0.08);
        const std::vector<double> ef = phase_exact_crossings(t0, T, c_fine, 0, t.back());
        const std::vector<double> ec =
            phase_exact_crossings(t0 + tau, T_coarse, c_coarse, 0, t.back());
        ASSERT_EQ(ef.size(), 5u);  // 0.11 ... 2.11
        ASSERT_EQ(ec.size(), 4u);  // 0.14 ... 1.70; the fifth, 2.22, is after the run

        const sim::PhaseComparison p = sim::compare_phase(t, fine, coarse);
        const double tol = dt * dt / T;
        EXPECT_EQ(p.crossings_fine, 5);
        EXPECT_EQ(p.crossings, 4);
        ASSERT_TRUE(p.period_fine && p.period && p.period_rel && p.lag);
        EXPECT_NEAR(*p.period_fine, T, tol);
        EXPECT_NEAR(*p.period, T_coarse, tol);
        EXPECT_NEAR(*p.period_rel, T_coarse / T - 1, 3 * tol / T);
        // The 4th crossings, the last both have: τ + 3 (T' − T) late, apart from the means.
        EXPECT_NEAR(*p.lag, ec[3] - ef[3], tol);
        EXPECT_NEAR(ec[3] - ef[3], tau + 3 * (T_coarse - T), 0.01);  // the asin(c) terms
    }
}

// The mean over the run is removed before crossing zero; a model that is early has a negative lag.
TEST(Phase, MeansAreRemovedAndAnEarlySignalLeads) {
    const double T = 1.0, dt = 0.01;
    const std::vector<double> t = phase_times(dt, 3.5);
    std::vector<double> fine = phase_sine(t, 0.2, T), coarse = phase_sine(t, 0.15, T);
    for (double& v : fine) v = 5 + 2 * v;  // far from zero: no crossing before the mean is removed
    for (double& v : coarse) v = -3 + v;
    const sim::PhaseComparison p = sim::compare_phase(t, fine, coarse);
    ASSERT_TRUE(p.lag && p.period_rel);
    EXPECT_NEAR(*p.lag, -0.05, 0.01);  // the means differ a little: asin(c) / 2π
    EXPECT_NEAR(*p.period_rel, 0.0, dt * dt / T);
    EXPECT_TRUE(sim::upward_crossings(t, fine).empty());
}

// Fewer than two upward crossings: no period, so no period_rel and no lag.
TEST(Phase, FewerThanTwoCrossingsGiveNoFigures) {
    const std::vector<double> t = phase_times(0.01, 1.2);
    const std::vector<double> fine = phase_sine(t, 0.5, 1.0);  // one upward crossing, near 0.5
    const std::vector<double> flat(t.size(), 2.0);
    sim::PhaseComparison p = sim::compare_phase(t, fine, fine);
    EXPECT_EQ(p.crossings_fine, 1);
    EXPECT_FALSE(p.period_fine || p.period || p.period_rel || p.lag);
    const std::vector<double> longer_t = phase_times(0.01, 3.2);
    const std::vector<double> sine = phase_sine(longer_t, 0.0, 1.0);
    p = sim::compare_phase(longer_t, sine, std::vector<double>(longer_t.size(), 2.0));
    EXPECT_EQ(p.crossings, 0);
    EXPECT_TRUE(p.period_fine);
    EXPECT_FALSE(p.period || p.period_rel || p.lag);
    EXPECT_TRUE(sim::upward_crossings(t, flat).empty());
}

TEST(Phase, BadInputIsAnError) {
    EXPECT_THROW(sim::upward_crossings({0, 1}, {0, 1, 2}), Error);
    EXPECT_THROW(sim::upward_crossings({0, 1, 1}, {-1, 0, 1}), Error);
    EXPECT_THROW(sim::compare_phase({0, 1}, {0, 1}, {0}), Error);
}
