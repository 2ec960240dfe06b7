#pragma once
/// @file Load vectors: gravity (body force) and surface traction.
#include <vector>

#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/boundary.hpp"

namespace coarsegrain::fem {

/// Consistent nodal forces of gravity: f = ∫ rho g N_a (interleaved, num_dofs), equal to the
/// consistent mass matrix applied to the uniform field g.
/// @param[in] g  acceleration (size dim)
Vector gravity_load(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                    const Eigen::VectorXd& g);

/// Consistent nodal forces of a uniform traction t (force per unit area, size dim) on the
/// given boundary facets (indices into b): f_a = t ∫ N_a over each facet, i.e. t L/2 per node
/// of an edge, t A/3 per node of a triangle, and 2x2 Gauss over the bilinear map for a quad
/// facet (exact for planar quads). Only b.facets is read.
/// @throws Error if t has the wrong size, a facet index is out of range or the facets have the
///         wrong number of nodes for the mesh's dimension
Vector traction_load(const mesh::Mesh& mesh, const mesh::Boundary& b,
                     const std::vector<Index>& facets, const Eigen::VectorXd& t);

}  // namespace coarsegrain::fem
