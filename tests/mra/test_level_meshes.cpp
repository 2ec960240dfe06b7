// The hierarchy on simplicial level meshes, nested or not (Chen et al. 2019, Secs. 3.1, 5.1):
// the canonical operators' identities, the nested and grid oracles, and Algorithm 1's exactness.
#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>

#include "../test_util.hpp"
#include "coarsegrain/mra/level_meshes.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

using mesh::ElementType;

/// A simplicial grid mesh over [0, 1]^dim (scaled by `scale` about the centre) with `n` cells per
/// axis and its interior nodes moved by up to `distortion` of a cell.
mesh::Mesh simplex_grid(int dim, const Eigen::Vector3i& n, double distortion, unsigned seed,
                        double scale = 1) {
    const Eigen::VectorXd centre = Eigen::VectorXd::Constant(dim, 0.5);
    const Eigen::VectorXd half = Eigen::VectorXd::Constant(dim, 0.5 * scale);
    mesh::Mesh m = mesh::make_grid(dim == 2 ? ElementType::Tri3 : ElementType::Tet4, centre - half,
                                   centre + half, n.head(dim));
    test::distort_interior(m, distortion, seed);
    for (Index e = 0; e < m.num_elements(); ++e)
        EXPECT_GT(mesh::element_measure(m, e), 0) << "inverted element " << e;
    return m;
}

/// Three non-nested levels: the fine mesh (12^2 or 6^3 cells, distorted), a middle one of
/// other cell counts (distorted) and a coarsest one 4% larger than the object, so that fine
/// nodes coincide with no coarse node and the coarsest boundary nodes lie outside the object.
std::vector<mesh::Mesh> non_nested_levels(int dim) {
    if (dim == 2)
        return {simplex_grid(2, {3, 2, 1}, 0.0, 3, 1.04), simplex_grid(2, {7, 5, 1}, 0.2, 2),
                simplex_grid(2, {12, 12, 1}, 0.2, 1)};
    return {simplex_grid(3, {2, 2, 1}, 0.0, 3, 1.04), simplex_grid(3, {3, 4, 3}, 0.25, 2),
            simplex_grid(3, {6, 6, 6}, 0.3, 1)};
}

/// The coarser two of non_nested_levels.
std::vector<mesh::Mesh> coarser_levels(int dim) {
    std::vector<mesh::Mesh> levels = non_nested_levels(dim);
    levels.pop_back();
    return levels;
}

/// Present fine DOFs: all but those fixed by the problem (the Eliminate treatment).
IndexVector free_dofs(const test::GridProblem& p) {
    std::vector<char> fixed(static_cast<std::size_t>(p.mesh.num_dofs()), 0);
    for (const Index d : p.bc.dofs) fixed[d] = 1;
    std::vector<Index> out;
    for (Index d = 0; d < p.mesh.num_dofs(); ++d)
        if (!fixed[d]) out.push_back(d);
    return Eigen::Map<IndexVector>(out.data(), static_cast<Index>(out.size()));
}

using LevelParam = std::tuple<int, Refinement>;

class LevelMeshes : public ::testing::TestWithParam<LevelParam> {
  protected:
    int dim() const { return std::get<0>(GetParam()); }
    Refinement refinement() const { return std::get<1>(GetParam()); }
    test::GridProblem problem() const {
        return test::hung_problem_on(non_nested_levels(dim()).back(), 1.0, 1e3,
                                     test::checker_pattern);
    }
    /// The canonical operators of the step from `fine` to `coarse` on the present DOFs.
    RefinementOperators operators(const mesh::Mesh& coarse, const mesh::Mesh& fine,
                                  const IndexVector& dofs, bool keep_boundary_rows) const {
        const std::vector<Index> pivots = pivot_nodes(coarse.rest_positions, fine.rest_positions);
        const SparseMatrix C_node = refinement() == Refinement::Linear
                                        ? linear_refinement(coarse, fine.rest_positions)
                                        : selection_refinement(pivots, fine.num_nodes());
        return local_refinement_operators(C_node, pivots, fine.elements, dim(), dofs,
                                          keep_boundary_rows);
    }
};

