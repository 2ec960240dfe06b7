#pragma once
/// @file Regular grids in 2D and 3D.
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// Makes a regular grid over the box [min, max].
///
/// Nodes are numbered x fastest, then y, then z: node (i,j,k) = i + (nx+1)(j + (ny+1) k).
/// Cells likewise: cell (i,j,k) = i + nx (j + ny k). For Tri3 each cell is split into 2
/// triangles and for Tet4 into 6 tets (Kuhn/Freudenthal split along the main diagonal, so
/// neighbouring cells share face diagonals and every tet is positively oriented); the
/// elements of cell c are then c*2 .. c*2+1 (resp. c*6 .. c*6+5).
/// All material ids are 0; GridInfo is set for every type.
///
/// @param[in] type   Tri3 or Quad4 (2D: min/max/cells use x,y) or Tet4 or Hex8 (3D)
/// @param[in] min    lower corner (size dim)
/// @param[in] max    upper corner (size dim), > min componentwise
/// @param[in] cells  cells per axis (size dim), each >= 1
/// @throws Error on invalid sizes
Mesh make_grid(ElementType type, const Eigen::VectorXd& min, const Eigen::VectorXd& max,
               const Eigen::VectorXi& cells);

/// Centre of each element: #E by dim.
Matrix element_centroids(const Mesh& mesh);

}  // namespace coarsegrain::mesh
