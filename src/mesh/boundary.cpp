#include "coarsegrain/mesh/boundary.hpp"

#include <algorithm>
#include <array>
#include <numeric>
#include <span>
#include <utility>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::mesh {

namespace {

// Local facets of each element type, node lists in outward order (see Boundary).
constexpr std::array<std::array<int, 4>, 3> kTriEdges = {{{0, 1}, {1, 2}, {2, 0}}};
constexpr std::array<std::array<int, 4>, 4> kQuadEdges = {{{0, 1}, {1, 2}, {2, 3}, {3, 0}}};
constexpr std::array<std::array<int, 4>, 4> kTetFaces = {
    {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {0, 2, 1}}};
constexpr std::array<std::array<int, 4>, 6> kHexFaces = {
    {{0, 4, 7, 3}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 3, 2, 1}, {4, 5, 6, 7}}};

struct FacetTable {
    std::span<const std::array<int, 4>> facets;
    int nodes = 0;  // nodes per facet
};

FacetTable facet_table(ElementType type) {
    switch (type) {
        case ElementType::Tri3:
            return {kTriEdges, 2};
        case ElementType::Quad4:
            return {kQuadEdges, 2};
        case ElementType::Tet4:
            return {kTetFaces, 3};
        case ElementType::Hex8:
            return {kHexFaces, 4};
    }
    return {};
}

using FacetKey = std::array<Index, 4>;

// Node list of local facet lf of element e, sorted, unused slots -1.
FacetKey facet_key(const Mesh& mesh, const FacetTable& table, Index e, int lf) {
    FacetKey key;
    key.fill(-1);
    // Insertion sort of at most 4 values (std::sort is slower here, and GCC 12 misreads its
    // bounds on a variable-length prefix of a std::array).
    for (int a = 0; a < table.nodes; ++a) {
        const Index v = mesh.elements(e, table.facets[lf][a]);
        int b = a;
        for (; b > 0 && key[b - 1] > v; --b) key[b] = key[b - 1];
        key[b] = v;
    }
    return key;
}

Index facet_min_node(const Mesh& mesh, const FacetTable& table, Index e, int lf) {
    Index m = mesh.elements(e, table.facets[lf][0]);
    for (int a = 1; a < table.nodes; ++a) m = std::min(m, mesh.elements(e, table.facets[lf][a]));
    return m;
}