TEST_P(LevelMeshes, LeftInverseAndKernelHoldToRoundOff) {
    const std::vector<mesh::Mesh> levels = non_nested_levels(dim());
    const test::GridProblem p = problem();
    IndexVector all(p.mesh.num_dofs());
    for (Index d = 0; d < all.size(); ++d) all[d] = d;
    for (const bool keep : {false, true})
        for (const IndexVector& dofs : {free_dofs(p), all}) {
            const RefinementOperators ops = operators(levels[1], levels[2], dofs, keep);
            // C C^{†,T} = I: each row of C^† solves its local system by a dense least-norm solve of
            // O(1) entries (checked to 1e-12 inside); C W^T = C - C C^{†,T} C adds one product:
            // 1e-12.
            const Matrix CCd = Matrix(ops.C * SparseMatrix(ops.C_dagger.transpose()));
            EXPECT_LT(test::max_abs(CCd - Matrix::Identity(CCd.rows(), CCd.cols())), 1e-12);
            EXPECT_LT(test::max_abs(Matrix(ops.C * SparseMatrix(ops.W.transpose()))), 1e-12);
            // The kernel's dimension and full rank (dense rank-revealing QR of W^T).
            EXPECT_EQ(ops.W.rows(), ops.C.cols() - ops.C.rows());
            const Eigen::ColPivHouseholderQR<Matrix> qr{Matrix(ops.W.transpose())};
            EXPECT_EQ(qr.rank(), ops.W.rows());
            // Fine nodes coincide with no middle-level node: the linear C^† is not the injection.
            if (refinement() == Refinement::Linear) {
                EXPECT_GT(ops.C_dagger.nonZeros(), ops.C.rows());
            }
        }
}

// A coarse node whose hat function reaches only absent (fixed) fine nodes measures nothing and
// is dropped, even with its pivot present: a pivot is the nearest free fine node, which can lie
// outside the node's hat function (automatic levels with a clamped slab of the object). Here
// the pivot of one coarse node is moved to a fine neighbour of its hat function's support and
// that support is fixed; the other coarse DOFs are kept and C^† and W stay exact.
TEST(LevelMeshOperators, ANodeMeasuringOnlyFixedNodesIsDropped) {
    for (const int dim : {2, 3}) {
        const std::vector<mesh::Mesh> levels = non_nested_levels(dim);
        const mesh::Mesh &coarse = levels[1], &fine = levels[2];
        std::vector<Index> pivots = pivot_nodes(coarse.rest_positions, fine.rest_positions);
        const SparseMatrix C_node = linear_refinement(coarse, fine.rest_positions);
        using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor, Index>;
        const RowMajor rows = C_node;
        // The interior coarse node with the smallest support, and a fine node beside it that
        // is no pivot.
        Index node = -1;
        for (Index i = 0; i < coarse.num_nodes(); ++i)
            if (rows.row(i).nonZeros() > 1 &&
                (node < 0 || rows.row(i).nonZeros() < rows.row(node).nonZeros()))
                node = i;
        std::vector<char> support(static_cast<std::size_t>(fine.num_nodes()), 0),
            is_pivot(support.size(), 0);
        for (RowMajor::InnerIterator it(rows, node); it; ++it) support[it.col()] = 1;
        for (const Index q : pivots) is_pivot[q] = 1;
        Index beside = -1;
        for (Index e = 0; e < fine.num_elements() && beside < 0; ++e) {
            bool touches = false;
            for (Index a = 0; a < fine.elements.cols(); ++a)
                touches |= support[fine.elements(e, a)];
            for (Index a = 0; a < fine.elements.cols() && touches && beside < 0; ++a) {
                const Index v = fine.elements(e, a);
                if (!support[v] && !is_pivot[v]) beside = v;
            }
        }
        ASSERT_GE(beside, 0);
        pivots[node] = beside;
        std::vector<Index> present;
        for (Index d = 0; d < fine.num_dofs(); ++d)
            if (!support[d / dim]) present.push_back(d);
        const IndexVector dofs =
            Eigen::Map<IndexVector>(present.data(), static_cast<Index>(present.size()));
        for (const bool keep : {false, true}) {
            const RefinementOperators ops =
                local_refinement_operators(C_node, pivots, fine.elements, dim, dofs, keep);
            // Dropped: the node's DOFs, and those of nodes whose pivot was fixed with it (all of
            // them without boundary rows).
            std::vector<Index> expected;
            for (Index i = 0; i < coarse.num_nodes(); ++i)
                if (i == node || (!keep && support[pivots[i]]))
                    for (int d = 0; d < dim; ++d) expected.push_back(dim * i + d);
            const std::vector<Index> dropped(ops.dropped_dofs.begin(), ops.dropped_dofs.end());
            if (keep) {
                for (const Index d : expected)
                    EXPECT_TRUE(std::binary_search(dropped.begin(), dropped.end(), d)) << d;
            } else {
                EXPECT_EQ(dropped, expected);
            }
            // As LeftInverseAndKernelHoldToRoundOff.
            const Matrix CCd = Matrix(ops.C * SparseMatrix(ops.C_dagger.transpose()));
            EXPECT_LT(test::max_abs(CCd - Matrix::Identity(CCd.rows(), CCd.cols())), 1e-12);
            EXPECT_LT(test::max_abs(Matrix(ops.C * SparseMatrix(ops.W.transpose()))), 1e-12);
        }
    }
}

