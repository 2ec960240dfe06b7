// Localized coarse spaces beyond the nodal basis against global solves, on a scene's hex grid of
// N^3 (or NX x NY x NZ, all even) cells with coarse cells of 2^3 fine cells (two levels): the
// routes of docs/mra-localization.md, "Beyond the nodal basis: enrichment and super-localization
// (3D)".
//
//   bench_mra_enrichment SCENE N|NXxNYxNZ RINGS|inf [construction=lod|slod] [relaxation=0]
//                        [enrichment=none|rigid-vectors|rigid-measurements|spectral] [tau=0.1]
//                        [global=1]
//
// lod: the textbook Localized Orthogonal Decomposition (Målqvist and Peterseim 2014; Henning and
// Peterseim 2013), written out here independently of the library's hierarchy so that its
// measurements can be extended. With P the trilinear prolongation from the coarse grid (over the
// free DOFs) and the measurements C = M^T, the fine-scale space is W = ker C, and each coarse
// vector p_j becomes p_j - sum_T Q_T p_j: the element corrector Q_T p_j in W(omega_T) = {w in W,
// supp w in omega_T} solves a(Q_T p_j, w) = a_T(p_j, w) for all w in W(omega_T) (one sparse KKT
// system per coarse cell T; omega_T is T grown by RINGS fine rings). With M = P only, the global
// space span(A^{-1} M) is the hierarchy's with linear refinement (bench_mra's global errors).
// relaxation gamma > 0 turns the constraints C w = 0 into a penalty: the KKT system's constraint
// block is -eps I with eps = gamma / d_soft (d_soft: A's diagonal at an interior node of the
// softest material), so that Q_T p_j minimizes a(w, w) / 2 - a_T(p_j, w) + |C w|^2 / (2 eps)
// over the functions supported in omega_T (as the relaxed CEM-GMsFEM of Chung, Efendiev and Leung
// 2018). The global space stays the same for every eps > 0: p - (A + C^T C / eps)^{-1} A p =
// (A + C^T C / eps)^{-1} C^T (C p) / eps, and (A + C^T C / eps)^{-1} C^T = A^{-1} C^T (I + C A^{-1}
// C^T / eps)^{-1} (Woodbury); the local solves see the reaction term C^T C / eps, which makes the
// correctors decay faster.
// Enrichments (lod only):
// - rigid-vectors: the stiff clusters' rigid motions (fem::cluster_rigid_modes, extended over 2
//   rings) appended to the space as coarse vectors;
// - rigid-measurements: the same motions (not extended) as further measurements and coarse
//   vectors, so that W loses them too (constraint energy minimization with CEM-GMsFEM's
//   auxiliary space; Chung, Efendiev and Leung 2018);
// - spectral: per patch of 4^3 coarse cells (stride 2 cells) the eigenvectors v of A on W(patch)
//   with A v = lambda D v, D = diag(A), lambda < tau (the fine-scale space's low-energy modes,
//   GenEO-style), as measurements D v and coarse vectors v.
// A measurement group cut by a region (a cluster's or patch's rows restricted to the region's
// DOFs) is replaced by an orthonormal basis of its restriction.
// slod: super-localized functions, 3 per coarse node (slod_basis).
// Prints the coarse DOFs and the coarse Galerkin energy errors ||u_H - u||_A / ||u||_A against
// the fine solve, global (skipped with global = 0) and localized (skipped with RINGS inf), the
// localized basis's build time (2 threads, wall seconds) and density.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/fem/stiff_clusters.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/solve/lu_solver.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace cg = coarsegrain;
using cg::Index;
using cg::Matrix;
using cg::SparseMatrix;
using cg::Vector;
using Triplet = Eigen::Triplet<double>;

