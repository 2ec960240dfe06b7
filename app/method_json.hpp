#pragma once
/// @file The coarse models' typed reports as summary.json "coarse" figures: every key is the
/// name of a field (DESIGN.md "summary.json").
#include <nlohmann/json.hpp>

#include "coarsegrain/coarsen/coarse_model.hpp"

namespace coarsegrain::app {

/// The figures of a coarse model's report (an empty object for none).
nlohmann::json method_json(const coarsen::MethodReport& report);

/// Adds what a method reports once the fine solution is known to `coarse` (the summary "coarse"
/// of the model whose report is `method`): for the hierarchy, "levels" (each level's build
/// figures, updated with its diagnostics), "spectrum_max_dofs" and "coarsest_cells".
void add_comparison_json(nlohmann::json& coarse, const coarsen::MethodReport& method,
                         const coarsen::ComparisonReport& comparison);

}  // namespace coarsegrain::app
