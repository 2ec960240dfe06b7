#pragma once
/// @file Node-element incidence, node adjacency, block sparsity patterns and an OpenMP loop
/// that carries exceptions out of the parallel region (private to src/fem).
#include <exception>
#include <mutex>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem::detail {

/// Loops shorter than this run on one thread: a parallel region costs a barrier, which is
/// expensive on a busy machine (and small meshes gain nothing from threads).
inline constexpr Index kMinParallel = 512;

/// Runs f(i) for i in [0, n) on all OpenMP threads (static schedule). The first exception thrown
/// by any f(i) is rethrown after the loop; the remaining iterations still run.
template <class F>
void parallel_for(Index n, F&& f) {
    std::exception_ptr error;
    std::mutex mutex;
#pragma omp parallel for schedule(static) if (n >= kMinParallel)
    for (Index i = 0; i < n; ++i) {
        try {
            f(i);
        } catch (...) {
            const std::lock_guard<std::mutex> lock(mutex);
            if (!error) error = std::current_exception();
        }
    }
    if (error) std::rethrow_exception(error);
}

/// Runs f() for element e; an Error it throws is rethrown, its type kept, with "element e: " in
/// front, so a kernel's message (e.g. an inverted element) names the element.
template <class F>
decltype(auto) for_element(Index e, F&& f) {
    try {
        return f();
    } catch (const Error& error) {
        error.rethrow_with(fmt::format("element {}: {}", e, error.what()));
    }
}

/// Checks that mats describes the elements of mesh: one valid table index per element and the
/// mesh's dimension. `what` names the caller in the message.
void verify_materials(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                      const char* what);

/// Node -> incident elements (CSR), each with the node's local index in that element.
/// Elements of a node are in increasing order.
struct NodeElements {
    std::vector<Index> ptr;  ///< #V + 1 offsets
    std::vector<Index> element;
    std::vector<int> local;
};
NodeElements node_elements(const mesh::Mesh& mesh);

/// Node adjacency (CSR): for every node the sorted list of the nodes it shares an element with,
/// itself included.
struct NodeGraph {
    std::vector<Index> ptr;  ///< #V + 1 offsets
    std::vector<Index> adj;
};
NodeGraph node_graph(const mesh::Mesh& mesh, const NodeElements& incidence);

/// Compressed (CSC) pattern of a num_dofs square matrix with interleaved DOFs, all values zero.
/// full = true: a dim x dim block per adjacent node pair (stiffness); false: only the diagonal
/// of each block (consistent mass, the same scalar entry for every component). The dim columns
/// of a node share one row pattern: column (v, j) holds per_block * deg(v) entries starting at
/// per_block * dim * graph.ptr[v] + j * per_block * deg(v), per_block = full ? dim : 1.
/// Written into A (resized); the values are zeroed if `zero`, else left for the caller to
/// write.
void block_pattern(const NodeGraph& graph, int dim, bool full, bool zero, SparseMatrix& A);

/// Greedy colouring of the elements: elements that share a node get different colours.
/// Returns the elements grouped by colour: ptr (#colours + 1 offsets) into element.
struct Colouring {
    std::vector<Index> ptr;
    std::vector<Index> element;
    Index num_colours() const { return static_cast<Index>(ptr.size()) - 1; }
};
Colouring colour_elements(const mesh::Mesh& mesh, const NodeElements& incidence);

}  // namespace coarsegrain::fem::detail