TEST_P(LevelMeshes, AdaptedRefinementSatisfiesEq9AndEq12) {
    const test::GridProblem p = problem();
    for (const Options& o : test::exact_level_options(refinement())) {
        const Hierarchy h = build_hierarchy(coarser_levels(dim()), p.mesh, p.K, p.bc.dofs, o);
        const SparseMatrix* A = &h.A_fine;
        SparseMatrix A_level;
        for (int k = h.num_levels() - 1; k >= 1; --k) {
            const Level& L = h.level(k);
            const SparseMatrix Ct = L.C_adapted.sparse();
            // Eq. 9: C̃ C^T = I, as on grids: the round-off of Z W C^T: 1e-12.
            const Matrix CtCt = Matrix(Ct * SparseMatrix(L.C.transpose()));
            EXPECT_LT(test::max_abs(CtCt - Matrix::Identity(CtCt.rows(), CtCt.cols())), 1e-12) << k;
            // Eq. 12: C̃ A W^T = 0 relative to |C̃| |A| |W|: a CHOLMOD solve's round-off: 1e-10.
            const Matrix CAWt = Matrix(Ct * (*A) * SparseMatrix(L.W.transpose()));
            EXPECT_LT(CAWt.norm(), 1e-10 * Ct.norm() * A->norm() * L.W.norm()) << k;
            A_level = symmetric_from_lower(L.A);
            A = &A_level;
        }
    }
}

TEST_P(LevelMeshes, MultilevelSolveReproducesFineSolve) {
    const test::GridProblem p = problem();
    for (const Options& o : test::exact_level_options(refinement())) {
        const Hierarchy h = build_hierarchy(coarser_levels(dim()), p.mesh, p.K, p.bc.dofs, o);
        MultilevelSolver solver(h);
        // Exact block-diagonalization (Eq. 4): q + 1 sparse Cholesky solves' round-off: 1e-9.
        EXPECT_LT((solver.solve(p.f) - p.u).norm(), 1e-9 * p.u.norm())
            << dirichlet_name(o.dirichlet);
    }
}

