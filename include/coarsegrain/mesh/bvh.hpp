#pragma once
/// @file A static bounding-volume hierarchy (AABB tree) over axis-aligned boxes, in 2D or 3D.
#include <algorithm>
#include <array>
#include <numeric>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::mesh {

/// Closed axis-aligned box in D dimensions (D = 2 or 3).
template <int D>
using Box = Eigen::AlignedBox<double, D>;

/// Static AABB tree over a list of boxes: built once (top-down, median split along the longest
/// axis of the box centres, leaves of at most kLeafSize boxes), then queried for every box
/// that overlaps a query box. O(n log n) build, O(n) memory; a query costs O(log n + k) for k
/// results on well-spread boxes. Queries are const and may run concurrently from several
/// threads.
///
/// @tparam D  dimension, 2 or 3
template <int D>
class AabbTree {
  public:
    static_assert(D == 2 || D == 3, "AabbTree: dimension must be 2 or 3");
    static constexpr Index kLeafSize = 4;

    AabbTree() = default;
    /// Builds the tree; box i of the input is reported as index i by the queries.
    /// @param[in] boxes  #B boxes (empty boxes are never reported)
    explicit AabbTree(std::vector<Box<D>> boxes) : m_boxes(std::move(boxes)) {
        const Index n = static_cast<Index>(m_boxes.size());
        m_order.resize(n);
        std::iota(m_order.begin(), m_order.end(), Index{0});
        if (n == 0) return;
        m_nodes.reserve(2 * static_cast<std::size_t>(n / kLeafSize + 1));
        build(0, n);
    }

    /// Number of boxes the tree was built over.
    Index size() const { return static_cast<Index>(m_boxes.size()); }
    /// Box i as given to the constructor.
    const Box<D>& box(Index i) const { return m_boxes[i]; }

    /// Calls visit(i) once for every box i that overlaps `query` (closed boxes: boxes that only
    /// touch overlap), in no particular order.
    template <class Visit>
    void for_each_overlap(const Box<D>& query, Visit&& visit) const {
        if (m_nodes.empty() || query.isEmpty()) return;
        // Median splits keep the depth below log2(n) + 1 <= 32, so one stack entry per level
        // (the right child waits while the left subtree is searched) always suffices.
        std::array<Index, 64> stack;
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Index id = stack[--top];
            const Node& node = m_nodes[id];
            if (!node.box.intersects(query)) continue;
            if (node.count > 0) {
                for (Index k = node.first; k < node.first + node.count; ++k)
                    if (m_boxes[m_order[k]].intersects(query)) visit(m_order[k]);
            } else {
                stack[top++] = node.right;
                stack[top++] = id + 1;  // left child, searched first
            }
        }
    }

    /// Indices of every box overlapping `query`, ascending.
    std::vector<Index> overlapping(const Box<D>& query) const {
        std::vector<Index> hits;
        for_each_overlap(query, [&](Index i) { hits.push_back(i); });
        std::sort(hits.begin(), hits.end());
        return hits;
    }

  private:
    // Nodes in depth-first order: an inner node's left child follows it, `right` is the index
    // of its right child. A leaf holds boxes m_order[first .. first + count).
    struct Node {
        Box<D> box;
        Index first = 0;
        Index count = 0;  // 0 for inner nodes
        Index right = 0;
    };

    Index build(Index begin, Index end) {
        const Index id = static_cast<Index>(m_nodes.size());
        m_nodes.emplace_back();
        Box<D> box, centres;
        for (Index k = begin; k < end; ++k) {
            box.extend(m_boxes[m_order[k]]);
            centres.extend(m_boxes[m_order[k]].center());
        }
        m_nodes[id].box = box;
        if (end - begin <= kLeafSize) {
            m_nodes[id].first = begin;
            m_nodes[id].count = end - begin;
            return id;
        }
        int axis = 0;
        centres.sizes().maxCoeff(&axis);
        const Index mid = begin + (end - begin) / 2;
        std::nth_element(m_order.begin() + begin, m_order.begin() + mid, m_order.begin() + end,
                         [&](Index i, Index j) {
                             return m_boxes[i].center()[axis] < m_boxes[j].center()[axis];
                         });
        build(begin, mid);
        const Index right = build(mid, end);
        m_nodes[id].right = right;
        return id;
    }

    std::vector<Box<D>> m_boxes;
    std::vector<Index> m_order;  // box indices, grouped by leaf
    std::vector<Node> m_nodes;
};

/// Bounding box of every element of a mesh (any element type), #E boxes.
/// @tparam D  the mesh's dimension
/// @throws Error if the mesh's dimension is not D
template <int D>
std::vector<Box<D>> element_boxes(const Mesh& mesh) {
    CG_VERIFY(mesh.dim() == D && mesh.rest_positions.cols() == D,
              "element_boxes: a {}D mesh of {} elements was given where a {}D mesh is needed",
              mesh.dim(), element_name(mesh.type), D);
    const Index ne = mesh.num_elements();
    std::vector<Box<D>> boxes(static_cast<std::size_t>(ne));
#pragma omp parallel for schedule(static)
    for (Index e = 0; e < ne; ++e)
        for (Eigen::Index a = 0; a < mesh.elements.cols(); ++a)
            boxes[e].extend(mesh.rest_positions.row(mesh.elements(e, a)).transpose());
    return boxes;
}

}  // namespace coarsegrain::mesh
