#pragma once
/// @file Boundary extraction and boundary connected components.
#include <vector>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// The boundary facets of a mesh: faces (3D) or edges (2D) that belong to exactly one element.
///
/// Local facet numbering (VTK), with node lists already in outward order:
/// - Tri3/Quad4: edge i joins corners i and i+1 (mod 3 or 4).
/// - Tet4:  (0,1,3) (1,2,3) (2,0,3) (0,2,1).
/// - Hex8:  (0,4,7,3) x=0, (1,2,6,5) x=1, (0,1,5,4) y=0, (3,7,6,2) y=1, (0,3,2,1) z=0,
///          (4,5,6,7) z=1 (the planes of the reference cube).
struct Boundary {
    /// #F by nodes per facet (2 for edges, 3 for triangles, 4 for quads), ordered so that the
    /// facet's normal (right-hand rule in 3D, (dy, -dx) of the edge in 2D) points out of the
    /// owner element. Facets are listed by owner element, then local facet index.
    IndexMatrix facets;
    IndexVector owner;        ///< #F element that owns each facet
    IndexVector local_facet;  ///< #F index of the facet within its owner element
    /// #F by dim unit outward normals at the facet centre. For a quad facet the normal at the
    /// centre of the bilinear patch is parallel to its vector area (p2 - p0) x (p3 - p1) / 2.
    Matrix normals;
    /// #F facet measure: length in 2D, area in 3D. For a non-planar quad facet this is the norm
    /// of its vector area (exact for planar quads), so that sum(normals * areas) = 0 holds
    /// exactly for every closed boundary.
    Vector areas;
    /// #F connected component of each facet (facets sharing a node are connected). Component 0
    /// is the outer boundary: the component of the boundary node with the smallest x (then y,
    /// z), which lies on the convex hull. The others (cavities, or the outer boundaries of
    /// further disconnected parts) are numbered 1.. by decreasing facet count, ties by their
    /// first facet.
    IndexVector component;
    Index num_components = 0;

    Index size() const { return static_cast<Index>(facets.rows()); }
};

/// Extracts the boundary facets with owners, outward normals, areas and connected components.
///
/// Facets are matched by their sorted node lists, bucketed by smallest node (linear time,
/// OpenMP-parallel), so a 10^6-element mesh takes well under a second.
/// @param[in] mesh  a conforming mesh (elements meet face to face)
/// @throws Error if an element refers to a missing node, or a facet is shared by more than
///         two elements (a non-manifold mesh)
Boundary boundary(const Mesh& mesh);

/// The element across each facet (face in 3D, edge in 2D; local numbering as Boundary's): #E by
/// facets per element, -1 where the facet is on the boundary. Matched as boundary() does.
/// @throws Error as boundary() on bad element arrays or a non-manifold mesh
IndexMatrix element_neighbours(const Mesh& mesh);

/// Connected components of the elements with a label >= 0, two elements being connected when
/// they share a facet and have the same label (element_neighbours).
/// @param[in]  labels  #E label per element; < 0: in no component
/// @param[out] count   the number of components
/// @return #E component of each element, numbered 0..count-1 by their first element, -1 where
///         the label is < 0
/// @throws Error if labels has not #E entries, or as element_neighbours
IndexVector element_components(const Mesh& mesh, const IndexVector& labels, Index& count);

/// Sorted list of the nodes on the boundary (optionally only those of one component; -1 means
/// all). @throws Error if component is not -1 or in [0, b.num_components)
std::vector<Index> boundary_nodes(const Boundary& b, Index component = -1);

/// Nodes whose rest positions lie in the closed box [lo, hi] (each of size dim), sorted.
std::vector<Index> nodes_in_box(const Mesh& mesh, const Eigen::VectorXd& lo,
                                const Eigen::VectorXd& hi);

/// Boundary facets all of whose nodes lie in the closed box [lo, hi], as indices into b.
std::vector<Index> facets_in_box(const Mesh& mesh, const Boundary& b, const Eigen::VectorXd& lo,
                                 const Eigen::VectorXd& hi);

}  // namespace coarsegrain::mesh
