#include "mesh_graph.hpp"

#include <algorithm>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::fem::detail {

void verify_materials(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                      const char* what) {
    CG_VERIFY(mats.size() == mesh.num_elements(), "{}: {} element materials for {} elements", what,
              mats.size(), mesh.num_elements());
    CG_VERIFY(mats.dim == mesh.dim(), "{}: materials are {}D but the mesh is {}D", what, mats.dim,
              mesh.dim());
    const Index nt = static_cast<Index>(mats.table.size());
    for (Index e = 0; e < mats.size(); ++e)
        CG_VERIFY(mats.index[e] >= 0 && mats.index[e] < nt,
                  "{}: element {} uses material {} of a table of {}", what, e, mats.index[e], nt);
}

NodeElements node_elements(const mesh::Mesh& mesh) {
    const Index nv = mesh.num_nodes(), ne = mesh.num_elements();
    const int npe = static_cast<int>(mesh.elements.cols());
    NodeElements inc;
    inc.ptr.assign(static_cast<std::size_t>(nv) + 1, 0);
    for (Index e = 0; e < ne; ++e)
        for (int a = 0; a < npe; ++a) {
            const Index v = mesh.elements(e, a);
            CG_VERIFY(v >= 0 && v < nv,
                      "element {} refers to node {}, but nodes are numbered 0..{}", e, v, nv - 1);
            ++inc.ptr[static_cast<std::size_t>(v) + 1];
        }
    for (Index v = 0; v < nv; ++v) inc.ptr[v + 1] += inc.ptr[v];
    inc.element.resize(static_cast<std::size_t>(inc.ptr[nv]));
    inc.local.resize(inc.element.size());
    std::vector<Index> next(inc.ptr.begin(), inc.ptr.end() - 1);
    for (Index e = 0; e < ne; ++e)
        for (int a = 0; a < npe; ++a) {
            const Index k = next[mesh.elements(e, a)]++;
            inc.element[k] = e;
            inc.local[k] = a;
        }
    return inc;
}

NodeGraph node_graph(const mesh::Mesh& mesh, const NodeElements& inc) {
    const Index nv = mesh.num_nodes();
    const int npe = static_cast<int>(mesh.elements.cols());
    NodeGraph g;
    g.ptr.assign(static_cast<std::size_t>(nv) + 1, 0);
    // Two passes (count, then fill) over each node's incident elements; a per-thread stamp
    // array removes duplicates in O(1) per visited node.
    const auto visit = [&](std::vector<Index>& stamp, Index v, auto&& emit) {
        for (Index k = inc.ptr[v]; k < inc.ptr[v + 1]; ++k)
            for (int a = 0; a < npe; ++a) {
                const Index w = mesh.elements(inc.element[k], a);
                if (stamp[w] != v) {
                    stamp[w] = v;
                    emit(w);
                }
            }
    };
#pragma omp parallel if (nv >= kMinParallel)
    {
        std::vector<Index> stamp(static_cast<std::size_t>(nv), -1);
#pragma omp for schedule(static)
        for (Index v = 0; v < nv; ++v) {
            Index count = 0;
            visit(stamp, v, [&](Index) { ++count; });
            g.ptr[v + 1] = count;
        }
    }
    for (Index v = 0; v < nv; ++v) g.ptr[v + 1] += g.ptr[v];
    g.adj.resize(static_cast<std::size_t>(g.ptr[nv]));
#pragma omp parallel if (nv >= kMinParallel)
    {
        std::vector<Index> stamp(static_cast<std::size_t>(nv), -1);
#pragma omp for schedule(static)
        for (Index v = 0; v < nv; ++v) {
            Index* out = g.adj.data() + g.ptr[v];
            Index n = 0;
            visit(stamp, v, [&](Index w) { out[n++] = w; });
            std::sort(out, out + n);
        }
    }
    return g;
}

void block_pattern(const NodeGraph& g, int dim, bool full, bool zero, SparseMatrix& A) {
    const Index nv = static_cast<Index>(g.ptr.size()) - 1;
    const Index n = dim * nv;
    const Index per_block = full ? dim : 1;  // rows per adjacent node in one column
    A.resize(n, n);
    const std::size_t nnz = static_cast<std::size_t>(per_block * dim * g.ptr[nv]);
    A.resizeNonZeros(static_cast<Index>(nnz));
    Index* outer = A.outerIndexPtr();
    Index* inner = A.innerIndexPtr();
    double* values = A.valuePtr();
#pragma omp parallel for schedule(static) if (nv >= kMinParallel)
    for (Index v = 0; v < nv; ++v) {
        const Index deg = g.ptr[v + 1] - g.ptr[v];
        for (int j = 0; j < dim; ++j) {
            const Index start = per_block * dim * g.ptr[v] + j * per_block * deg;
            outer[dim * v + j] = start;
            if (zero) std::fill(values + start, values + start + per_block * deg, 0.0);
            Index k = start;
            for (Index p = g.ptr[v]; p < g.ptr[v + 1]; ++p) {
                if (full) {
                    for (int i = 0; i < dim; ++i) inner[k++] = dim * g.adj[p] + i;
                } else {
                    inner[k++] = dim * g.adj[p] + j;
                }
            }
        }
    }
    outer[n] = per_block * dim * g.ptr[nv];
}

Colouring colour_elements(const mesh::Mesh& mesh, const NodeElements& inc) {
    const Index ne = mesh.num_elements();
    const int npe = static_cast<int>(mesh.elements.cols());
    std::vector<Index> colour(static_cast<std::size_t>(ne), -1);
    std::vector<Index> taken;  // taken[c] == e: colour c is used by a neighbour of element e
    Index num_colours = 0;
    for (Index e = 0; e < ne; ++e) {
        for (int a = 0; a < npe; ++a) {
            const Index v = mesh.elements(e, a);
            for (Index k = inc.ptr[v]; k < inc.ptr[v + 1]; ++k) {
                const Index c = colour[inc.element[k]];
                if (c >= 0) taken[c] = e;
            }
        }
        Index c = 0;
        while (c < num_colours && taken[c] == e) ++c;
        if (c == num_colours) {
            taken.push_back(-1);
            ++num_colours;
        }
        colour[e] = c;
    }
    Colouring out;
    out.ptr.assign(static_cast<std::size_t>(num_colours) + 1, 0);
    for (Index e = 0; e < ne; ++e) ++out.ptr[colour[e] + 1];
    for (Index c = 0; c < num_colours; ++c) out.ptr[c + 1] += out.ptr[c];
    out.element.resize(static_cast<std::size_t>(ne));
    std::vector<Index> next(out.ptr.begin(), out.ptr.end() - 1);
    for (Index e = 0; e < ne; ++e) out.element[next[colour[e]]++] = e;
    return out;
}

}  // namespace coarsegrain::fem::detail
