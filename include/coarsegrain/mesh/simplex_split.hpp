#pragma once
/// @file Splitting quad/hex meshes into triangles/tets on the same nodes.
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// Simplices each element of `type` is split into: 2 for Quad4, 6 for Hex8, 1 for Tri3/Tet4.
int simplices_per_element(ElementType type);

/// The same object as a simplicial mesh on the same nodes (same numbering): each quad is split
/// into 2 triangles along its (0,2) diagonal, each hex into the 6 tets of the Kuhn split along
/// its (0,6) diagonal (the split make_grid uses, so splitting a Hex8 grid gives exactly the Tet4
/// grid, element for element). Element s of the result comes from element
/// s / simplices_per_element(mesh.type) and keeps its material id. A simplicial mesh is
/// returned unchanged (without GridInfo for split meshes).
///
/// The Kuhn split cuts every hex face along the diagonal through the corners with local
/// reference coordinates (0,0) and (1,1) of that face; two hexes sharing a face therefore cut it
/// alike when their local axes agree, as in any structured grid.
/// @throws Error if a resulting simplex is inverted or degenerate (a strongly distorted hex), or
///         if two hexes cut a shared face along different diagonals (the result would not be
///         conforming), naming the element
Mesh simplex_split(const Mesh& mesh);

}  // namespace coarsegrain::mesh
