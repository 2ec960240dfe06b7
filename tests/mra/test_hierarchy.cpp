// Algorithm 1 with global solves: the identities of Eq. 9 and 12, Eq. 10's closed form and the
// exact multilevel solve of Sec. 3.6.
#include <gtest/gtest.h>

#include <limits>
#include <tuple>

#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

using GlobalParam = std::tuple<int, Refinement, DirichletTreatment>;

class MraGlobal : public ::testing::TestWithParam<GlobalParam> {
  protected:
    int dim() const { return std::get<0>(GetParam()); }
    Refinement refinement() const { return std::get<1>(GetParam()); }
    DirichletTreatment treatment() const { return std::get<2>(GetParam()); }
    // 8x8 (2D) or 4x4x4 (3D) cells, 3 levels, contrast 1000.
    test::GridProblem problem() const {
        const Eigen::Vector3i cells =
            dim() == 2 ? Eigen::Vector3i(8, 8, 1) : Eigen::Vector3i(4, 4, 4);
        return test::hung_problem(dim(), cells, 1.0, 1e3, test::checker_pattern);
    }
    Options options() const {
        Options o = test::exact_options(3, refinement());
        o.dirichlet = treatment();
        return o;
    }
};

TEST_P(MraGlobal, AdaptedRefinementSatisfiesEq9AndEq12) {
    const test::GridProblem p = problem();
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, options());
    const SparseMatrix* A = &h.A_fine;
    SparseMatrix A_level;  // A^{k+1}, both triangles
    for (int k = h.num_levels() - 1; k >= 1; --k) {
        const Level& L = h.level(k);
        // Eq. 9 constraint C̃ C^T = I: C̃ = C† + Z W with C† C^T = I and W C^T = 0 exactly, so
        // only the round-off of Z W C^T remains (|Z| <= ~10, sums of ~100 terms): 1e-12.
        const Matrix CtCt = Matrix(L.C_adapted.sparse() * SparseMatrix(L.C.transpose()));
        EXPECT_LT((CtCt - Matrix::Identity(CtCt.rows(), CtCt.cols())).cwiseAbs().maxCoeff(), 1e-12)
            << "level " << k;
        // Eq. 12: C̃ A W^T = 0, relative to |C̃| |A| |W| (Frobenius). The global solve with
        // B = W A W^T leaves the round-off of a CHOLMOD solve of a matrix with condition
        // number below ~1e6: 1e-10.
        const Matrix CAWt = Matrix(L.C_adapted.sparse() * (*A) * SparseMatrix(L.W.transpose()));
        const double scale = L.C_adapted.sparse().norm() * A->norm() * L.W.norm();
        EXPECT_LT(CAWt.norm(), 1e-10 * scale) << "level " << k;
        // B^k = W A^{k+1} W^T (Alg. 1 line 2), symmetrized: Eigen's product, to round-off.
        const SparseMatrix B = L.W * (*A) * SparseMatrix(L.W.transpose());
        EXPECT_LT((symmetric_from_lower(L.B) - B).norm(), 1e-13 * B.norm()) << "level " << k;
        A_level = symmetric_from_lower(L.A);
        A = &A_level;
    }
}

TEST_P(MraGlobal, MultilevelSolveReproducesFineSolve) {
    const test::GridProblem p = problem();
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, options());
    MultilevelSolver solver(h);
    const Vector u = solver.solve(p.f);
    if (treatment() == DirichletTreatment::Eliminate ||
        treatment() == DirichletTreatment::Constrain) {
        // The hierarchy block-diagonalizes A^q (Eq. 4): the solve is exact up to the round-off
        // of q + 1 sparse Cholesky solves of well-conditioned blocks: 1e-9.
        EXPECT_LT((u - p.u).norm(), 1e-9 * p.u.norm());
        // The single level q is the fine solve itself.
        EXPECT_LT((solver.solve_level(p.f, h.num_levels()) - p.u).norm(), 1e-9 * p.u.norm());
    } else {
        // Penalty: the multilevel solve reproduces the penalized fine solve exactly.
        solve::SpdSolver fine;
        fine.compute(h.A_fine);
        const Vector u_pen = fine.solve(p.f);
        EXPECT_LT((u - u_pen).norm(), 1e-9 * u_pen.norm());
    }
}