namespace {

double since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The fine problem on the grid, its free-DOF system and the map from grid DOFs to free DOFs.
struct Problem {
    cg::scene::FineModel model;
    cg::fem::ReducedSystem system;
    std::vector<Index> free_position;  ///< grid DOF -> free DOF, -1 if fixed
    std::array<int, 3> n{};            ///< cells per axis
    Index node(int i, int j, int k) const { return i + (n[0] + 1) * (j + (n[1] + 1) * k); }
    /// Grid node index along axis a of a node of a grid with m[0] x m[1] x m[2] nodes.
    static int along(const std::array<int, 3>& m, Index node, int a) {
        return static_cast<int>(a == 0   ? node % m[0]
                                : a == 1 ? node / m[0] % m[1]
                                         : node / (m[0] * m[1]));
    }
    /// Nodes per axis of the coarse grid (cells n / 2).
    std::array<int, 3> coarse_nodes() const { return {n[0] / 2 + 1, n[1] / 2 + 1, n[2] / 2 + 1}; }
    /// Free DOF of component d of grid node (i, j, k), -1 if fixed.
    Index dof(int i, int j, int k, int d) const { return free_position[3 * node(i, j, k) + d]; }
};

Problem make_problem(const std::string& file, const std::array<int, 3>& n) {
    std::ifstream in(file);
    if (!in) throw std::runtime_error("bench_mra_enrichment: cannot read scene file " + file);
    nlohmann::json j = nlohmann::json::parse(in);
    j["mesh"]["grid"]["cells"] = {n[0], n[1], n[2]};
    Problem p;
    p.n = n;
    p.model = cg::scene::build_fine_model(cg::scene::parse_scene(j, file, "."));
    const cg::mesh::Mesh& mesh = p.model.mesh;
    if (mesh.type != cg::mesh::ElementType::Hex8 || !mesh.grid)
        throw std::runtime_error("bench_mra_enrichment: the scene must be a hex grid");
    // make_grid numbers nodes and elements x fastest; the corrector loop relies on it.
    for (Index e = 0; e < mesh.num_elements(); e += 7) {
        const Index i = e % n[0], j2 = e / n[0] % n[1], k = e / (n[0] * n[1]);
        if (mesh.elements(e, 0) != p.node(i, j2, k))
            throw std::runtime_error("bench_mra_enrichment: unexpected grid numbering");
    }
    p.system = cg::fem::reduce(p.model.K, p.model.f, p.model.bc);
    p.free_position.assign(static_cast<std::size_t>(mesh.num_dofs()), -1);
    for (Index i = 0; i < p.system.free_dofs.size(); ++i)
        p.free_position[p.system.free_dofs[i]] = i;
    return p;
}

/// The trilinear prolongation from the coarse grid of n / 2 cells per axis: P, #free DOFs by the
/// coarse DOFs whose functions do not vanish on the free DOFs, and the column of each coarse grid
/// DOF (3 x coarse nodes entries, -1 if dropped).
struct Prolongation {
    SparseMatrix P;
    std::vector<Index> column;
};

Prolongation trilinear_prolongation(const Problem& p) {
    const std::array<int, 3> m = p.coarse_nodes();
    std::vector<Triplet> t;
    for (int k = 0; k <= p.n[2]; ++k)
        for (int j = 0; j <= p.n[1]; ++j)
            for (int i = 0; i <= p.n[0]; ++i) {
                const int f[3] = {i, j, k};
                for (int corner = 0; corner < 8; ++corner) {
                    Index coarse = 0, stride = 1;
                    double w = 1;
                    for (int a = 0; a < 3; ++a) {
                        const int up = corner >> a & 1;
                        if (f[a] % 2 == 0 && up) w = 0;
                        coarse += (f[a] / 2 + up) * stride;
                        stride *= m[a];
                        if (f[a] % 2 == 1) w *= 0.5;
                    }
                    if (w == 0) continue;
                    for (int d = 0; d < 3; ++d)
                        if (const Index q = p.dof(i, j, k, d); q >= 0)
                            t.emplace_back(q, 3 * coarse + d, w);
                }
            }
    SparseMatrix P(p.system.K.rows(), 3 * m[0] * m[1] * m[2]);
    P.setFromTriplets(t.begin(), t.end());
    Prolongation pr;
    pr.column.assign(static_cast<std::size_t>(P.cols()), -1);
    Index kept = 0;
    for (Index c = 0; c < P.cols(); ++c)
        if (P.col(c).nonZeros() > 0) pr.column[c] = kept++;
    SparseMatrix S(P.cols(), kept);
    for (Index c = 0; c < P.cols(); ++c)
        if (pr.column[c] >= 0) S.insert(c, pr.column[c]) = 1;
    pr.P = P * S;
    return pr;
}

/// Free DOFs of the grid nodes inside the box [lo, hi]^3 (fine node indices) that are not on
/// its faces, except faces on the domain's boundary: the DOFs of functions supported in the box.
std::vector<Index> box_dofs(const Problem& p, const int lo_in[3], const int hi_in[3]) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(lo_in[a], 0);
        hi[a] = std::min(hi_in[a], p.n[a]);
    }
    const auto inside = [&](int x, int a) {
        return (x > lo[a] || lo[a] == 0) && (x < hi[a] || hi[a] == p.n[a]);
    };
    std::vector<Index> dofs;
    for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
            for (int i = lo[0]; i <= hi[0]; ++i)
                if (inside(i, 0) && inside(j, 1) && inside(k, 2))
                    for (int d = 0; d < 3; ++d)
                        if (const Index q = p.dof(i, j, k, d); q >= 0) dofs.push_back(q);
    return dofs;
}

