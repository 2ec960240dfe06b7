#pragma once
/// @file The phase of a coarse model's oscillation against the fine model's: periods from the
/// upward zero crossings of each signal about its mean, and the time lag between their crossings
/// (summary.json "errors.phase" of `coarsegrain simulate`).
#include <optional>
#include <vector>

namespace coarsegrain::sim {

/// Times at which a sampled signal crosses zero upward: for each pair of samples with
/// x[i] < 0 <= x[i+1], the zero of the straight line through them. For a smooth signal the
/// error of each crossing is at most |x''| dt² / (8 |x'|) at the crossing (the linear
/// interpolant's error over its slope) plus O(dt³) terms.
/// @param t  #T sample times, strictly increasing
/// @param x  #T samples
/// @return the crossing times, ascending (empty if there is none)
/// @throws Error if the sizes differ or t is not strictly increasing
std::vector<double> upward_crossings(const std::vector<double>& t, const std::vector<double>& x);

/// A coarse signal's period and phase against a fine one, each taken about its own mean over
/// the run. A figure is empty (summary.json null) when a signal it needs has fewer than two
/// upward crossings.
struct PhaseComparison {
    int crossings_fine = 0;  ///< upward crossings of the fine signal
    int crossings = 0;       ///< upward crossings of the coarse signal
    /// Mean spacing of the fine signal's upward crossings, (c_n - c_1) / (n - 1)
    std::optional<double> period_fine;
    std::optional<double> period;      ///< the same for the coarse signal
    std::optional<double> period_rel;  ///< period / period_fine - 1
    /// Coarse n-th upward crossing minus the fine n-th, n the last index both signals have:
    /// positive when the coarse signal is late. Meaningful only while the two stay within half
    /// a period of each other (periods that differ by a few percent over a few periods).
    std::optional<double> lag;
};

/// Compares the phase of `coarse` with that of `fine`, both sampled at the times `t` (each minus
/// its own mean over the samples, then upward_crossings).
/// @param t       #T sample times, strictly increasing
/// @param fine    #T samples of the reference signal
/// @param coarse  #T samples of the signal compared with it
/// @throws Error if the sizes differ or t is not strictly increasing
PhaseComparison compare_phase(const std::vector<double>& t, const std::vector<double>& fine,
                              const std::vector<double>& coarse);

}  // namespace coarsegrain::sim