TEST_P(LevelMeshes, InvarianceCorrectionReproducesRigidMotions) {
    // C̃^{k,T} Rig^k = Rig^{k+1} on every corrected column, the rigid motions of the fine nodes
    // carried by the measurements Rig^k = C^k Rig^{k+1}. Each column's correction is a
    // least-squares solve of at most 6 unknowns: 1e-10 relative. With the conditions ignored by
    // the construction (the blind treatment) every column is corrected; constrained, those
    // away from the Dirichlet nodes (Sec. 3.5), for global and localized solves. At one fine
    // ring some columns have too few entries to meet the conditions: they are not flagged.
    const test::GridProblem p = problem();
    const double inf = std::numeric_limits<double>::infinity();
    for (const DirichletTreatment t : {DirichletTreatment::Ignore, DirichletTreatment::Constrain})
        for (const double radius : {inf, 2.0, 1.0}) {
            Options o;
            o.levels = 3;
            o.refinement = refinement();
            o.dirichlet = t;
            o.radius = {radius};
            const Hierarchy h = build_hierarchy(coarser_levels(dim()), p.mesh, p.K, p.bc.dofs, o);
            const int m = dim() == 3 ? 6 : 3;
            Matrix rig = Matrix::Zero(h.fine_dofs.size(), m);
            for (Index a = 0; a < h.fine_dofs.size(); ++a) {
                const int c = h.fine_dofs[a] % dim();
                const Eigen::VectorXd x =
                    p.mesh.rest_positions.row(h.fine_dofs[a] / dim()).transpose();
                rig(a, c) = 1;
                if (dim() == 2) {
                    rig(a, 2) = c == 0 ? -x[1] : x[0];
                } else {  // u = e_r x x for r = 0, 1, 2
                    for (int r = 0; r < 3; ++r) {
                        Eigen::Vector3d e = Eigen::Vector3d::Zero();
                        e[r] = 1;
                        rig(a, 3 + r) = e.cross(Eigen::Vector3d(x[0], x[1], x[2]))[c];
                    }
                }
            }
            const double scale = test::max_abs(rig);
            for (int k = h.num_levels() - 1; k >= 1; --k) {
                const Level& L = h.level(k);
                const IndexVector& finer_dofs =
                    k + 1 == h.num_levels() ? h.fine_dofs : h.level(k + 1).dofs;
                const Matrix coarse = L.C * rig;
                const Matrix error = L.C_adapted.sparse().transpose() * coarse - rig;
                Index corrected = 0;
                for (Index a = 0; a < error.rows(); ++a)
                    if (L.invariance_applied[finer_dofs[a] / dim()]) {
                        ++corrected;
                        EXPECT_LT(test::max_abs(error.row(a)), 1e-10 * scale)
                            << dirichlet_name(t) << " radius " << radius << " level " << k;
                    }
                // (The coarsest step's supports all reach a Dirichlet node.)
                if (radius == 1.0) {
                    EXPECT_GT(corrected, 0) << dirichlet_name(t) << " level " << k;
                } else if (t == DirichletTreatment::Ignore) {
                    EXPECT_EQ(corrected, error.rows()) << "radius " << radius << " level " << k;
                } else if (radius < inf && k + 1 == h.num_levels()) {
                    EXPECT_GT(corrected, 0);
                }
                rig = coarse;
            }
        }
}

/// Finer-level nodes within `rings` rings of `centre` in the graph of `elements` (nodes sharing
/// an element), by breadth-first search.
std::vector<Index> ring_nodes(const IndexMatrix& elements, Index nodes, Index centre, int rings) {
    std::vector<std::vector<Index>> adjacent(static_cast<std::size_t>(nodes));
    for (Index e = 0; e < elements.rows(); ++e)
        for (Index a = 0; a < elements.cols(); ++a)
            for (Index b = 0; b < elements.cols(); ++b)
                adjacent[elements(e, a)].push_back(elements(e, b));
    std::vector<int> distance(static_cast<std::size_t>(nodes), -1);
    std::vector<Index> out{centre};
    distance[static_cast<std::size_t>(centre)] = 0;
    for (std::size_t a = 0; a < out.size(); ++a)
        for (const Index n : adjacent[static_cast<std::size_t>(out[a])])
            if (distance[static_cast<std::size_t>(n)] < 0 &&
                distance[static_cast<std::size_t>(out[a])] < rings) {
                distance[static_cast<std::size_t>(n)] =
                    distance[static_cast<std::size_t>(out[a])] + 1;
                out.push_back(n);
            }
    return out;
}