/// The dense principal submatrix of A on `dofs`.
Matrix principal_submatrix(const SparseMatrix& A, const std::vector<Index>& dofs) {
    std::map<Index, Index> local;
    for (std::size_t q = 0; q < dofs.size(); ++q) local[dofs[q]] = static_cast<Index>(q);
    Matrix S = Matrix::Zero(static_cast<Index>(dofs.size()), static_cast<Index>(dofs.size()));
    for (std::size_t q = 0; q < dofs.size(); ++q)
        for (SparseMatrix::InnerIterator it(A, dofs[q]); it; ++it)
            if (const auto f = local.find(it.row()); f != local.end())
                S(f->second, static_cast<Index>(q)) = it.value();
    return S;
}

/// Coarse vectors, their measurements (same shape) and the group of each column (-1: a nodal
/// measurement, kept as one row; others: restricted to a region together).
struct CoarseSpace {
    SparseMatrix vectors, measurements;
    std::vector<Index> group;
};

/// Appends columns to both matrices (measurements = D vectors, D diagonal, or = vectors).
void append(CoarseSpace& s, const SparseMatrix& Z, const Vector* D, std::vector<Index> groups) {
    const auto stack = [](const SparseMatrix& a, const SparseMatrix& b) {
        SparseMatrix c(a.rows(), a.cols() + b.cols());
        c.leftCols(a.cols()) = a;
        c.rightCols(b.cols()) = b;
        return c;
    };
    SparseMatrix DZ = Z;
    if (D)
        for (Index c = 0; c < DZ.outerSize(); ++c)
            for (SparseMatrix::InnerIterator it(DZ, c); it; ++it) it.valueRef() *= (*D)[it.row()];
    s.vectors = stack(s.vectors, Z);
    s.measurements = stack(s.measurements, DZ);
    s.group.insert(s.group.end(), groups.begin(), groups.end());
}

/// Group of each column of fem::cluster_rigid_modes: its cluster, read at a node of that cluster
/// alone (every kept cluster has one).
std::vector<Index> cluster_of_columns(const Problem& p, const cg::fem::StiffClusters& clusters,
                                      const SparseMatrix& Z) {
    const cg::mesh::Mesh& mesh = p.model.mesh;
    std::vector<std::vector<Index>> of_node(static_cast<std::size_t>(mesh.num_nodes()));
    for (Index e = 0; e < mesh.num_elements(); ++e)
        for (Index a = 0; a < 8 && clusters.cluster[e] >= 0; ++a) {
            std::vector<Index>& c = of_node[mesh.elements(e, a)];
            if (std::find(c.begin(), c.end(), clusters.cluster[e]) == c.end())
                c.push_back(clusters.cluster[e]);
        }
    std::vector<Index> group(static_cast<std::size_t>(Z.cols()), -1);
    for (Index c = 0; c < Z.cols(); ++c)
        for (SparseMatrix::InnerIterator it(Z, c); it && group[c] < 0; ++it)
            if (const auto& owners = of_node[p.system.free_dofs[it.row()] / 3]; owners.size() == 1)
                group[c] = owners[0];
    return group;
}

