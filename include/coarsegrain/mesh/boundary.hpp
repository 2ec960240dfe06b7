#pragma once
/// @file Boundary extraction and boundary connected components.
#include <vector>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// The boundary facets of a mesh: faces (3D) or edges (2D) that belong to exactly one element.
struct Boundary {
    /// #F by nodes per facet (2 for edges, 3 for triangles, 4 for quads), ordered so that the
    /// facet's normal (right-hand rule in 3D, (dy, -dx) of the edge in 2D) points out of the
    /// owner element.
    IndexMatrix facets;
    IndexVector owner;        ///< #F element that owns each facet
    IndexVector local_facet;  ///< #F index of the facet within its owner element
    Matrix normals;           ///< #F by dim unit outward normals (at the facet centre)
    Vector areas;             ///< #F facet measure (length in 2D, area in 3D)
    /// #F connected component of each facet (facets sharing a node are connected); component 0
    /// is the outer boundary (the one reaching the bounding box), the rest are cavities.
    IndexVector component;
    Index num_components = 0;

    Index size() const { return static_cast<Index>(facets.rows()); }
};

/// Extracts the boundary facets with owners, outward normals, areas and connected components.
Boundary boundary(const Mesh& mesh);

/// Sorted list of the nodes on the boundary (optionally only those of one component).
std::vector<Index> boundary_nodes(const Boundary& b, Index component = -1);

/// Nodes whose rest positions lie in the closed box [lo, hi] (each of size dim), sorted.
std::vector<Index> nodes_in_box(const Mesh& mesh, const Eigen::VectorXd& lo,
                                const Eigen::VectorXd& hi);

/// Boundary facets all of whose nodes lie in the closed box [lo, hi], as indices into b.
std::vector<Index> facets_in_box(const Mesh& mesh, const Boundary& b, const Eigen::VectorXd& lo,
                                 const Eigen::VectorXd& hi);

}  // namespace coarsegrain::mesh
