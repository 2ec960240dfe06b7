#pragma once
/// @file Figures of an effective-tensor or baseline coarsening (homogenize::coarsening), which
/// the CLI writes to summary.json "coarse" under the names of the fields.
#include <optional>
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::homogenize {

/// Figures only the effective-tensor method has.
struct EffectiveTensorReport {
    bool coarse_normals = true;   ///< coarse.normals: "coarse" if true, else "fine"
    bool mixed_boundary = false;  ///< coarse.boundary: "mixed" if true, else "neumann"
    /// Smallest and largest condition number of the coarse mollifiers 𝔾_q.
    double mollifier_condition_min = 0, mollifier_condition_max = 0;
    /// Mixed boundary only (summary "fallback_elements"): the coarse elements that fell back to
    /// the pure-Neumann mollifier (Coarsening::fallback).
    std::vector<Index> fallback_elements;
};

/// Figures of a coarsening, every method.
struct Report {
    Index fine_simplices = 0;    ///< elements of the simplicial fine mesh
    Index coarse_simplices = 0;  ///< elements of the simplicial coarse mesh
    Index overlaps = 0;          ///< nonempty fine-coarse intersections
    /// Coarse nodes outside the fine mesh by more than round-off, and the largest distance.
    Index coarse_nodes_outside = 0;
    double coarse_nodes_max_outside_distance = 0;
    double fine_mass = 0, coarse_mass = 0;  ///< summary "mass": "fine", "coarse"
    bool harmonic_map = false;  ///< summary "map": "harmonic" if true, else "barycentric"
    /// The fine Dirichlet conditions carried to the coarse DOFs (summary "conditions"): coarse
    /// DOFs fixed, coarse DOFs held in combination, and the combinations left free.
    Index fixed_dofs = 0, constrained_dofs = 0, combinations = 0;
    std::optional<EffectiveTensorReport> effective_tensor;  ///< effective-tensor method only
};

}  // namespace coarsegrain::homogenize
