#pragma once
/// @file The material-adapted hierarchy as a coarsening method (`coarsen --method mra`).
#include <nlohmann/json.hpp>
#include <string>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::mra {

/// Reads the hierarchy options from a scene's "coarse" block (null: all defaults). Keys (other
/// keys belong to other methods and are ignored):
/// - "levels": integer >= 2 (default 3);
/// - "refinement": "dirac" | "linear" (default);
/// - "radius": number >= 1, "inf", or an array of levels - 1 of them, entry k-1 for the step
///   that builds level k (default "inf": global solves);
/// - "radius_grid": "fine" (default) | "coarse";
/// - "truncation": number in [0, 1) (default 1e-7, Options::truncation);
/// - "invariance": true (default) | false;
/// - "dirichlet": "constrain" (default) | "eliminate" | "penalty" | "diagonal_penalty".
/// @throws InvalidScene naming `coarse.<key>` and the source
Options parse_options(const nlohmann::json& coarse, const std::string& source);

/// The coarsest level of a hierarchy as a coarse model: K = S A^1 S, f = S g^1 with
/// g^1 = C̃^1...C̃^{q-1} f, to_fine = Φ^{1,T} S, over all DOFs of the coarsest grid. S is
/// diagonal: the coefficients v of level 1 are measurements C^1...C^{q-1} u (Eq. 9), which for
/// a translation t are s t with s the row sums of the chain (s = 1 for Dirac, 4^(q-1) at
/// interior nodes of a 2D grid for the linear refinement); the model's DOFs u_c = v / s are
/// displacements of the coarse nodes. DOFs without a basis function (see
/// Level::dropped_dofs) have empty rows and columns and are fixed at 0 in bc. `report` holds the
/// options and per level: nodes, dofs, wavelets, radius, build_seconds, nnz and density of C̃,
/// A and B, and storage bytes of Φ and Ψ; `timings` the phases of h.
coarsen::CoarseModel coarse_model(const Hierarchy& h, const Vector& f_fine);

/// Builds the hierarchy from scene.coarse options (parse_options) and returns the coarsest
/// level as a CoarseModel (coarse_model).
/// @throws InvalidScene for bad options or nonzero Dirichlet values; Error as build_hierarchy
coarsen::CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine);

}  // namespace coarsegrain::mra
