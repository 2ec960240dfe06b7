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

/// Spatial index over a mesh's elements (uniform bucket grid over element bounding boxes).
/// Holds a reference to the mesh, which must outlive it.
class PointLocator {
public:
    explicit PointLocator(const Mesh& mesh);
    ~PointLocator();
    PointLocator(PointLocator&&) noexcept;
    PointLocator& operator=(PointLocator&&) noexcept;

    /// The element containing p (size dim), within a relative tolerance of 1e-10 of the element
    /// size; std::nullopt if p is outside the mesh.
    std::optional<Location> locate(const Eigen::VectorXd& p) const;

    /// Like locate, but for points outside the mesh returns the closest element, with local
    /// coordinates clamped to it (weights still sum to 1).
    Location locate_nearest(const Eigen::VectorXd& p) const;

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// Interpolates a nodal field (interleaved, `components` values per node) at a location.
Eigen::VectorXd interpolate(const Mesh& mesh, const Location& loc, const Vector& field,
                            int components);

}  // namespace coarsegrain::mesh