/// Per patch of 4^3 coarse cells (stride 2 coarse cells), the eigenvectors of A on W(patch)
/// with A v = lambda D v, lambda < tau: #free DOFs by #modes, unit columns; `group` gets each
/// column's patch.
SparseMatrix spectral_modes(const Problem& p, const SparseMatrix& P, double tau,
                            std::vector<Index>& group) {
    const SparseMatrix& A = p.system.K;
    const Vector D = A.diagonal();
    const SparseMatrix PT = P.transpose();
    std::vector<Triplet> t;
    Index count = 0, patch = 0;
    for (int k = 0; k <= p.n[2]; k += 4)
        for (int j = 0; j <= p.n[1]; j += 4)
            for (int i = 0; i <= p.n[0]; i += 4, ++patch) {
                const int lo[3] = {i - 4, j - 4, k - 4}, hi[3] = {i + 4, j + 4, k + 4};
                const std::vector<Index> dofs = box_dofs(p, lo, hi);
                const Index nl = static_cast<Index>(dofs.size());
                // W(patch) = ker of the nodal measurements restricted to the patch.
                std::map<Index, Index> rows;
                std::vector<Triplet> ct;
                for (Index q = 0; q < nl; ++q)
                    for (SparseMatrix::InnerIterator it(PT, dofs[q]); it; ++it)
                        ct.emplace_back(rows.emplace(it.row(), rows.size()).first->second, q,
                                        it.value());
                Matrix C = Matrix::Zero(static_cast<Index>(rows.size()), nl);
                for (const Triplet& c : ct) C(c.row(), c.col()) = c.value();
                const Eigen::ColPivHouseholderQR<Matrix> qr(C.transpose());
                const Matrix Q = qr.householderQ();
                const Matrix N = Q.rightCols(nl - qr.rank());
                Vector Dl(nl);
                for (Index q = 0; q < nl; ++q) Dl[q] = D[dofs[q]];
                const Eigen::GeneralizedSelfAdjointEigenSolver<Matrix> eig(
                    N.transpose() * principal_submatrix(A, dofs) * N,
                    N.transpose() * Dl.asDiagonal() * N);
                for (Index a = 0; a < eig.eigenvalues().size() && eig.eigenvalues()[a] < tau;
                     ++a, ++count) {
                    const Vector v = (N * eig.eigenvectors().col(a)).normalized();
                    for (Index q = 0; q < nl; ++q)
                        if (std::abs(v[q]) > 1e-14) t.emplace_back(dofs[q], count, v[q]);
                    group.push_back(patch);
                }
            }
    SparseMatrix Z(A.rows(), count);
    Z.setFromTriplets(t.begin(), t.end());
    return Z;
}

/// The diagonal entry of A at an interior node of the softest material, 8 K_e(0, 0): the scale of
/// the penalty's relaxation (the soft matrix carries the correctors' decay).
double soft_diagonal(const Problem& p) {
    double d = std::numeric_limits<double>::infinity();
    for (const cg::material::Material& m : p.model.materials.table)
        d = std::min(d, 8 * cg::fem::element_stiffness(cg::mesh::ElementType::Hex8,
                                                       p.model.mesh.element_positions(0),
                                                       cg::material::tensor(m, 3))(0, 0));
    return d;
}

