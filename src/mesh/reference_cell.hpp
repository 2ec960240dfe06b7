#pragma once
// The unit grid cell and its splits into simplices, shared by make_grid and split_to_simplices
// (private to src/mesh). Corners are named by bit patterns of the reference cell: x = 1, y = 2,
// z = 4.
#include <array>

namespace coarsegrain::mesh::detail {

/// Hex8 / Quad4 corner order as bit patterns. The orderings swap patterns 2 <-> 3 (and
/// 6 <-> 7), so each table is its own inverse: it also maps a bit pattern to its local index.
constexpr std::array<int, 8> kHexCorners = {0, 1, 3, 2, 4, 5, 7, 6};
constexpr std::array<int, 4> kQuadCorners = {0, 1, 3, 2};

/// Kuhn split of the cube into 6 tets: each tet is a monotone path 0 -> 7 that adds the axes in
/// one order. Odd permutations are listed with their last two nodes swapped, so that every tet
/// is positively oriented.
constexpr std::array<std::array<int, 4>, 6> kKuhnTets = {{
    {0, 1, 3, 7},  // x y z
    {0, 1, 7, 5},  // x z y (odd)
    {0, 2, 7, 3},  // y x z (odd)
    {0, 2, 6, 7},  // y z x
    {0, 4, 5, 7},  // z x y
    {0, 4, 7, 6},  // z y x (odd)
}};

/// Two triangles split along the (0,0)-(1,1) diagonal, both counter-clockwise.
constexpr std::array<std::array<int, 3>, 2> kTriangles = {{{0, 1, 3}, {0, 3, 2}}};

}  // namespace coarsegrain::mesh::detail
