#pragma once
/// @file The one interface every coarsening method implements (DESIGN.md "data flow"): a method
/// maps the fine model and the scene's "coarse" options to a CoarseModel; one runtime solves any
/// CoarseModel and carries its solution to the fine mesh, so every comparison (the effective
/// tensors, the material-adapted hierarchy, the naive/Voigt/Reuss baselines) is the same code.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::coarsen {

/// A VTU file a method adds to the output folder (e.g. coarse_model.vtu, harmonic.vtu).
struct VtuOutput {
    std::string file;  ///< name inside the output folder
    mesh::Mesh mesh;
    io::VtuFields fields;
};

/// A coarse model: an operator on coarse DOFs, its load and conditions, and the linear map that
/// carries a coarse displacement to the fine nodes.
struct CoarseModel {
    std::string method;    ///< "effective-tensor", "naive", "voigt", "reuss", "mra"
    Index nodes = 0;       ///< coarse nodes (mra: nodes of the coarsest grid)
    Index elements = 0;    ///< coarse elements (mra: cells of the coarsest grid)
    SparseMatrix K;        ///< coarse stiffness over all coarse DOFs, both triangles stored
    Vector f;              ///< coarse load, one entry per coarse DOF
    fem::Dirichlet bc;     ///< coarse Dirichlet conditions (empty when built into K)
    SparseMatrix to_fine;  ///< fine DOFs x coarse DOFs: u_fine = to_fine * u_coarse
    Vector mass;           ///< lumped mass per coarse DOF; empty if the method defines none
    Timings timings;       ///< build phases; their sum is reported as coarse.timings.build
    nlohmann::json report = nlohmann::json::object();  ///< method figures for summary "coarse"
    std::vector<VtuOutput> outputs;                    ///< extra files for the output folder
};

}  // namespace coarsegrain::coarsen