// Union-find with path halving (over nodes or elements).
Index find_root(std::vector<Index>& parent, Index v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

void unite(std::vector<Index>& parent, Index a, Index b) {
    a = find_root(parent, a);
    b = find_root(parent, b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

// For each local facet (flat id e * nf + lf), the flat id of the same facet in the other
// element that has it, or -1 if it belongs to one element only (a boundary facet). Facets are
// bucketed by their smallest node (counting sort), then equal keys are found by sorting each
// small bucket.
std::vector<Index> facet_partners(const Mesh& mesh, const FacetTable& table) {
    const Index ne = mesh.num_elements();
    const Index nv = mesh.num_nodes();
    const int nf = static_cast<int>(table.facets.size());
    const Index total = ne * nf;

    std::vector<Index> start(static_cast<size_t>(nv) + 1, 0);
    for (Index e = 0; e < ne; ++e)
        for (int lf = 0; lf < nf; ++lf) ++start[facet_min_node(mesh, table, e, lf) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<Index> bucket(static_cast<size_t>(total));
    {
        std::vector<Index> fill(start.begin(), start.end() - 1);
        for (Index e = 0; e < ne; ++e)
            for (int lf = 0; lf < nf; ++lf)
                bucket[fill[facet_min_node(mesh, table, e, lf)]++] = e * nf + lf;
    }

    std::vector<Index> partner(static_cast<size_t>(total), -1);
    Index non_manifold = -1;  // a flat facet id shared by more than two elements
#pragma omp parallel
    {
        std::vector<std::pair<FacetKey, Index>> local;
#pragma omp for schedule(dynamic, 4096)
        for (Index v = 0; v < nv; ++v) {
            local.clear();
            for (Index i = start[v]; i < start[v + 1]; ++i) {
                const Index f = bucket[i];
                local.emplace_back(facet_key(mesh, table, f / nf, static_cast<int>(f % nf)), f);
            }
            std::sort(local.begin(), local.end());
            for (size_t i = 0; i < local.size();) {
                size_t j = i + 1;
                while (j < local.size() && local[j].first == local[i].first) ++j;
                if (j - i == 2) {
                    partner[local[i].second] = local[i + 1].second;
                    partner[local[i + 1].second] = local[i].second;
                }
                if (j - i > 2) {
#pragma omp critical(coarsegrain_boundary_non_manifold)
                    non_manifold = std::max(non_manifold, local[i].second);
                }
                i = j;
            }
        }
    }
    CG_VERIFY(non_manifold < 0,
              "boundary: facet {} of {} element {} is shared by more than two elements; the "
              "mesh must be conforming and manifold",
              non_manifold % nf, element_name(mesh.type), non_manifold / nf);
    return partner;
}

// The checks of boundary and element_neighbours on the mesh's arrays.
void verify_elements(const Mesh& mesh, const char* what) {
    const int npe = nodes_per_element(mesh.type);
    CG_VERIFY(mesh.elements.cols() == npe, "{}: {} elements need {} nodes, got {}", what,
              element_name(mesh.type), npe, mesh.elements.cols());
    if (mesh.num_elements() > 0) {
        const Index lo = mesh.elements.minCoeff(), hi = mesh.elements.maxCoeff();
        CG_VERIFY(lo >= 0 && hi < mesh.num_nodes(),
                  "{}: elements refer to nodes {}..{}, but nodes are numbered 0..{}", what, lo, hi,
                  mesh.num_nodes() - 1);
    }
}

// Outward normals and measures of the facets.
void facet_geometry(const Mesh& mesh, Boundary& b) {
    const int dim = mesh.dim();
    const Index nb = b.size();
    b.normals.resize(nb, dim);
    b.areas.resize(nb);
    const auto X = [&](Index f, int a) -> Eigen::VectorXd {
        return mesh.rest_positions.row(b.facets(f, a)).transpose();
    };
#pragma omp parallel for schedule(static)
    for (Index f = 0; f < nb; ++f) {
        Eigen::VectorXd n(dim);
        if (dim == 2) {
            const Eigen::Vector2d t = X(f, 1) - X(f, 0);
            n = Eigen::Vector2d(t.y(), -t.x());
        } else if (b.facets.cols() == 3) {
            const Eigen::Vector3d u = X(f, 1) - X(f, 0), w = X(f, 2) - X(f, 0);
            n = 0.5 * u.cross(w);
        } else {
            const Eigen::Vector3d d0 = X(f, 2) - X(f, 0), d1 = X(f, 3) - X(f, 1);
            n = 0.5 * d0.cross(d1);
        }
        const double a = n.norm();
        b.areas[f] = a;
        b.normals.row(f) = (a > 0 ? n / a : n).transpose();
    }
}

// Connected components of the boundary (facets sharing a node), numbered as documented.
void facet_components(const Mesh& mesh, Boundary& b) {
    const Index nb = b.size();
    b.component.resize(nb);
    b.num_components = 0;
    if (nb == 0) return;
    std::vector<Index> parent(static_cast<size_t>(mesh.num_nodes()));
    std::iota(parent.begin(), parent.end(), 0);
    for (Index f = 0; f < nb; ++f)
        for (Index a = 1; a < b.facets.cols(); ++a) unite(parent, b.facets(f, 0), b.facets(f, a));

    // The boundary node that is smallest in (x, y, z) lexicographic order is a vertex of the
    // convex hull, so it lies on the outer boundary.
    Index extreme = b.facets(0, 0);
    const auto less = [&](Index u, Index v) {
        for (int d = 0; d < mesh.dim(); ++d) {
            if (mesh.rest_positions(u, d) != mesh.rest_positions(v, d))
                return mesh.rest_positions(u, d) < mesh.rest_positions(v, d);
        }
        return u < v;
    };
    for (Index f = 0; f < nb; ++f)
        for (Index a = 0; a < b.facets.cols(); ++a)
            if (less(b.facets(f, a), extreme)) extreme = b.facets(f, a);
    const Index outer_root = find_root(parent, extreme);

    // Per root: facet count and first facet.
    std::vector<Index> label(static_cast<size_t>(mesh.num_nodes()), -1);
    struct Part {
        Index root, count, first;
    };
    std::vector<Part> parts;
    for (Index f = 0; f < nb; ++f) {
        const Index r = find_root(parent, b.facets(f, 0));
        if (label[r] < 0) {
            label[r] = static_cast<Index>(parts.size());
            parts.push_back({r, 0, f});
        }
        ++parts[label[r]].count;
        b.component[f] = label[r];
    }
    std::vector<Index> order(parts.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](Index i, Index j) {
        const bool oi = parts[i].root == outer_root, oj = parts[j].root == outer_root;
        if (oi != oj) return oi;
        if (parts[i].count != parts[j].count) return parts[i].count > parts[j].count;
        return parts[i].first < parts[j].first;
    });
    std::vector<Index> renumber(parts.size());
    for (size_t k = 0; k < order.size(); ++k) renumber[order[k]] = static_cast<Index>(k);
    for (Index f = 0; f < nb; ++f) b.component[f] = renumber[b.component[f]];
    b.num_components = static_cast<Index>(parts.size());
}

}  // namespace

Boundary boundary(const Mesh& mesh) {
    const FacetTable table = facet_table(mesh.type);
    verify_elements(mesh, "boundary");
    CG_VERIFY(mesh.rest_positions.cols() == mesh.dim(),
              "boundary: a {} mesh needs {} coordinates per node, got {}", element_name(mesh.type),
              mesh.dim(), mesh.rest_positions.cols());
    const int nf = static_cast<int>(table.facets.size());
    const std::vector<Index> partner = facet_partners(mesh, table);

    const Index nb = static_cast<Index>(std::count(partner.begin(), partner.end(), Index{-1}));
    Boundary b;
    b.facets.resize(nb, table.nodes);
    b.owner.resize(nb);
    b.local_facet.resize(nb);
    Index k = 0;
    for (size_t f = 0; f < partner.size(); ++f) {
        if (partner[f] >= 0) continue;
        const Index e = static_cast<Index>(f / nf);
        const int lf = static_cast<int>(f % nf);
        b.owner[k] = e;
        b.local_facet[k] = lf;
        for (int a = 0; a < table.nodes; ++a)
            b.facets(k, a) = mesh.elements(e, table.facets[lf][a]);
        ++k;
    }
    facet_geometry(mesh, b);
    facet_components(mesh, b);
    return b;
}

IndexMatrix element_neighbours(const Mesh& mesh) {
    const FacetTable table = facet_table(mesh.type);
    verify_elements(mesh, "element_neighbours");
    const Index nf = static_cast<Index>(table.facets.size());
    const std::vector<Index> partner = facet_partners(mesh, table);
    IndexMatrix neighbours(mesh.num_elements(), nf);
    for (Index f = 0; f < static_cast<Index>(partner.size()); ++f)
        neighbours(f / nf, f % nf) = partner[f] < 0 ? -1 : partner[f] / nf;
    return neighbours;
}

IndexVector element_components(const Mesh& mesh, const IndexVector& labels, Index& count) {
    const Index ne = mesh.num_elements();
    CG_VERIFY(labels.size() == ne, "element_components: {} labels for {} elements", labels.size(),
              ne);
    const IndexMatrix neighbours = element_neighbours(mesh);
    std::vector<Index> parent(static_cast<size_t>(ne));
    std::iota(parent.begin(), parent.end(), Index{0});
    for (Index e = 0; e < ne; ++e)
        for (Index f = 0; labels[e] >= 0 && f < neighbours.cols(); ++f)
            if (const Index n = neighbours(e, f); n >= 0 && labels[n] == labels[e])
                unite(parent, e, n);
    IndexVector component = IndexVector::Constant(ne, -1);
    std::vector<Index> number(static_cast<size_t>(ne), -1);
    count = 0;
    for (Index e = 0; e < ne; ++e) {
        if (labels[e] < 0) continue;
        Index& n = number[static_cast<size_t>(find_root(parent, e))];
        if (n < 0) n = count++;
        component[e] = n;
    }
    return component;
}

std::vector<Index> boundary_nodes(const Boundary& b, Index component) {
    CG_VERIFY(component == -1 || (component >= 0 && component < b.num_components),
              "boundary_nodes: component {} does not exist (the boundary has {} components; -1 "
              "selects all)",
              component, b.num_components);
    std::vector<Index> nodes;
    nodes.reserve(static_cast<size_t>(b.facets.size()));
    for (Index f = 0; f < b.size(); ++f)
        if (component < 0 || b.component[f] == component)
            for (Index a = 0; a < b.facets.cols(); ++a) nodes.push_back(b.facets(f, a));
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    return nodes;
}

}  // namespace coarsegrain::mesh