/// The localized basis: columns p_j - sum_T Q_T p_j of the coarse vectors (see the file's
/// head), #free DOFs by #coarse vectors.
SparseMatrix element_correctors(const Problem& p, const CoarseSpace& s, int rings,
                                double relaxation) {
    const SparseMatrix& A = p.system.K;
    const Index nf = A.rows(), ncols = s.vectors.cols();
    const std::array<int, 3> nc = {p.n[0] / 2, p.n[1] / 2, p.n[2] / 2};  // coarse cells
    const SparseMatrix MT = s.measurements.transpose();  // column q: the measurements seeing q
    // The constraints enter the KKT system scaled by d_soft, which balances it against A, with
    // the block -eps I: relaxation gamma > 0 makes it the penalty |C w|^2 / (2 gamma / d_soft)
    // (see the file's head), eps = gamma d_soft; without relaxation eps = 1e-12 d_soft keeps the
    // system regular where restricted rows are dependent (1e-12 of the scale of the constraints'
    // Schur complement in the soft material, 1e-9 in a stiff one 1000 times stiffer).
    const double scale = soft_diagonal(p);
    const double eps = (relaxation > 0 ? relaxation : 1e-12) * scale;
    std::vector<Triplet> basis;
    for (Index c = 0; c < s.vectors.outerSize(); ++c)
        for (SparseMatrix::InnerIterator it(s.vectors, c); it; ++it)
            basis.emplace_back(it.row(), c, it.value());
#pragma omp parallel
    {
        std::vector<Triplet> mine;
        std::vector<Index> local(static_cast<std::size_t>(nf), -1);
        std::vector<Index> seen(static_cast<std::size_t>(ncols), -1);
#pragma omp for schedule(dynamic)
        for (Index T = 0; T < nc[0] * nc[1] * nc[2]; ++T) {
            const int ti = Problem::along(nc, T, 0), tj = Problem::along(nc, T, 1),
                      tk = Problem::along(nc, T, 2);
            const int lo[3] = {2 * ti - rings, 2 * tj - rings, 2 * tk - rings};
            const int hi[3] = {2 * ti + 2 + rings, 2 * tj + 2 + rings, 2 * tk + 2 + rings};
            const std::vector<Index> dofs = box_dofs(p, lo, hi);
            const Index nl = static_cast<Index>(dofs.size());
            for (Index q = 0; q < nl; ++q) local[dofs[q]] = q;
            std::vector<Triplet> kkt;
            for (Index q = 0; q < nl; ++q)
                for (SparseMatrix::InnerIterator it(A, dofs[q]); it; ++it)
                    if (local[it.row()] >= 0) kkt.emplace_back(local[it.row()], q, it.value());
            // The measurements restricted to the region: nodal rows as they are, each other
            // group by an orthonormal basis of its restricted rows.
            std::vector<Index> hit;
            std::vector<std::vector<std::pair<Index, double>>> row;
            for (Index q = 0; q < nl; ++q)
                for (SparseMatrix::InnerIterator it(MT, dofs[q]); it; ++it) {
                    if (seen[it.row()] < 0) {
                        seen[it.row()] = static_cast<Index>(hit.size());
                        hit.push_back(it.row());
                        row.emplace_back();
                    }
                    row[seen[it.row()]].emplace_back(q, it.value());
                }
            Index ncon = 0;
            const auto constrain = [&](Index q, double v) {
                kkt.emplace_back(nl + ncon, q, scale * v);
                kkt.emplace_back(q, nl + ncon, scale * v);
            };
            std::map<Index, std::vector<std::size_t>> groups;
            for (std::size_t h = 0; h < hit.size(); ++h) {
                if (s.group[hit[h]] >= 0) {
                    groups[s.group[hit[h]]].push_back(h);
                    continue;
                }
                for (const auto& [q, v] : row[h]) constrain(q, v);
                ++ncon;
            }
            for (const auto& [g, members] : groups) {
                std::vector<Index> qs;
                for (std::size_t h : members)
                    for (const auto& e : row[h]) qs.push_back(e.first);
                std::sort(qs.begin(), qs.end());
                qs.erase(std::unique(qs.begin(), qs.end()), qs.end());
                Matrix R =
                    Matrix::Zero(static_cast<Index>(members.size()), static_cast<Index>(qs.size()));
                for (std::size_t a = 0; a < members.size(); ++a)
                    for (const auto& [q, v] : row[members[a]])
                        R(static_cast<Index>(a),
                          std::lower_bound(qs.begin(), qs.end(), q) - qs.begin()) = v;
                const Eigen::JacobiSVD<Matrix> svd(R, Eigen::ComputeThinV);
                for (Index a = 0; a < svd.singularValues().size(); ++a) {
                    if (svd.singularValues()[a] <= 1e-8 * svd.singularValues()[0]) break;
                    for (std::size_t b = 0; b < qs.size(); ++b)
                        constrain(qs[b], svd.matrixV()(static_cast<Index>(b), a));
                    ++ncon;
                }
            }
            for (Index c = 0; c < ncon; ++c) kkt.emplace_back(nl + c, nl + c, -eps);
            SparseMatrix K(nl + ncon, nl + ncon);
            K.setFromTriplets(kkt.begin(), kkt.end());
            cg::solve::SparseLu lu;
            lu.factorize(K);
            // a_T(p_j, .) for the coarse vectors that do not vanish on T's 8 fine cells.
            std::vector<Index> cols;
            for (int c = 0; c <= 2; ++c)
                for (int b = 0; b <= 2; ++b)
                    for (int a = 0; a <= 2; ++a)
                        for (int d = 0; d < 3; ++d)
                            if (const Index q = p.dof(2 * ti + a, 2 * tj + b, 2 * tk + c, d);
                                q >= 0)
                                for (SparseMatrix::InnerIterator it(MT, q); it; ++it)
                                    cols.push_back(it.row());
            std::sort(cols.begin(), cols.end());
            cols.erase(std::unique(cols.begin(), cols.end()), cols.end());
            Matrix rhs = Matrix::Zero(nl + ncon, static_cast<Index>(cols.size()));
            for (int e = 0; e < 8; ++e) {
                const Index elem = (2 * ti + (e & 1)) + p.n[0] * ((2 * tj + (e >> 1 & 1)) +
                                                                  p.n[1] * (2 * tk + (e >> 2)));
                const Matrix Ke = cg::fem::element_stiffness(
                    cg::mesh::ElementType::Hex8, p.model.mesh.element_positions(elem),
                    cg::material::tensor(p.model.materials.of(elem), 3));
                std::vector<Index> edofs(24);
                for (int a = 0; a < 8; ++a)
                    for (int d = 0; d < 3; ++d)
                        edofs[3 * a + d] = p.free_position[3 * p.model.mesh.elements(elem, a) + d];
                for (std::size_t c = 0; c < cols.size(); ++c) {
                    Vector pe(24);
                    for (int a = 0; a < 24; ++a)
                        pe[a] = edofs[a] >= 0 ? s.vectors.coeff(edofs[a], cols[c]) : 0.0;
                    const Vector ke = Ke * pe;
                    for (int a = 0; a < 24; ++a)
                        if (edofs[a] >= 0) rhs(local[edofs[a]], static_cast<Index>(c)) += ke[a];
                }
            }
            for (std::size_t c = 0; c < cols.size(); ++c) {
                const Vector w = lu.solve(rhs.col(static_cast<Index>(c)));
                for (Index q = 0; q < nl; ++q)
                    if (w[q] != 0) mine.emplace_back(dofs[q], cols[c], -w[q]);
            }
            for (Index q : dofs) local[q] = -1;
            for (Index h : hit) seen[h] = -1;
        }
#pragma omp critical
        basis.insert(basis.end(), mine.begin(), mine.end());
    }
    SparseMatrix Psi(nf, ncols);
    Psi.setFromTriplets(basis.begin(), basis.end());
    Psi.prune(1e-14, 1);
    return Psi;
}