TEST_P(LevelMeshes, LocalizedSolvesOverTheWholeLevelAreTheGlobalSolves) {
    // Regions of more rings than the finer levels' graph diameters hold every wavelet: each
    // region's solve is the global solve restricted to its rows' columns, so C̃ is the global
    // one up to the round-off of two sparse Cholesky solves (1e-10 relative).
    const test::GridProblem p = problem();
    for (Options o : test::exact_level_options(refinement())) {
        const Hierarchy global = build_hierarchy(coarser_levels(dim()), p.mesh, p.K, p.bc.dofs, o);
        o.radius = {40};
        const Hierarchy local = build_hierarchy(coarser_levels(dim()), p.mesh, p.K, p.bc.dofs, o);
        for (int k = 1; k < global.num_levels(); ++k) {
            const SparseMatrix G = global.level(k).C_adapted.sparse();
            const SparseMatrix L = local.level(k).C_adapted.sparse();
            EXPECT_LT(Matrix(G - L).cwiseAbs().maxCoeff(), 1e-10 * Matrix(G).cwiseAbs().maxCoeff())
                << "level " << k;
            EXPECT_EQ(local.level(k).region_rings.size(), local.level(k).dirichlet_nodes.size());
        }
    }
}

TEST_P(LevelMeshes, LocalizedRowsAreAOrthogonalToTheWaveletsOfTheirRegion) {
    // Node localization (Sec. 3.5) on level meshes: the rows of C̃ of coarse node i solve
    // B z = -R on the wavelets S_i with a nonzero within rho rings (the finer mesh's graph) of
    // i's pivot, so Eq. 12 holds on S_i, (C̃ A W^T)[r, S_i] = 0, to a dense or sparse
    // Cholesky solve's round-off (1e-10 relative to |C̃_r| |A| |W|), and not beyond.
    const test::GridProblem p = problem();
    const std::vector<mesh::Mesh> levels = non_nested_levels(dim());
    for (Options o : test::exact_level_options(refinement())) {
        o.radius = {1};
        const Hierarchy h = build_hierarchy(coarser_levels(dim()), p.mesh, p.K, p.bc.dofs, o);
        const int k = h.num_levels() - 1;  // the fine step
        const Level& L = h.level(k);
        const SparseMatrix Ct = L.C_adapted.sparse();
        const Matrix CAWt = Matrix(Ct * h.A_fine * SparseMatrix(L.W.transpose()));
        const std::vector<Index> pivots =
            pivot_nodes(levels[1].rest_positions, levels[2].rest_positions);
        std::vector<Index> local(static_cast<std::size_t>(p.mesh.num_dofs()), -1);
        for (Index l = 0; l < h.fine_dofs.size(); ++l) local[h.fine_dofs[l]] = l;
        double outside = 0;
        for (Index r = 0; r < L.dofs.size(); ++r) {
            std::vector<char> in_region(static_cast<std::size_t>(L.W.rows()), 0);
            for (const Index v :
                 ring_nodes(p.mesh.elements, p.mesh.num_nodes(), pivots[L.dofs[r] / dim()], 1))
                for (int d = 0; d < dim(); ++d)
                    if (const Index l = local[dim() * v + d]; l >= 0)
                        for (SparseMatrix::InnerIterator it(L.W, l); it; ++it)
                            in_region[it.row()] = 1;
            const double scale = Ct.row(r).norm() * h.A_fine.norm() * L.W.norm();
            for (Index w = 0; w < L.W.rows(); ++w) {
                if (in_region[w])
                    EXPECT_LT(std::abs(CAWt(r, w)), 1e-10 * scale)
                        << "row " << r << " wavelet " << w;
                else
                    outside = std::max(outside, std::abs(CAWt(r, w)) / scale);
            }
        }
        EXPECT_GT(outside, 1e-8) << "the regions should not hold every wavelet at radius 1";
    }
}

