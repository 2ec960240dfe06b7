#pragma once
/// @file Assembly of element matrices into a node-blocked compressed pattern by gathering, one
/// node's columns per parallel iteration (private to src/fem: the stiffness and mass matrices,
/// the corotated tangent).
#include <algorithm>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem::detail {

/// Everything an assembly needs: incidence, adjacency and the compressed matrix A (held by
/// reference: Eigen 3.4's SparseMatrix has no move constructor, so the result is built in the
/// caller's variable to avoid copying hundreds of MB).
struct Skeleton {
    NodeElements incidence;
    NodeGraph graph;
    SparseMatrix& A;
};

/// The incidence and adjacency of `mesh`, and A resized to its block pattern (block_pattern;
/// zero = false leaves the values uninitialized: gather() writes every entry).
inline Skeleton skeleton(const mesh::Mesh& mesh, bool full_blocks, bool zero, SparseMatrix& A) {
    Skeleton s{node_elements(mesh), {}, A};
    s.graph = node_graph(mesh, s.incidence);
    block_pattern(s.graph, mesh.dim(), full_blocks, zero, A);
    return s;
}

/// Writes the sum of the element matrices into s.A, one node per parallel iteration (threads
/// write disjoint columns: race free without colouring). column(e, b) returns the columns of
/// local node b of element e's matrix: with Full, its npe*dim x dim column block (C(dim*a + i,
/// j) couples component i of local node a with component j of node b); otherwise the npe
/// scalar entries C(a) of a scalar element matrix, written on the diagonal of each block. Each
/// node's columns are zeroed here (they are contiguous and stay in cache), so the pattern's
/// values need not be.
template <class S, bool Full, class ColumnOf>
void gather(const mesh::Mesh& mesh, Skeleton& s, ColumnOf&& column) {
    constexpr int dim = S::dim;
    constexpr int per_block = Full ? dim : 1;
    const Index nv = mesh.num_nodes();
    const Index* outer = s.A.outerIndexPtr();
    double* values = s.A.valuePtr();
#pragma omp parallel if (nv >= kMinParallel)
    {
        // position[w] = index of node w in the adjacency list of the current node.
        std::vector<Index> position(static_cast<std::size_t>(nv), 0);
#pragma omp for schedule(static)
        for (Index v = 0; v < nv; ++v) {
            const Index first = s.graph.ptr[v];
            for (Index p = first; p < s.graph.ptr[v + 1]; ++p) position[s.graph.adj[p]] = p - first;
            std::fill(values + outer[dim * v], values + outer[dim * v + dim], 0.0);
            for (Index k = s.incidence.ptr[v]; k < s.incidence.ptr[v + 1]; ++k) {
                const Index e = s.incidence.element[k];
                const auto& C = column(e, s.incidence.local[k]);
                for (int a = 0; a < S::npe; ++a) {
                    const Index offset = per_block * position[mesh.elements(e, a)];
                    for (int j = 0; j < dim; ++j) {
                        double* col = values + outer[dim * v + j] + offset;
                        if constexpr (Full) {
                            for (int i = 0; i < dim; ++i) col[i] += C(dim * a + i, j);
                        } else {
                            col[0] += C(a);
                        }
                    }
                }
            }
        }
    }
}

}  // namespace coarsegrain::fem::detail
