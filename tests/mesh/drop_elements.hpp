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
    std::vector<Index> new_id(m.num_nodes(), -1);
    for (Index e : kept)
        for (Index a = 0; a < m.elements.cols(); ++a) new_id[m.elements(e, a)] = 0;
    Index nv = 0;
    for (Index& id : new_id)
        if (id == 0) id = nv++;
    mesh::Mesh out;
    out.type = m.type;
    out.rest_positions.resize(nv, m.dim());
    for (Index v = 0; v < m.num_nodes(); ++v)
        if (new_id[v] >= 0) out.rest_positions.row(new_id[v]) = m.rest_positions.row(v);
    out.elements.resize(static_cast<Index>(kept.size()), m.elements.cols());
    for (size_t i = 0; i < kept.size(); ++i)
        for (Index a = 0; a < m.elements.cols(); ++a)
            out.elements(static_cast<Index>(i), a) = new_id[m.elements(kept[i], a)];
    out.material_ids = IndexVector::Zero(out.num_elements());
    return out;
}

}  // namespace coarsegrain::test
