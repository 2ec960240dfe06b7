#pragma once
/// @file The fine (or coarse) mesh: one element type, rest positions, connectivity, material ids.
#include <optional>
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::mesh {

/// Linear element types. Node orderings are those of VTK and Gmsh (identical for these types):
/// - Tri3:  counter-clockwise, positive area.
/// - Quad4: counter-clockwise: (0,0) (1,0) (1,1) (0,1) in reference coordinates.
/// - Tet4:  positive volume, det[x1-x0, x2-x0, x3-x0] > 0.
/// - Hex8:  bottom face counter-clockwise seen from +z, then top face:
///          (0,0,0) (1,0,0) (1,1,0) (0,1,0) (0,0,1) (1,0,1) (1,1,1) (0,1,1).
enum class ElementType { Tri3, Quad4, Tet4, Hex8 };

/// Spatial dimension of an element type (2 or 3).
int element_dim(ElementType type);
/// Number of nodes of an element type (3, 4, 4, 8).
int nodes_per_element(ElementType type);
/// "tri", "quad", "tet", "hex".
std::string element_name(ElementType type);
/// True for Tri3 and Tet4.
bool is_simplex(ElementType type);

/// Description of a regular axis-aligned grid. Set on meshes made by make_grid: all elements
/// of a quad/hex grid are congruent, so element matrices can be computed once.
struct GridInfo {
    Eigen::Vector3d min = Eigen::Vector3d::Zero();  ///< lower corner (z unused in 2D)
    Eigen::Vector3d max = Eigen::Vector3d::Ones();  ///< upper corner
    Eigen::Vector3i cells = Eigen::Vector3i::Ones();  ///< cells per axis (z = 1 in 2D)
    /// Cell size along each axis.
    Eigen::Vector3d spacing() const;
};

/// A mesh with a single element type.
struct Mesh {
    ElementType type = ElementType::Tet4;
    Matrix rest_positions;       ///< #V by dim rest positions
    IndexMatrix elements;        ///< #E by nodes_per_element(type), orderings as in ElementType
    IndexVector material_ids;    ///< #E material id of each element (Gmsh physical tag, grid field)
    std::optional<GridInfo> grid;  ///< set when the mesh is a regular grid (see make_grid)

    int dim() const { return element_dim(type); }
    Index num_nodes() const { return static_cast<Index>(rest_positions.rows()); }
    Index num_elements() const { return static_cast<Index>(elements.rows()); }
    Index num_dofs() const { return dim() * num_nodes(); }
    /// nodes_per_element by dim rest positions of element e's corners.
    Matrix element_positions(Index e) const;
};

/// Checks a mesh for consistency: matching sizes, indices in range, finite coordinates, every
/// element with positive measure (not inverted or degenerate: measure > 1e-12 h^dim).
/// @param[in] source  name used in error messages (e.g. the file name)
/// @throws Error naming the source and the first bad element or node
void validate(const Mesh& mesh, const std::string& source);

/// Signed measure (area/volume) of element e: positive for a correctly oriented element.
/// For quads/hexes the measure of the bilinear/trilinear map is integrated exactly.
double element_measure(const Mesh& mesh, Index e);

/// Axis-aligned bounding box of the mesh, 2 by dim: row 0 min, row 1 max.
Matrix bounding_box(const Mesh& mesh);

/// The elements `kept` of `mesh` (indices, in that order) with the nodes they use, renumbered in
/// their original order; material ids 0, no GridInfo.
/// @throws Error if an index is out of range
Mesh element_subset(const Mesh& mesh, const std::vector<Index>& kept);

}  // namespace coarsegrain::mesh
