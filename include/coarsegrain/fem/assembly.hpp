#pragma once
/// @file Global operators assembled in parallel (OpenMP) straight into compressed storage.
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

enum class MassType { Lumped, Consistent };

/// Global stiffness K (num_dofs square, both triangles stored, symmetric PSD).
/// On regular grids (mesh.grid set, Quad4/Hex8) element matrices are computed once per
/// material and reused. Element colouring makes the parallel scatter race free.
/// @throws Error if an element is inverted/degenerate
SparseMatrix stiffness_matrix(const mesh::Mesh& mesh, const material::ElementMaterials& mats);

/// Global mass matrix (num_dofs square), lumped (diagonal) or consistent.
SparseMatrix mass_matrix(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                         MassType type);

}  // namespace coarsegrain::fem
