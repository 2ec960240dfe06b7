#pragma once
/// @file Google Benchmark runs whose real times a program reads back, to print ratios measured
/// in the same run (machines differ by 2-4x in absolute times; a ratio carries).
#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <vector>

namespace coarsegrain::bench {

/// Runs the benchmarks selected on the command line (benchmark::Initialize must have run),
/// printing them as usual, and returns each one's real time per iteration, by benchmark name,
/// in the unit it reports.
inline std::map<std::string, double> run_and_collect_times() {
    class Reporter : public benchmark::ConsoleReporter {
      public:
        void ReportRuns(const std::vector<Run>& runs) override {
            for (const Run& r : runs) times[r.benchmark_name()] = r.GetAdjustedRealTime();
            ConsoleReporter::ReportRuns(runs);
        }
        std::map<std::string, double> times;
    } reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    return reporter.times;
}

}  // namespace coarsegrain::bench