/// A super-localized basis (after SLOD; Hauck and Peterseim 2023) in the measurements' terms: per
/// coarse node, the patch of the fine cells within `rings` of it (functions zero on the patch's
/// inner faces) and the local functions phi = A_patch^{-1} C_patch^T lambda over the nodal
/// measurements supported in the patch. Were the force phi leaves on the patch's faces,
/// R lambda = (A phi)|faces, zero, phi would be the global A^{-1} C^T lambda exactly. For each
/// component d the node's function is the phi of least face residual ||R lambda||^2 (plus 1e-10
/// of its relative energy, which makes the choice unique) whose measurement of the node's d-th
/// DOF is 1. SLOD proper takes per coarse element the right singular vector of least residual;
/// that choice (per unit norm or energy of lambda) spans the coarse space worse here (see the
/// docs). #free DOFs by 3 x coarse nodes; `worst` gets the largest residual per energy kept,
/// ||R lambda||^2 / ||phi||_A^2.
SparseMatrix slod_basis(const Problem& p, const Prolongation& pr, int rings, double& worst) {
    const SparseMatrix& A = p.system.K;
    const std::array<int, 3> m = p.coarse_nodes();
    const Index nodes = m[0] * m[1] * m[2];
    const auto coarse = [&m](Index node, int a) { return Problem::along(m, node, a); };
    std::vector<Triplet> basis;
    worst = 0;
#pragma omp parallel
    {
        std::vector<Triplet> mine;
        std::vector<Index> local(static_cast<std::size_t>(A.rows()), -1);
        double my_worst = 0;
#pragma omp for schedule(dynamic)
        for (Index node = 0; node < nodes; ++node) {
            int lo[3], hi[3];
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::max(2 * coarse(node, a) - rings, 0);
                hi[a] = std::min(2 * coarse(node, a) + rings, p.n[a]);
            }
            const std::vector<Index> dofs = box_dofs(p, lo, hi);
            const Index nl = static_cast<Index>(dofs.size());
            for (Index q = 0; q < nl; ++q) local[dofs[q]] = q;
            std::vector<Triplet> ct;  // C_patch^T
            Index nm = 0, centre[3] = {-1, -1, -1};
            for (Index j = 0; j < nodes; ++j) {
                bool inside = true;
                for (int a = 0; a < 3; ++a)
                    inside = inside && std::max(2 * coarse(j, a) - 2, 0) >= lo[a] &&
                             std::min(2 * coarse(j, a) + 2, p.n[a]) <= hi[a];
                for (int d = 0; d < 3 && inside; ++d) {
                    const Index col = pr.column[3 * j + d];
                    if (col < 0) continue;
                    if (j == node) centre[d] = nm;
                    for (SparseMatrix::InnerIterator it(pr.P, col); it; ++it)
                        ct.emplace_back(local[it.row()], nm, it.value());
                    ++nm;
                }
            }
            // The faces: free DOFs outside the patch coupled to it by A.
            std::map<Index, Index> face;
            std::vector<Triplet> at, rt;
            for (Index q = 0; q < nl; ++q)
                for (SparseMatrix::InnerIterator it(A, dofs[q]); it; ++it) {
                    if (local[it.row()] >= 0)
                        at.emplace_back(local[it.row()], q, it.value());
                    else
                        rt.emplace_back(face.emplace(it.row(), face.size()).first->second, q,
                                        it.value());
                }
            SparseMatrix Al(nl, nl), Ctl(nl, nm), Rl(static_cast<Index>(face.size()), nl);
            Al.setFromTriplets(at.begin(), at.end());
            Ctl.setFromTriplets(ct.begin(), ct.end());
            Rl.setFromTriplets(rt.begin(), rt.end());
            cg::solve::SpdSolver solver;
            solver.compute(Al);
            const Matrix Phi = solver.solve(Matrix(Ctl));
            const Matrix R = Rl * Phi;
            const Matrix S = Ctl.transpose() * Phi;  // C_patch phi: the measurements
            const Matrix RtR = R.transpose() * R;
            const Eigen::LDLT<Matrix> G(RtR + 1e-10 * RtR.trace() / S.trace() * S);
            for (int k = 0; k < 3; ++k) {
                if (centre[k] < 0) continue;
                const Vector c = S.row(centre[k]).transpose();
                const Vector lambda = G.solve(c) / c.dot(G.solve(c));
                my_worst = std::max(my_worst, lambda.dot(RtR * lambda) / lambda.dot(S * lambda));
                const Vector phi = Phi * lambda;
                for (Index q = 0; q < nl; ++q)
                    if (std::abs(phi[q]) > 1e-14) mine.emplace_back(dofs[q], 3 * node + k, phi[q]);
            }
            for (Index q : dofs) local[q] = -1;
        }
#pragma omp critical
        {
            basis.insert(basis.end(), mine.begin(), mine.end());
            worst = std::max(worst, my_worst);
        }
    }
    SparseMatrix V(A.rows(), 3 * nodes);
    V.setFromTriplets(basis.begin(), basis.end());
    return V;
}

