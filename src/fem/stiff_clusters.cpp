#include "coarsegrain/fem/stiff_clusters.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <exception>
#include <mutex>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/solve/spd_solver.hpp"
#include "mesh_graph.hpp"

namespace coarsegrain::fem {

namespace {

/// Singular values of a cluster's rigid motions below this fraction of the largest are
/// directions the Dirichlet conditions remove (a cluster fixed along a line keeps its rotation
/// about it).
constexpr double kRankTolerance = 1e-8;

/// The rigid motions of `nodes` about their centroid: dim * #nodes by dim(dim+1)/2
/// (translations, then rotations: about z in 2D; about x, y, z in 3D), interleaved DOFs.
Matrix rigid_motions(const mesh::Mesh& mesh, const std::vector<Index>& nodes) {
    const int dim = mesh.dim();
    const Index k = static_cast<Index>(nodes.size());
    Eigen::RowVectorXd centre = Eigen::RowVectorXd::Zero(dim);
    for (const Index v : nodes) centre += mesh.rest_positions.row(v);
    centre /= static_cast<double>(k);
    Matrix R = Matrix::Zero(dim * k, dim * (dim + 1) / 2);
    for (Index a = 0; a < k; ++a) {
        const Eigen::RowVectorXd x =
            mesh.rest_positions.row(nodes[static_cast<size_t>(a)]) - centre;
        for (int d = 0; d < dim; ++d) R(dim * a + d, d) = 1;
        if (dim == 2) {
            R(2 * a, 2) = -x[1];
            R(2 * a + 1, 2) = x[0];
        } else {
            R(3 * a + 1, 3) = -x[2];  // about x: (0, -z, y)
            R(3 * a + 2, 3) = x[1];
            R(3 * a, 4) = x[2];  // about y: (z, 0, -x)
            R(3 * a + 2, 4) = -x[0];
            R(3 * a, 5) = -x[1];  // about z: (-y, x, 0)
            R(3 * a + 1, 5) = x[0];
        }
    }
    return R;
}

/// The number of singular values above kRankTolerance times the largest.
Index rank(const Vector& sigma) {
    Index r = 0;
    while (r < sigma.size() && sigma[r] > kRankTolerance * sigma[0]) ++r;
    return r;
}

/// Reusable per-thread maps from free DOFs to local rows (-1: none), reset after each use.
struct Scratch {
    std::vector<Index> interior;  ///< free DOF -> row of the extension's unknowns
    std::vector<Index> boundary;  ///< free DOF -> row of the cluster's values
    std::vector<Index> seen;      ///< node -> last cluster that reached it
};

/// The free DOFs of the nodes within `rings` rings of `nodes` through nodes of no cluster
/// (breadth first over the node graph), sorted; seen[v] == c marks the nodes reached.
std::vector<Index> ring_dofs(const std::vector<Index>& nodes, const std::vector<int>& in_cluster,
                             const detail::NodeGraph& graph,
                             const std::vector<Index>& free_position, int dim, int rings, Index c,
                             std::vector<Index>& seen) {
    std::vector<Index> front = nodes, reached;
    for (const Index v : nodes) seen[static_cast<size_t>(v)] = c;
    for (int ring = 0; ring < rings && !front.empty(); ++ring) {
        std::vector<Index> next;
        for (const Index v : front)
            for (Index i = graph.ptr[static_cast<size_t>(v)];
                 i < graph.ptr[static_cast<size_t>(v) + 1]; ++i) {
                const Index w = graph.adj[static_cast<size_t>(i)];
                if (seen[static_cast<size_t>(w)] == c || in_cluster[static_cast<size_t>(w)] > 0)
                    continue;
                seen[static_cast<size_t>(w)] = c;
                next.push_back(w);
            }
        reached.insert(reached.end(), next.begin(), next.end());
        front = std::move(next);
    }
    std::vector<Index> dofs;
    for (const Index v : reached)
        for (int d = 0; d < dim; ++d)
            if (const Index p = free_position[static_cast<size_t>(dim * v + d)]; p >= 0)
                dofs.push_back(p);
    std::sort(dofs.begin(), dofs.end());
    return dofs;
}

/// A cluster's rigid motions over its nodes' DOFs (rows as rigid_motions; `dofs`: the free DOF
/// of each row, -1 for a fixed one, whose row is zero), orthonormal, the directions the Dirichlet
/// conditions remove dropped. No columns when its own nodes (in_cluster 1) do not carry every
/// direction kept: the columns of all clusters kept are then linearly independent.
Matrix rigid_basis(const mesh::Mesh& mesh, const std::vector<Index>& nodes,
                   const std::vector<int>& in_cluster, const std::vector<Index>& dofs) {
    const int dim = mesh.dim();
    Matrix R = rigid_motions(mesh, nodes);
    for (Index r = 0; r < R.rows(); ++r)
        if (dofs[static_cast<size_t>(r)] < 0) R.row(r).setZero();
    const Eigen::JacobiSVD<Matrix> svd(R, Eigen::ComputeThinU);
    const Index columns = rank(svd.singularValues());
    Matrix own = R;
    for (Index a = 0; a < static_cast<Index>(nodes.size()); ++a)
        if (in_cluster[static_cast<size_t>(nodes[static_cast<size_t>(a)])] > 1)
            own.middleRows(dim * a, dim).setZero();
    if (columns == 0 || rank(Eigen::JacobiSVD<Matrix>(own).singularValues()) < columns)
        return Matrix(R.rows(), 0);
    return svd.matrixU().leftCols(columns);
}

/// The free DOF of each DOF of `nodes` (interleaved), -1 for fixed ones.
std::vector<Index> node_free_dofs(const std::vector<Index>& nodes, int dim,
                                  const std::vector<Index>& free_position) {
    std::vector<Index> dofs;
    dofs.reserve(nodes.size() * static_cast<size_t>(dim));
    for (const Index v : nodes)
        for (int d = 0; d < dim; ++d)
            dofs.push_back(free_position[static_cast<size_t>(dim * v + d)]);
    return dofs;
}

/// The columns of one cluster as triplets (free DOF, local column, value): its rigid basis U
/// (rows over `dofs`, as rigid_basis) divided by m at a node of m clusters kept (`kept`), then
/// extended over `rings` rings.
std::vector<Eigen::Triplet<double>> cluster_columns(
    const mesh::Mesh& mesh, const std::vector<Index>& nodes, const std::vector<Index>& dofs,
    Matrix U, const std::vector<int>& in_cluster, const std::vector<int>& kept,
    const detail::NodeGraph& graph, const std::vector<Index>& free_position, const SparseMatrix& A,
    int rings, Index c, Scratch& s) {
    const int dim = mesh.dim();
    const Index columns = U.cols();
    std::vector<Eigen::Triplet<double>> out;
    if (columns == 0) return out;
    // Partition of unity over the nodes shared with other clusters.
    for (Index a = 0; a < static_cast<Index>(nodes.size()); ++a)
        if (const int m = kept[static_cast<size_t>(nodes[static_cast<size_t>(a)])]; m > 1)
            U.middleRows(dim * a, dim) /= m;
    for (Index r = 0; r < U.rows(); ++r)
        if (dofs[static_cast<size_t>(r)] >= 0)
            for (Index j = 0; j < columns; ++j)
                out.emplace_back(dofs[static_cast<size_t>(r)], j, U(r, j));
    if (rings == 0) return out;

    const std::vector<Index> interior =
        ring_dofs(nodes, in_cluster, graph, free_position, dim, rings, c, s.seen);
    if (interior.empty()) return out;
    const Index ni = static_cast<Index>(interior.size());
    for (Index i = 0; i < ni; ++i)
        s.interior[static_cast<size_t>(interior[static_cast<size_t>(i)])] = i;
    for (Index r = 0; r < U.rows(); ++r)
        if (dofs[static_cast<size_t>(r)] >= 0)
            s.boundary[static_cast<size_t>(dofs[static_cast<size_t>(r)])] = r;

    // A_II X = -A_IB U_B (A symmetric: column i of A is row i).
    std::vector<Eigen::Triplet<double>> entries;
    Matrix rhs = Matrix::Zero(ni, columns);
    for (Index i = 0; i < ni; ++i)
        for (SparseMatrix::InnerIterator it(A, interior[static_cast<size_t>(i)]); it; ++it) {
            const Index row = it.row();
            if (const Index j = s.interior[static_cast<size_t>(row)]; j >= 0)
                entries.emplace_back(j, i, it.value());
            else if (const Index b = s.boundary[static_cast<size_t>(row)]; b >= 0)
                rhs.row(i) -= it.value() * U.row(b);
        }
    for (const Index p : interior) s.interior[static_cast<size_t>(p)] = -1;
    for (Index r = 0; r < U.rows(); ++r)
        if (dofs[static_cast<size_t>(r)] >= 0)
            s.boundary[static_cast<size_t>(dofs[static_cast<size_t>(r)])] = -1;
    SparseMatrix A_II(ni, ni);
    A_II.setFromTriplets(entries.begin(), entries.end());
    solve::SolverOptions o;
    o.node_dofs = 1;
    solve::SpdSolver solver(o);
    solver.compute(A_II);
    const Matrix X = solver.solve(rhs);
    for (Index i = 0; i < ni; ++i)
        for (Index j = 0; j < columns; ++j)
            out.emplace_back(interior[static_cast<size_t>(i)], j, X(i, j));
    return out;
}

/// The largest eigenvalue of m's elasticity tensor in dimension dim.
double stiffness_scale(const material::Material& m, int dim) {
    const Matrix C = material::tensor(m, dim);
    return Eigen::SelfAdjointEigenSolver<Matrix>(C, Eigen::EigenvaluesOnly)
        .eigenvalues()
        .maxCoeff();
}

}  // namespace

StiffClusters stiff_clusters(const mesh::Mesh& mesh, const material::ElementMaterials& materials,
                             double contrast) {
    CG_VERIFY(std::isfinite(contrast) && contrast > 1,
              "stiff_clusters: contrast = {}: expected a finite value > 1", contrast);
    detail::verify_materials(mesh, materials, "stiff_clusters");
    const Index ne = mesh.num_elements();
    std::vector<char> used(materials.table.size(), 0);
    for (Index e = 0; e < ne; ++e) used[static_cast<size_t>(materials.index[e])] = 1;
    std::vector<double> scale(materials.table.size(), 0);
    double softest = std::numeric_limits<double>::infinity();
    for (size_t t = 0; t < scale.size(); ++t) {
        scale[t] = stiffness_scale(materials.table[t], mesh.dim());
        if (used[t]) softest = std::min(softest, scale[t]);
    }
    IndexVector labels = IndexVector::Constant(ne, -1);
    bool any = false;
    for (Index e = 0; e < ne; ++e) {
        const Index t = materials.index[e];
        if (scale[static_cast<size_t>(t)] < contrast * softest) continue;
        labels[e] = t;
        any = true;
    }
    StiffClusters result;
    // A homogeneous model, or contrasts below `contrast`: no facet matching needed.
    result.cluster = any ? mesh::element_components(mesh, labels, result.count) : labels;
    return result;
}

SparseMatrix cluster_rigid_modes(const mesh::Mesh& mesh, const StiffClusters& clusters,
                                 const SparseMatrix& A_free, const std::vector<Index>& fixed_dofs,
                                 int rings) {
    const Index nd = mesh.num_dofs(), nv = mesh.num_nodes();
    CG_VERIFY(clusters.cluster.size() == mesh.num_elements(),
              "cluster_rigid_modes: clusters of {} elements for a mesh of {}",
              clusters.cluster.size(), mesh.num_elements());
    CG_VERIFY(rings >= 0, "cluster_rigid_modes: rings = {}: expected >= 0", rings);
    const IndexVector free = free_dofs(nd, fixed_dofs);
    const Index nf = free.size();
    CG_VERIFY(A_free.rows() == nf && A_free.cols() == nf,
              "cluster_rigid_modes: the operator is {}x{}, the free DOFs {}", A_free.rows(),
              A_free.cols(), nf);
    std::vector<Index> free_position(static_cast<size_t>(nd), -1);
    for (Index i = 0; i < nf; ++i) free_position[static_cast<size_t>(free[i])] = i;

    // Nodes of each cluster, sorted; in_cluster counts the clusters of each node (a node shared
    // by clusters whose elements meet along an edge or at a corner is listed by each).
    std::vector<std::vector<Index>> nodes(static_cast<size_t>(clusters.count));
    for (Index e = 0; e < mesh.num_elements(); ++e)
        if (const Index c = clusters.cluster[e]; c >= 0)
            for (Index a = 0; a < mesh.elements.cols(); ++a)
                nodes[static_cast<size_t>(c)].push_back(mesh.elements(e, a));
    std::vector<int> in_cluster(static_cast<size_t>(nv), 0);
    for (auto& list : nodes) {
        std::sort(list.begin(), list.end());
        list.erase(std::unique(list.begin(), list.end()), list.end());
        for (const Index v : list) ++in_cluster[static_cast<size_t>(v)];
    }
    const detail::NodeGraph graph =
        rings > 0 ? detail::node_graph(mesh, detail::node_elements(mesh)) : detail::NodeGraph{};

    std::vector<std::vector<Index>> dofs(static_cast<size_t>(clusters.count));
    std::vector<Matrix> bases(static_cast<size_t>(clusters.count));
    detail::parallel_for(clusters.count, [&](Index c) {
        const auto i = static_cast<size_t>(c);
        dofs[i] = node_free_dofs(nodes[i], mesh.dim(), free_position);
        bases[i] = rigid_basis(mesh, nodes[i], in_cluster, dofs[i]);
    });
    std::vector<int> kept(static_cast<size_t>(nv), 0);  // clusters with columns at each node
    std::vector<Index> columns(static_cast<size_t>(clusters.count));
    for (Index c = 0; c < clusters.count; ++c) {
        columns[static_cast<size_t>(c)] = bases[static_cast<size_t>(c)].cols();
        if (columns[static_cast<size_t>(c)] > 0)
            for (const Index v : nodes[static_cast<size_t>(c)]) ++kept[static_cast<size_t>(v)];
    }

    std::vector<std::vector<Eigen::Triplet<double>>> parts(static_cast<size_t>(clusters.count));
    std::exception_ptr error;
    std::mutex mutex;
#pragma omp parallel if (clusters.count > 1)
    {
        Scratch s{std::vector<Index>(static_cast<size_t>(nf), -1),
                  std::vector<Index>(static_cast<size_t>(nf), -1),
                  std::vector<Index>(static_cast<size_t>(nv), -1)};
#pragma omp for schedule(dynamic, 1)
        for (Index c = 0; c < clusters.count; ++c) {
            try {
                parts[static_cast<size_t>(c)] = cluster_columns(
                    mesh, nodes[static_cast<size_t>(c)], dofs[static_cast<size_t>(c)],
                    std::move(bases[static_cast<size_t>(c)]), in_cluster, kept, graph,
                    free_position, A_free, rings, c, s);
            } catch (...) {
                const std::lock_guard<std::mutex> lock(mutex);
                if (!error) error = std::current_exception();
            }
        }
    }
    if (error) std::rethrow_exception(error);

    std::vector<Eigen::Triplet<double>> entries;
    Index m = 0;
    for (Index c = 0; c < clusters.count; ++c) {
        for (const auto& t : parts[static_cast<size_t>(c)])
            entries.emplace_back(t.row(), m + t.col(), t.value());
        m += columns[static_cast<size_t>(c)];
    }
    SparseMatrix Z(nf, m);
    Z.setFromTriplets(entries.begin(), entries.end());
    return Z;
}

}  // namespace coarsegrain::fem
