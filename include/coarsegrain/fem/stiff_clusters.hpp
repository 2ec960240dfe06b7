#pragma once
/// @file The stiff clusters of a composite and their rigid motions, the near-kernel that point
/// smoothers and local coarse spaces miss at high contrast: moving a stiff inclusion rigidly
/// costs only the soft material's strain around it. Deflation vectors of the fine solvers
/// (solve/deflation.hpp; Jönsthövel, van Gijzen, Vuik, Kasbergen and Scarpas 2009, "Preconditioned
/// conjugate gradient method enhanced by deflation of rigid body modes applied to composite
/// materials").
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

/// Elements grouped into stiff clusters.
struct StiffClusters {
    IndexVector cluster;  ///< #E cluster of each element (0..count-1), -1 in no cluster
    Index count = 0;
};

/// The stiff clusters: connected components, through shared facets (mesh::element_components),
/// of the elements of one material whose stiffness (the largest eigenvalue of its elasticity
/// tensor: 3 lambda + 2 mu for an isotropic 3D material with nu >= 0) is at least `contrast`
/// times that of the softest material of the mesh. Numbered by their first element. None when
/// every material is within `contrast` of the softest (a homogeneous model has none).
/// @throws Error if contrast <= 1 or is not finite, or the materials do not match the mesh
StiffClusters stiff_clusters(const mesh::Mesh& mesh, const material::ElementMaterials& materials,
                             double contrast);

/// The rigid motions of each cluster as vectors over the free DOFs (all DOFs of `mesh` but
/// `fixed_dofs`, ascending, as fem::reduce numbers them): per cluster, the dim(dim+1)/2
/// translations and rotations of its nodes with the fixed DOFs zeroed, orthonormalized (thin
/// SVD; directions with a singular value below 1e-8 of the largest, those the Dirichlet
/// conditions remove, dropped; a cluster whose own nodes, those of no other cluster, do not
/// carry every direction kept is skipped, e.g. a stiff element touching others at its corners,
/// so that all columns are linearly independent), divided by m at a node of m clusters kept (a
/// partition of unity over the shared nodes: any motion rigid on each cluster and continuous
/// where they touch, such as a hinge of two stiff cubes meeting along an edge, lies in their
/// span; without it, the checkerboard's edge-connected cubes need 3x the iterations), then
/// extended over `rings` rings of the node graph around the cluster into nodes of no cluster by
/// the energy-minimizing extension: A_free restricted to those nodes' free DOFs solved with the
/// cluster's values as boundary data and zero beyond the rings and on the other clusters.
/// rings = 0: zero outside the cluster's nodes.
/// @param A_free  the operator on the free DOFs (both triangles), symmetric positive definite
/// @return #free DOFs by (at most dim(dim+1)/2 per cluster) columns, a cluster's consecutive
/// @throws Error if the sizes do not match, fixed_dofs is not sorted and in range, or rings < 0
SparseMatrix cluster_rigid_modes(const mesh::Mesh& mesh, const StiffClusters& clusters,
                                 const SparseMatrix& A_free, const std::vector<Index>& fixed_dofs,
                                 int rings);

}  // namespace coarsegrain::fem