INSTANTIATE_TEST_SUITE_P(Mra, LevelMeshes,
                         ::testing::Combine(::testing::Values(2, 3),
                                            ::testing::Values(Refinement::Dirac,
                                                              Refinement::Linear)),
                         [](const auto& p) { return test::dim_refinement_label(p.param); });

// On nested meshes the pivots coincide with the coarse nodes and the construction is the grid's:
// the injection C^† and W = [-P I]. The operator builder on the grids' trilinear refinement with
// the coincident nodes gives exactly refinement_operators' matrices (elimination, no boundary
// rows): every entry is a product of powers of two.
TEST(LevelMeshOperators, EqualTheGridOperatorsOnNestedGrids) {
    for (const int dim : {2, 3}) {
        const Eigen::Vector3i coarse_cells =
            dim == 2 ? Eigen::Vector3i(3, 2, 1) : Eigen::Vector3i(2, 1, 2);
        const test::GridProblem p =
            test::hung_problem(dim, 2 * coarse_cells, 1.0, 10.0, test::checker_pattern);
        const IndexVector dofs = free_dofs(p);
        for (const Refinement r : {Refinement::Dirac, Refinement::Linear}) {
            const SparseMatrix C_node = canonical_refinement(coarse_cells, dim, r);
            const std::vector<Index> coincident = coincident_nodes(coarse_cells, dim);
            const RefinementOperators grid =
                refinement_operators(C_node, coincident, dim, dofs, false);
            const RefinementOperators local =
                local_refinement_operators(C_node, coincident, p.mesh.elements, dim, dofs, false);
            EXPECT_EQ(local.coarse_dofs, grid.coarse_dofs);
            EXPECT_EQ(local.dropped_dofs, grid.dropped_dofs);
            EXPECT_EQ(test::max_abs(Matrix(local.C - grid.C)), 0.0);
            EXPECT_EQ(test::max_abs(Matrix(local.C_dagger - grid.C_dagger)), 0.0);
            EXPECT_EQ(test::max_abs(Matrix(local.W - grid.W)), 0.0);
        }
    }
}

// Regular subdivision: nested levels where the P1 refinement is 1 at the coincident node and 1/2
// at the midpoints of the node's edges, C^† the injection.
TEST(LevelMeshOperators, SubdivisionIsNestedAndConservesMeasure) {
    for (const int dim : {2, 3}) {
        const mesh::Mesh coarse = simplex_grid(dim, {2, 3, 2}, 0.3, 4);
        const mesh::Mesh fine = subdivide(coarse);
        EXPECT_EQ(fine.num_elements(), (dim == 2 ? 4 : 8) * coarse.num_elements());
        double coarse_measure = 0, fine_measure = 0;
        for (Index e = 0; e < coarse.num_elements(); ++e)
            coarse_measure += mesh::element_measure(coarse, e);
        for (Index e = 0; e < fine.num_elements(); ++e) {
            const double v = mesh::element_measure(fine, e);
            EXPECT_GT(v, 0) << "element " << e;
            fine_measure += v;
        }
        EXPECT_NEAR(fine_measure, coarse_measure, 1e-13 * coarse_measure);
        const std::vector<Index> pivots = pivot_nodes(coarse.rest_positions, fine.rest_positions);
        for (Index i = 0; i < coarse.num_nodes(); ++i) EXPECT_EQ(pivots[i], i);
        const SparseMatrix C = linear_refinement(coarse, fine.rest_positions);
        for (Index j = 0; j < C.outerSize(); ++j)
            for (SparseMatrix::InnerIterator it(C, j); it; ++it) {
                const double expected = j < coarse.num_nodes() ? 1.0 : 0.5;
                if (std::abs(it.value()) > 1e-14) {
                    EXPECT_NEAR(it.value(), expected, 1e-14);
                }
            }
        IndexVector all(fine.num_dofs());
        for (Index d = 0; d < all.size(); ++d) all[d] = d;
        SparseMatrix C_clean = C;
        C_clean.prune(1e-14, 1);
        const RefinementOperators ops =
            local_refinement_operators(C_clean, pivots, fine.elements, dim, all, false);
        EXPECT_EQ(ops.C_dagger.nonZeros(), ops.C.rows());
    }
}

