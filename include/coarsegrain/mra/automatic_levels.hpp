#pragma once
/// @file Level meshes made automatically for the hierarchy on a simplicial fine mesh that is no
/// grid (build_hierarchy on level meshes): carved simplicial background grids. Simple,
/// dimension-generic and without a mesher; a level follows the object's shape to within a cell
/// of its grid.
#include <vector>

#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/mra/options.hpp"

namespace coarsegrain::mra {

/// Smallest barycentric coordinate each corner of a kept element of the finest automatic level
/// must reach at one of the fine mesh's nodes the element contains (automatic_level_meshes).
inline constexpr double kMinCornerSupport = 0.05;

/// The meshes of levels 1..q-1 (q = levels; the fine mesh is level q) for build_hierarchy on
/// level meshes, made by carving nested simplicial background grids.
///
/// With N the fine mesh's nodes, V its measure and d its dimension, h = (V/N)^{1/d} is its mean
/// node spacing, and level k gets a spacing of about h_k = 2^{q-k} h, so that it has about
/// N / 2^{d(q-k)} nodes. Level k is the grid of mesh::make_grid (the fine mesh's element type:
/// 2 triangles or 6 Kuhn tetrahedra per cell) over the fine mesh's bounding box with
/// c 2^{k-1} cells along each axis, c = max(1, round(extent / h_1)), carved:
/// - level q-1 keeps the elements that contain a node of the fine mesh (barycentric
///   coordinates >= -1e-10) and whose every corner has a barycentric coordinate of at least
///   kMinCornerSupport at one of the fine nodes they contain;
/// - a level k < q-1 keeps the elements whose corners are all nodes of level k+1. The grids are
///   nested (each has half the cells of the next), so these levels are nested: the hierarchy's
///   left inverse between them is the injection, whatever the Dirichlet conditions. (Keeping
///   corners that are only ends of finer edges, at support 1/2, covers the finer level closer
///   but made two such corners of one edge share their only finer node, and the cheese wheel's
///   4-level hierarchy had no local left inverse.)
/// Nodes of no kept element are dropped. The levels are built from the finest down.
///
/// The grids span the bounding box exactly, so that its faces, where Dirichlet conditions
/// usually sit, are grid planes at every level: coarse nodes on a clamped face then pivot on
/// fixed fine nodes and are dropped by the hierarchy, instead of keeping a few weights at free
/// fine nodes next to the face (a centred, stretched box put the clamped face mid-cell, and those
/// rows had no local left inverse). The corner rule makes every node's P1 hat function at least
/// kMinCornerSupport at a fine node, so that no row of the refinement C^{q-1} vanishes or nearly
/// does; it drops the elements the fine mesh touches only along a face, an edge or a corner, or
/// only in a sliver along a face. The finer nodes the kept elements miss lie outside them by
/// less than a cell's diagonal (tests/mra/test_automatic_levels.cpp), where linear_refinement
/// extrapolates.
///
/// @param[in] fine    the fine mesh, triangles (Tri3) or tetrahedra (Tet4), level q
/// @param[in] levels  q >= 2
/// @return levels - 1 meshes, coarsest first, of the fine mesh's element type, positively
///         oriented, material ids 0 and no GridInfo (they are not grids)
/// @throws Error if the fine mesh is not simplicial or has no measure, levels < 2 or more than
///         max_automatic_levels, or a level has fewer than d + 1 nodes or no fewer nodes than
///         the next finer level (the message says to use fewer levels or give the level
///         meshes)
std::vector<mesh::Mesh> automatic_level_meshes(const mesh::Mesh& fine, int levels);

/// The most levels q for which the coarsest automatic level is expected to have at least d + 1
/// nodes: N / 2^{d(q-1)} >= d + 1 for N fine nodes in dimension d (at least 1).
int max_automatic_levels(const mesh::Mesh& fine);

/// The checks of automatic_level_meshes and build_hierarchy on level meshes that need no level
/// mesh, for a scene to make them before any work: the fine mesh is simplicial, 2 <= levels <=
/// max_automatic_levels, and the options are those of level meshes
/// (validate_level_mesh_options).
/// @throws Error saying what was expected
void validate_automatic_levels(const mesh::Mesh& fine, const Options& options);

}  // namespace coarsegrain::mra