/// ||u_H - u||_A / ||u||_A for the Galerkin solution u_H in the span of V's columns.
double galerkin_error(const SparseMatrix& A, const SparseMatrix& V, const Vector& b,
                      const Vector& u) {
    const Matrix gram = Matrix(V.transpose() * (A * V));
    const Vector uH = V * gram.ldlt().solve(V.transpose() * b);
    const Vector e = uH - u;
    return std::sqrt(e.dot(A * e) / u.dot(A * u));
}

/// The Galerkin error in span{A^{-1} M, Z}, the global construction (the A-orthogonal complement
/// of ker M^T) with Z appended, without storing A^{-1} M: with X = A^{-1} M, the Gram matrix is
/// [M^T X, M^T Z; Z^T M, Z^T A Z] and the right-hand side [M^T u; Z^T A u], so that
/// ||u_H - u||_A^2 = ||u||_A^2 - y^T G^{-1} y. X is formed 256 columns at a time.
double global_error(const SparseMatrix& A, const cg::solve::SpdSolver& fine, const SparseMatrix& M,
                    const SparseMatrix& Z, const Vector& u) {
    const Index m = M.cols(), z = Z.cols();
    Matrix G(m + z, m + z);
    for (Index c = 0; c < m; c += 256) {
        const Index w = std::min<Index>(256, m - c);
        G.block(0, c, m, w) = M.transpose() * fine.solve(Matrix(M.middleCols(c, w)));
    }
    G.block(0, m, m, z) = Matrix(M.transpose() * Z);
    G.block(m, 0, z, m) = G.block(0, m, m, z).transpose();
    G.block(m, m, z, z) = Matrix(Z.transpose() * (A * Z));
    Vector y(m + z);
    y << M.transpose() * u, Z.transpose() * (A * u);
    const double uu = u.dot(A * u);
    return std::sqrt(std::max(0.0, uu - y.dot(G.ldlt().solve(y))) / uu);
}

