#pragma once
/// @file summary.json figures shared by the command-line tool and the Python module.
#include <nlohmann/json.hpp>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::coarsen {

/// The entries of v as a std::vector (a JSON array).
std::vector<double> to_std(const Eigen::VectorXd& v);

/// {"phase": seconds, ...} in the order the phases ran (a repeated phase: its last seconds).
nlohmann::json timings_json(const Timings& timings);

/// The fine model's sizes for summary.json "fine": "nodes", "elements", "element", "dofs",
/// "free_dofs" (without the Dirichlet DOFs) and "nonzeros" (of the stiffness).
nlohmann::json fine_sizes(const scene::FineModel& model);

}  // namespace coarsegrain::coarsen
