#pragma once
/// @file Point location: which element contains a point, and its local coordinates there.
#include <memory>
#include <optional>

#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// Where a point lies in a mesh.
struct Location {
    Index element = -1;
    /// Local coordinates: barycentric (dim+1 weights summing to 1) for simplices, reference
    /// coordinates in [0,1]^dim for quads/hexes.
    Eigen::VectorXd local;
    /// Interpolation weights of the element's nodes at the point (nodes_per_element values):
    /// barycentric for simplices, bilinear/trilinear for quads/hexes.
    Eigen::VectorXd weights;
};

/// Spatial index over a mesh's elements (uniform bucket grid over element bounding boxes,
/// about one bucket per element). Holds a reference to the mesh, which must outlive it and
/// not move its nodes. Queries are const and may run concurrently from several threads.
class PointLocator {
  public:
    /// Builds the bucket grid: O(#E) time and memory.
    /// @throws Error if the mesh has no elements or inconsistent sizes
    explicit PointLocator(const Mesh& mesh);
    ~PointLocator();
    PointLocator(PointLocator&&) noexcept;
    PointLocator& operator=(PointLocator&&) noexcept;

    /// The element containing p (size dim), or std::nullopt if p is outside the mesh.
    ///
    /// A point is inside an element when its barycentric coordinates (simplices) or reference
    /// coordinates (quads/hexes, from Newton's method on the bilinear/trilinear map, converged
    /// to 1e-15) are in [0, 1] up to 1e-10, i.e. within about 1e-10 element sizes. A point on
    /// a face shared by several elements gets the first one found. The local coordinates and
    /// weights are not clamped, so interpolation reproduces linear fields to round-off.
    /// @throws Error if p has the wrong size or a non-finite coordinate
    std::optional<Location> locate(const Eigen::VectorXd& p) const;

    /// Like locate, but for points outside the mesh (including inside a cavity) returns the
    /// element nearest to p, with the local coordinates of the point of that element nearest
    /// to p: for simplices the Euclidean projection onto the simplex (barycentric coordinates
    /// >= 0), for quads/hexes the minimizer of |x(xi) - p| over xi in [0,1]^dim (projected
    /// Gauss-Newton; exact for affine elements, a local minimum on strongly curved ones).
    /// Weights are >= 0 and sum to 1. The search visits buckets in rings around p until no
    /// closer element can remain.
    Location locate_nearest(const Eigen::VectorXd& p) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// Barycentric coordinates (dim + 1, summing to 1) of p in simplex e of `mesh`, not clamped:
/// negative outside the simplex, i.e. the weights of the affine extrapolation of the element's
/// linear interpolant to p.
/// @throws Error if the mesh is not simplicial or element e is degenerate
Eigen::VectorXd barycentric_coordinates(const Mesh& mesh, Index e, const Eigen::VectorXd& p);

/// Interpolates a nodal field (interleaved, `components` values per node) at a location:
/// sum over the element's nodes a of weights[a] * field(node a).
/// @return `components` values
/// @throws Error if the field size is not components * #V or loc does not fit the mesh
Eigen::VectorXd interpolate(const Mesh& mesh, const Location& loc, const Vector& field,
                            int components);

}  // namespace coarsegrain::mesh
