#pragma once
/// @file Load vectors: gravity (body force) and surface traction.
#include <vector>

#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/boundary.hpp"

namespace coarsegrain::fem {

/// Consistent nodal forces of gravity: f = ∫ rho g N_a (interleaved, num_dofs).
/// @param[in] g  acceleration (size dim)
Vector gravity_load(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                    const Eigen::VectorXd& g);

/// Consistent nodal forces of a uniform traction t (force per unit area, size dim) on the
/// given boundary facets (indices into b).
Vector traction_load(const mesh::Mesh& mesh, const mesh::Boundary& b,
                     const std::vector<Index>& facets, const Eigen::VectorXd& t);

}  // namespace coarsegrain::fem
