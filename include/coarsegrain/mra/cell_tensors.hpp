#pragma once
/// @file Effective elasticity of the coarsest cells of a material-adapted hierarchy and their
/// directional Young's modulus (Chen et al. 2019, Sec. 5.6, Fig. 17).
///
/// Fig. 17 computes E(d) = 1 / (div(dd^T) : (A^1)^{-1} : div(dd^T)) on a single square domain
/// coarsened to one element, boundary effects included. Here div(dd^T) is read as the load of
/// the uniform stress σ = dd^T: on the fine grid f(σ) = ∫ B^T σ, the traction σ n on the
/// boundary, coarse-grained to the coarsest level as every load is (Sec. 4.1):
/// g(σ) = C̃^1 ... C̃^{q-1} f(σ). With the Mandel unit stresses σ_a this gives the coarsest
/// compliance S_ab = g(σ_a)^T (A^1)^+ g(σ_b) / |cell| (A^1 is singular on a free body; the loads
/// are self-equilibrated and A^1's kernel is the rigid motions thanks to the invariance
/// correction, exactly with global solves and no truncation, up to a small perturbation
/// otherwise: the pseudo-inverse drops the dim(dim+1)/2 smallest eigenvalues), the effective
/// tensor C = S^{-1} and E(d) = 1 / (d⊗d : S : d⊗d).
///
/// Galerkin bound (global solves, no truncation): u^1 = Φ^{1,T} (A^1)^+ g is the energy projection
/// of the fine solution u of the same free-body problem, so for every σ
///   σ : S_fine : σ - σ : S : σ = ||u - u^1||_K^2 / |cell|,
/// the coarse cell is stiffer than the fine one by exactly its homogenization error. For a
/// homogeneous material S_fine = C^{-1} (the linear field is the exact fine solution).
#include <vector>

#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/mra/hierarchy.hpp"

namespace coarsegrain::mra {

/// Effective elasticity of one cell (Mandel, mandel_size(dim) square).
struct CellTensor {
    Matrix S;  ///< compliance S_ab = g(σ_a)^T (A^1)^+ g(σ_b) / |cell|
    Matrix C;  ///< S^{-1}
};

/// Uniform-stress loads of a free body: column a is f(σ_a) = ∫ B^T σ_a over all grid DOFs, the
/// traction σ_a n on the boundary facets, for the Mandel unit stresses σ_a (a shear unit
/// σ_ij = σ_ji = 1/√2). For every displacement u, f(σ_a) · u = ∫ σ_a : ε(u).
/// @pre `mesh` is a grid (GridInfo set): its boundary is the 2 dim sides of its box
Matrix uniform_stress_loads(const mesh::Mesh& mesh);

/// The coarsest cell of a single-cell hierarchy of `mesh` (a grid with 2^(levels-1) cells
/// along every axis) as a free body, see the file comment.
/// @param[in] options  hierarchy options; levels is set from the grid and the invariance
///                     correction is turned on (A^1's kernel must be the rigid motions)
/// @throws Error if the grid is not 2^m cells along every axis, or A^1's smallest
///         dim(dim+1)/2 eigenvalues are not below 1e-2 of the next one in absolute value
CellTensor coarsest_cell_tensor(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                                Options options);

/// coarsest_cell_tensor of each cell of the coarsest grid (`coarsest_cells` per axis) of a
/// hierarchy on the grid `fine`: the fine cells inside it with their materials, as a free body.
/// Cells in make_grid order.
/// @throws Error if `fine` is not a grid divisible into coarsest_cells, or as above
std::vector<CellTensor> coarsest_cell_tensors(const mesh::Mesh& fine,
                                              const material::ElementMaterials& mats,
                                              const Eigen::Vector3i& coarsest_cells,
                                              const Options& options);

/// Directions sampled for the directional Young's modulus: in 2D 36 angles 0°, 5°, ..., 175°
/// (d and -d are the same); in 3D the 3 axes, the 6 face diagonals and the 4 body diagonals.
/// #directions by dim, unit rows.
Matrix youngs_directions(int dim);

}  // namespace coarsegrain::mra
