#pragma once
/// @file Canonical multiresolution between simplicial level meshes, nested or not (Chen et al.
/// 2019, Secs. 3.1 and 5.1: the construction "does not make any special assumption on how these
/// meshes are related"): the node-level refinement C^k (Eq. 6) of level k's P1 hat functions in
/// those of level k+1, a pivot node of level k+1 per node of level k, and from them a sparse,
/// local left inverse C^{k,†} and kernel W^k.
///
/// On nested meshes (every node of level k is a node of level k+1, e.g. regular subdivision) the
/// operators are those of refinement.hpp: C^{k,†} is the injection at the coincident nodes and
/// W^k = [-P I]. Between non-nested meshes C^{k,†} is corrected locally
/// (local_refinement_operators).
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/mra/refinement.hpp"

namespace coarsegrain::mra {

/// Linear refinement between level meshes: c_ij = λ_i(x_j), the P1 hat function of node i of
/// `coarse` at node j of the finer level (rows of fine_positions), #coarse nodes by #fine nodes.
/// For a point inside the coarse mesh (within 1e-10 element sizes) λ are the barycentric
/// coordinates in the element containing it; outside (or in a cavity), the affine barycentric
/// coordinates in the nearest element, extrapolated (negative entries), as the effective
/// tensors' harmonic fields are sampled (Kharevych et al. 2009, Sec. 4.2). Every column sums to
/// 1 and C^T reproduces affine fields at every fine node to round-off. On nested meshes this is
/// the refinement relation of P1 hat functions (weights 1/2 at edge midpoints).
/// @param[in] coarse          a simplicial mesh (Tri3 or Tet4) of level k
/// @param[in] fine_positions  #fine nodes by coarse.dim()
/// @throws Error if `coarse` is not simplicial, has a degenerate element, or the sizes differ
SparseMatrix linear_refinement(const mesh::Mesh& coarse, const Matrix& fine_positions);

/// Dirac refinement between level meshes: c_ij = 1 for j = pivots[i], else 0 (lazy wavelets: the
/// coarse node is identified with its pivot fine node). #pivots by fine_nodes.
SparseMatrix selection_refinement(const std::vector<Index>& pivots, Index fine_nodes);

/// The pivot node of level k+1 of every node of level k: distinct nodes, each the nearest to its
/// coarse node among those not taken by a nearer pair (coarse nodes are served in the order of
/// their distance to their nearest fine node). On nested meshes: the coincident nodes.
/// @param[in] coarse_positions  #coarse nodes by dim
/// @param[in] fine_positions    #fine nodes by dim, at least as many as coarse nodes
/// @throws Error if there are fewer fine than coarse nodes or the dimensions differ
std::vector<Index> pivot_nodes(const Matrix& coarse_positions, const Matrix& fine_positions);

/// C^k, a left inverse C^{k,†} and the kernel W^k on the present DOFs for any scalar refinement
/// C_node with pivots (linear_refinement or selection_refinement with pivot_nodes).
///
/// A coarse DOF (i, d) whose row vanishes on the present DOFs (fine_dofs) measures nothing and is
/// dropped: its hat function reaches only absent fine nodes, while its pivot, the nearest fine
/// node, can lie outside it and be present (automatic levels beside a clamped part of the
/// object). Else one whose pivot DOF (d of node pivots[i]) is present is kept with it as its
/// pivot p, and one whose pivot DOF is absent (a Dirichlet DOF eliminated at the finest
/// level, or a DOF dropped at a finer level) is, as in refinement_operators,
/// - dropped if keep_boundary_rows is false (elimination);
/// - kept if keep_boundary_rows is true and its row has an exclusive pivot: a present DOF of a
///   node that is no pivot, weighted positively by no other such row (the largest weight wins,
///   then the smallest index); else dropped (always for Dirac refinement).
///
/// Row r = (i, d) of C^† solves C c = e_r (component d) on few fine nodes, so that the wavelets,
/// which hold the rows of C^† of the coarse nodes whose hat functions reach them, stay small:
/// - on a cell: the fine nodes whose columns of C (kept rows) have one support Σ ∋ i (the
///   vertices of a coarse element, face or edge they lie in), |Σ| of them (the best
///   conditioned by column-pivoted QR of C[Σ, nodes], reciprocal condition >= 1e-3) with
///   C[Σ, nodes] c = e_i; every other row of C vanishes on them. The smallest such Σ, then the
///   best conditioned. A fine node at coarse node i gives Σ = {i}: on nested meshes C^† is the
///   injection. Between levels of very different sizes (coarse elements holding d + 1 fine
///   nodes or more) most rows are of this kind, with at most d + 1 entries;
/// - else the smallest change of the injection e_p that makes it a left inverse:
///   c_r = argmin |c - e_p| subject to C c = e_r, with c supported on S_r, the present DOFs d of
///   the fine nodes within the fewest rings of p in the finer level's mesh graph (nodes sharing
///   an element) for which that has an exact solution (up to 8 rings), a small dense least-norm
///   problem (complete orthogonal decomposition) on the rows of C touching S_r.
/// A kept row with neither depends, near its pivot, on the other kept rows (two coarse nodes
/// whose hat functions reach the same single fine node, or levels too different there): such
/// rows are dropped one at a time, the weakest (smallest norm on the present DOFs) first, and
/// the others without a row of C^† solved again; the dropped DOFs join dropped_dofs.
///
/// The kernel is W = S_N (I - C^T C^†), S_N selecting the present fine DOFs outside a set P of one
/// kernel pivot per kept row: C W^T = C - C C^{†,T} C = 0, and W has full row rank exactly when
/// C^†[:, P] is nonsingular (a y != 0 with C^†[:, P]^T y = 0 gives the kernel vector C^{†,T} y,
/// zero on P, which the rows of W miss). P comes from an LU elimination of the rows of C^† with
/// threshold partial pivoting, rows served in the order of their largest |C^†(r, j) C(r, j)|,
/// each taking its DOF of largest such product not yet taken if its reduced entry is at least a
/// tenth of the row's largest, else its largest: on nested meshes P are the pivots and W = [-P I]
/// as on grids. (A matching of rows to DOFs is not enough: on distorted tetrahedra it left
/// C^†[:, P] with singular values down to 1e-15, docs/level-meshes.md.) A row of W holds its DOF
/// and the rows of C^† of the coarse nodes whose hat functions reach it.
/// @param[in] C_node     scalar refinement, #coarse nodes by #fine nodes
/// @param[in] pivots     distinct pivot fine node of every coarse node (pivot_nodes)
/// @param[in] fine_elements  elements of the finer level's mesh (node indices)
/// @param[in] dim        2 or 3
/// @param[in] fine_dofs  present fine DOFs, sorted, in [0, dim * C_node.cols())
/// @param[in] keep_boundary_rows  see above
/// @throws Error if the sizes disagree, pivots repeat, no row is left, or no kernel pivot is
///         found
RefinementOperators local_refinement_operators(const SparseMatrix& C_node,
                                               const std::vector<Index>& pivots,
                                               const IndexMatrix& fine_elements, int dim,
                                               const IndexVector& fine_dofs,
                                               bool keep_boundary_rows);

/// Regular subdivision of a simplicial mesh: every triangle into 4, every tetrahedron into 8
/// (edge midpoints as new nodes; the interior octahedron of a tetrahedron cut along its shortest
/// diagonal). The nodes of `coarse` keep their indices and come first, then one node per edge.
/// Materials ids are inherited by the children.
/// @throws Error if the mesh is not simplicial
mesh::Mesh subdivide(const mesh::Mesh& coarse);

}  // namespace coarsegrain::mra