// Dirac refinement selects the same nodes on a tetrahedral grid hierarchy and on its level
// meshes: both constructions compute the same C̃ and A^k, up to the order of the Galerkin
// product's sums (1e-12).
TEST(LevelMeshHierarchy, DiracEqualsTheGridHierarchyOnNestedTetGrids) {
    const Eigen::Vector3i cells(4, 4, 4);
    const test::GridProblem p = test::hung_problem_on(
        mesh::make_grid(ElementType::Tet4, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), cells),
        1.0, 1e3, test::checker_pattern);
    for (const DirichletTreatment t : {DirichletTreatment::Eliminate, DirichletTreatment::Ignore}) {
        Options o;
        o.levels = 3;
        o.refinement = Refinement::Dirac;
        o.dirichlet = t;
        const Hierarchy grid = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
        std::vector<mesh::Mesh> levels;
        for (const int n : {1, 2})
            levels.push_back(mesh::make_grid(ElementType::Tet4, Eigen::Vector3d::Zero(),
                                             Eigen::Vector3d::Ones(), Eigen::Vector3i(n, n, n)));
        const Hierarchy meshes = build_hierarchy(levels, p.mesh, p.K, p.bc.dofs, o);
        for (int k = 1; k < 3; ++k) {
            const Level& a = grid.level(k);
            const Level& b = meshes.level(k);
            ASSERT_EQ(a.dofs, b.dofs) << k;
            const SparseMatrix Ca = a.C_adapted.sparse(), Cb = b.C_adapted.sparse();
            EXPECT_LT((Ca - Cb).norm(), 1e-12 * Ca.norm()) << k;
            EXPECT_LT((a.A - b.A).norm(), 1e-12 * a.A.norm()) << k;
        }
    }
}

TEST(LevelMeshHierarchy, BadInputIsAnError) {
    const std::vector<mesh::Mesh> levels = coarser_levels(2);
    const test::GridProblem p =
        test::hung_problem_on(non_nested_levels(2).back(), 1.0, 10.0, test::checker_pattern);
    Options o;
    o.levels = 2;
    test::expect_error([&] { build_hierarchy(levels, p.mesh, p.K, p.bc.dofs, o); },
                       "2 coarser level meshes for levels = 2");
    o.levels = 3;
    o.radius = {2};
    o.patch = 2;
    test::expect_error([&] { build_hierarchy(levels, p.mesh, p.K, p.bc.dofs, o); },
                       "one region per node (patch 1), got patch 2");
    o.patch = 1;
    o.localization = Localization::Cell;
    test::expect_error([&] { build_hierarchy(levels, p.mesh, p.K, p.bc.dofs, o); },
                       "cell-wise and relaxed solves need grids");
    o.localization = Localization::Node;
    o.radius = {std::numeric_limits<double>::infinity()};
    std::vector<mesh::Mesh> quads = levels;
    quads[0] = mesh::make_grid(ElementType::Quad4, Eigen::Vector2d::Zero(), Eigen::Vector2d::Ones(),
                               Eigen::Vector2i(2, 2));
    test::expect_error([&] { build_hierarchy(quads, p.mesh, p.K, p.bc.dofs, o); },
                       "level mesh 1 has quad elements");
    std::vector<mesh::Mesh> swapped = levels;
    std::swap(swapped[0], swapped[1]);
    test::expect_error([&] { build_hierarchy(swapped, p.mesh, p.K, p.bc.dofs, o); },
                       "more than the finer level's");
}

}  // namespace
}  // namespace coarsegrain::mra