TEST_P(MraGlobal, CoarseLevelsAreGalerkinProjections) {
    // With exact orthogonality, the solve on level k equals the multilevel solve with the
    // wavelets of levels < k only (V^k = V^1 + W^1 + ... + W^{k-1}, Eq. 4), and its error is the
    // A-orthogonal projection error: (u - u^k) is A-orthogonal to u^k.
    const test::GridProblem p = problem();
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, options());
    MultilevelSolver solver(h);
    solve::SpdSolver fine;
    fine.compute(h.A_fine);
    Vector g(h.fine_dofs.size());
    for (Index i = 0; i < g.size(); ++i) g[i] = p.f[h.fine_dofs[i]];
    const Vector u_ref = expand_fine(h, fine.solve(g));
    SparseMatrix A_full = SparseMatrix(h.fine_grid_dofs(), h.fine_grid_dofs());
    {
        std::vector<Eigen::Triplet<double, Index>> t;
        for (Index c = 0; c < h.A_fine.outerSize(); ++c)
            for (SparseMatrix::InnerIterator it(h.A_fine, c); it; ++it)
                t.emplace_back(h.fine_dofs[it.row()], h.fine_dofs[c], it.value());
        A_full.setFromTriplets(t.begin(), t.end());
    }
    for (int k = 1; k < h.num_levels(); ++k) {
        const Vector uk = solver.solve_level(p.f, k);
        const Vector um = solver.solve_levels(p.f, k);
        // Two exact routes through different factorizations: 1e-9 relative.
        EXPECT_LT((uk - um).norm(), 1e-9 * uk.norm()) << "level " << k;
        const Vector e = u_ref - uk;
        EXPECT_LT(std::abs(e.dot(A_full * uk)), 1e-9 * u_ref.dot(A_full * u_ref)) << "level " << k;
    }
}

INSTANTIATE_TEST_SUITE_P(Mra, MraGlobal,
                         ::testing::Combine(::testing::Values(2, 3),
                                            ::testing::Values(Refinement::Dirac,
                                                              Refinement::Linear),
                                            ::testing::Values(DirichletTreatment::Constrain,
                                                              DirichletTreatment::Eliminate,
                                                              DirichletTreatment::DiagonalPenalty)),
                         [](const auto& p) {
                             return std::to_string(std::get<0>(p.param)) + "D_" +
                                    refinement_name(std::get<1>(p.param)) + "_" +
                                    dirichlet_name(std::get<2>(p.param));
                         });

// Eq. 10 gives the unique minimizer of Eq. 9, so it must equal the closed form of the
// constrained minimization computed independently with dense matrices,
//   C̃ = (C A^{-1} C^T)^{-1} C A^{-1}   (Lagrange conditions of min Tr M A M^T, M C^T = I),
// whatever left inverse C† the construction used (ours is the injection for the linear
// refinement, not the Moore-Penrose inverse of Eq. 10).
TEST(MraClosedForm, AdaptedRefinementIsTheConstrainedMinimizer) {
    for (const Refinement r : {Refinement::Dirac, Refinement::Linear}) {
        const test::GridProblem p =
            test::hung_problem(2, Eigen::Vector3i(8, 4, 1), 1.0, 50.0, test::checker_pattern);
        Options o = test::exact_options(2, r);
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
        const Level& L = h.level(1);
        const Matrix A = Matrix(h.A_fine);
        const Matrix C = Matrix(L.C);
        const Eigen::LLT<Matrix> llt(A);
        const Matrix AinvCt = llt.solve(C.transpose());
        const Matrix M = (C * AinvCt).llt().solve(AinvCt.transpose());
        // Dense solves with a ~1e4 condition number on 90 unknowns: 1e-10.
        EXPECT_LT((Matrix(L.C_adapted.sparse()) - M).cwiseAbs().maxCoeff(), 1e-10)
            << refinement_name(r);
        // A^1 = C̃ A C̃^T equals (C A^{-1} C^T)^{-1} then.
        const Matrix A1 = (C * AinvCt).inverse();
        EXPECT_LT((Matrix(symmetric_from_lower(L.A)) - A1).norm(), 1e-10 * A1.norm())
            << refinement_name(r);
    }
}

// Without store_wavelet_stiffness (the preconditioner's build) B^k is dropped and nothing else
// changes: the same C̃^k and A^k bit for bit, localized (radius 1, as mra-pcg) and global.
TEST(MraWaveletStiffness, DroppingItChangesNoOtherOperator) {
    const test::GridProblem p =
        test::hung_problem(3, Eigen::Vector3i(8, 8, 8), 1.0, 1e3, test::checker_pattern);
    for (const double radius : {1.0, std::numeric_limits<double>::infinity()}) {
        Options o = test::exact_options(3, Refinement::Linear);
        o.radius = {radius};
        const Hierarchy kept = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
        o.store_wavelet_stiffness = false;
        const Hierarchy dropped = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
        for (int k = 1; k < kept.num_levels(); ++k) {
            EXPECT_GT(kept.level(k).B.nonZeros(), 0);
            EXPECT_EQ(dropped.level(k).B.rows(), 0);
            EXPECT_EQ(Matrix(dropped.level(k).C_adapted.sparse()),
                      Matrix(kept.level(k).C_adapted.sparse()))
                << "radius " << radius << ", level " << k;
            EXPECT_EQ(Matrix(dropped.level(k).A), Matrix(kept.level(k).A));
        }
    }
}

}  // namespace
}  // namespace coarsegrain::mra
