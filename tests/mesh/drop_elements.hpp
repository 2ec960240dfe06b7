#pragma once
/// @file Test helper: meshes with holes, made by removing elements from a grid.
#include <functional>
#include <vector>

#include "coarsegrain/mesh/grid.hpp"

namespace coarsegrain::test {

/// Removes the elements whose centroid satisfies `drop` and the nodes no longer used,
/// renumbering the rest in their original order (material ids reset to 0).
inline mesh::Mesh drop_elements(const mesh::Mesh& m,
                                const std::function<bool(const Eigen::VectorXd&)>& drop) {
    const Matrix centres = mesh::element_centroids(m);
    std::vector<Index> kept;
    for (Index e = 0; e < m.num_elements(); ++e)
        if (!drop(centres.row(e).transpose())) kept.push_back(e);
    return mesh::element_subset(m, kept);
}

}  // namespace coarsegrain::test