int run(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr,
                     "usage: bench_mra_enrichment SCENE N|NXxNYxNZ RINGS|inf "
                     "[construction=lod|slod] [relaxation=0] "
                     "[enrichment=none|rigid-vectors|rigid-measurements|spectral] [tau=0.1] "
                     "[global=1]\n");
        return 2;
    }
    const std::string file = argv[1];
    // N: cells per axis, "N" (a cube) or "NXxNYxNZ".
    std::array<int, 3> n{};
    if (std::sscanf(argv[2], "%dx%dx%d", &n[0], &n[1], &n[2]) != 3) n[1] = n[2] = n[0];
    const int rings = std::string(argv[3]) == "inf" ? -1 : std::atoi(argv[3]);  // inf: global only
    const std::string construction = argc > 4 ? argv[4] : "lod";
    const double relaxation = argc > 5 ? std::atof(argv[5]) : 0.0;
    const std::string enrichment = argc > 6 ? argv[6] : "none";
    const double tau = argc > 7 ? std::atof(argv[7]) : 0.1;
    const bool global = argc > 8 ? std::atoi(argv[8]) != 0 : true;
    for (int a = 0; a < 3; ++a)
        if (n[a] < 2 || n[a] % 2 != 0)
            throw std::runtime_error("bench_mra_enrichment: the cells per axis must be even");
    if (rings < 0 && std::string(argv[3]) != "inf")
        throw std::runtime_error("bench_mra_enrichment: RINGS must be >= 0 or inf");
    if (construction != "lod" && construction != "slod")
        throw std::runtime_error("bench_mra_enrichment: unknown construction " + construction);
    if (enrichment != "none" && enrichment != "rigid-vectors" &&
        enrichment != "rigid-measurements" && enrichment != "spectral")
        throw std::runtime_error("bench_mra_enrichment: unknown enrichment " + enrichment);
    if (construction == "slod" && enrichment != "none")
        throw std::runtime_error("bench_mra_enrichment: slod takes no enrichment");
    const Problem p = make_problem(file, n);
    const SparseMatrix& A = p.system.K;
    cg::solve::SpdSolver fine;
    fine.compute(A);
    const Vector u = fine.solve(p.system.rhs);

    const Prolongation pr = trilinear_prolongation(p);
    CoarseSpace s;
    s.vectors = s.measurements = pr.P;
    s.group.assign(static_cast<std::size_t>(s.vectors.cols()), -1);
    const Index nodal = s.vectors.cols();
    SparseMatrix appended(A.rows(), 0);  // rigid-vectors: added after the correctors
    const auto t0 = std::chrono::steady_clock::now();
    if (enrichment == "rigid-vectors" || enrichment == "rigid-measurements") {
        const cg::fem::StiffClusters clusters =
            cg::fem::stiff_clusters(p.model.mesh, p.model.materials, 10);
        const bool vectors = enrichment == "rigid-vectors";
        const SparseMatrix Z = cg::fem::cluster_rigid_modes(p.model.mesh, clusters, A,
                                                            p.model.bc.dofs, vectors ? 2 : 0);
        if (vectors)
            appended = Z;
        else
            append(s, Z, nullptr, cluster_of_columns(p, clusters, Z));
    } else if (enrichment == "spectral") {
        std::vector<Index> group;
        const Vector D = A.diagonal();
        const SparseMatrix Z = spectral_modes(p, s.vectors, tau, group);
        append(s, Z, &D, group);
    }
    const Index extra = s.vectors.cols() - nodal + appended.cols();
    std::printf(
        "%s, %s cells (%ld free DOFs), %s, %s enrichment: %ld nodal + %ld coarse DOFs "
        "(enrichment %.1f s)\n",
        file.c_str(), argv[2], static_cast<long>(A.rows()), construction.c_str(),
        enrichment.c_str(), static_cast<long>(nodal), static_cast<long>(extra), since(t0));
    std::fflush(stdout);
    const auto with_appended = [&](const SparseMatrix& V) {
        SparseMatrix all(A.rows(), V.cols() + appended.cols());
        all.leftCols(V.cols()) = V;
        all.rightCols(appended.cols()) = appended;
        return all;
    };
    if (global) {
        std::printf("global: energy error %.4f\n",
                    global_error(A, fine, s.measurements, appended, u));
        std::fflush(stdout);
    }
    if (rings < 0) return 0;
    const auto t1 = std::chrono::steady_clock::now();
    double worst = 0;
    const SparseMatrix V = construction == "slod" ? slod_basis(p, pr, rings, worst)
                                                  : element_correctors(p, s, rings, relaxation);
    const double build = since(t1);
    std::printf("%s, %d rings: energy error %.4f; basis %.1f s, density %.3f", construction.c_str(),
                rings, galerkin_error(A, with_appended(V), p.system.rhs, u), build,
                static_cast<double>(V.nonZeros()) / static_cast<double>(V.size()));
    if (construction == "slod") std::printf(", largest face residual per energy %.3g", worst);
    std::printf("\n");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
