#pragma once
/// @file Global operators assembled in parallel (OpenMP) straight into compressed storage.
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

enum class MassType { Lumped, Consistent };

/// Global stiffness K = sum_e K_e (num_dofs square, compressed column storage, both triangles
/// stored, exactly symmetric, PSD with the rigid motions as kernel).
///
/// The pattern is built once from the node adjacency (the dim columns of a node share one row
/// pattern, rows sorted) and the values are written in place, never through triplets:
/// - regular grids (mesh.grid set, Quad4/Hex8): all elements are congruent, so K_e is computed
///   once per material table entry and each node's columns are gathered from its incident
///   elements, one node per parallel iteration;
/// - other meshes: element matrices are computed on the fly and scattered by an owner-computes
///   partition of the nodes into contiguous ranges (race free, cache friendly), or by greedy
///   element colouring when the node numbering has no locality.
/// 64^3 hexes (823,875 DOFs) assemble in 0.40 s on 2 cores, mostly writing the entries
/// (bench/bench_assembly.cpp; docs/performance.md, "Assembly").
/// `formulation` chooses the element (element_stiffness); Formulation::Incompatible needs a
/// Quad4 / Hex8 mesh.
/// @throws Error if the materials do not match the mesh, an element is inverted/degenerate
///         (the message names the element), or the formulation does not apply to the mesh
SparseMatrix stiffness_matrix(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                              Formulation formulation = Formulation::Standard);

/// Global mass matrix (num_dofs square): consistent, M = sum_e ∫ rho N_a N_b times the dim x dim
/// identity per node pair (stored entries only on the diagonal of each block), or lumped, the
/// diagonal of its row sums, rho ∫ N_a. Same parallel schemes as stiffness_matrix.
SparseMatrix mass_matrix(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                         MassType type);

}  // namespace coarsegrain::fem
