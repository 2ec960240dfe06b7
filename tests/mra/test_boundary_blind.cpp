// The boundary-blind construction (DirichletTreatment::Ignore; Chen et al. 2019, Sec. 1 and
// Fig. 12, about Chen et al. 2018): the hierarchy built on the unconstrained stiffness, the
// Dirichlet conditions applied on a level only when it is solved.
#include <gtest/gtest.h>

#include <cstdio>
#include <limits>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra_test_util.hpp"

namespace coarsegrain::mra {
namespace {

using BlindParam = std::tuple<int, Refinement>;

/// The rigid motions on every DOF of a mesh: translations, then rotations about the origin
/// (2D: one, 3D: about each axis).
Matrix rigid_motions(const mesh::Mesh& m) {
    const int dim = m.dim();
    const int nrot = dim == 3 ? 3 : 1;
    Matrix r = Matrix::Zero(m.num_dofs(), dim + nrot);
    for (Index v = 0; v < m.num_nodes(); ++v) {
        const Eigen::VectorXd x = m.rest_positions.row(v).transpose();
        for (int d = 0; d < dim; ++d) r(dim * v + d, d) = 1.0;
        if (dim == 2) {
            r(2 * v, 2) = -x[1];
            r(2 * v + 1, 2) = x[0];
            continue;
        }
        for (int a = 0; a < 3; ++a) {  // e_a x x
            const Eigen::Vector3d w =
                Eigen::Vector3d::Unit(a).cross(Eigen::Vector3d(x[0], x[1], x[2]));
            for (int d = 0; d < 3; ++d) r(3 * v + d, 3 + a) = w[d];
        }
    }
    return r;
}

class MraBoundaryBlind : public ::testing::TestWithParam<BlindParam> {
  protected:
    int dim() const { return std::get<0>(GetParam()); }
    Refinement refinement() const { return std::get<1>(GetParam()); }
    test::GridProblem problem() const {
        const Eigen::Vector3i cells =
            dim() == 2 ? Eigen::Vector3i(8, 8, 1) : Eigen::Vector3i(4, 4, 4);
        return test::hung_problem(dim(), cells, 1.0, 1e3, test::checker_pattern);
    }
    Options options() const {
        Options o;
        o.levels = 3;
        o.refinement = refinement();
        o.dirichlet = DirichletTreatment::Ignore;
        return o;
    }
};

/// Largest ||A^k r^k|| / (||A^k|| ||r^k||) over the rigid motions and levels k < q, with the
/// measured motions r^k = C^k r^{k+1} (r^q the fine ones on the hierarchy's fine DOFs).
double rigid_defect(const Hierarchy& h, const mesh::Mesh& m) {
    Matrix r = rigid_motions(m)(h.fine_dofs, Eigen::all);
    double worst = 0;
    for (int k = h.num_levels() - 1; k >= 1; --k) {
        r = h.level(k).C * r;
        const SparseMatrix A = symmetric_from_lower(h.level(k).A);
        for (Index c = 0; c < r.cols(); ++c)
            worst = std::max(worst, (A * r.col(c)).norm() / (A.norm() * r.col(c).norm()));
    }
    return worst;
}

// The construction never sees the conditions, so the invariance correction applies at every
// fine node and each level's basis reproduces the rigid motions exactly: C̃^{k,T} r^k = r^{k+1}
// and, since K r^q = 0, A^k r^k = C̃^k A^{k+1} r^{k+1} = 0 on every level, to round-off, with
// global and localized solves alike. The constrained hierarchy's A^k are definite (measured
// defect >= 1e-2 here).
TEST_P(MraBoundaryBlind, RigidMotionsSpanTheKernelOfEveryLevel) {
    const test::GridProblem p = problem();
    for (const double radius : {std::numeric_limits<double>::infinity(), 2.0}) {
        Options o = options();
        o.radius = {radius};
        const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, o);
        ASSERT_EQ(h.fine_dofs.size(), p.mesh.num_dofs());  // nothing eliminated
        EXPECT_EQ(h.fine_fixed.size(), static_cast<Index>(p.bc.dofs.size()));
        for (int k = 1; k < h.num_levels(); ++k) EXPECT_GT(h.level(k).fixed.size(), 0);
        o.dirichlet = DirichletTreatment::Constrain;
        const double blind = rigid_defect(h, p.mesh);
        const double constrained = rigid_defect(build_hierarchy(p.mesh, p.K, p.bc.dofs, o), p.mesh);
        std::printf("radius %g: rigid defect blind %.2g, constrained %.2g\n", radius, blind,
                    constrained);
        EXPECT_LE(blind, 1e-12) << "radius " << radius;
        EXPECT_GT(constrained, 1e-3) << "radius " << radius;
    }
}

// Solves at level k hold the level's fixed DOFs at zero and are Galerkin on the others: the
// residual f - K u of the reconstruction, coarse-grained to level k, vanishes at the free
// positions (to round-off against the coarse-grained load). The fine level is the fine solve.
// The coarse reconstructions do not vanish at the fixed fine DOFs: the conditions are not in
// the basis functions, as they are with the constrained treatment (exactly zero there).
TEST_P(MraBoundaryBlind, LevelSolvesAreGalerkinOnTheFreeDofsAndBlindAtTheFixedOnes) {
    const test::GridProblem p = problem();
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, options());
    MultilevelSolver solver(h);
    const int q = h.num_levels();
    const Vector u_fine = solver.solve_level(p.f, q);
    EXPECT_LE((u_fine - p.u).norm(), 1e-10 * p.u.norm());
    for (int k = 1; k < q; ++k) {
        const Vector u = solver.solve_level(p.f, k);
        const Vector residual = coarse_grain(h, p.f - p.K * u, k);
        const Vector load = coarse_grain(h, p.f, k);
        const IndexVector free = free_positions(h, k);
        EXPECT_LE(residual(free).norm(), 1e-10 * load.norm()) << "level " << k;
        double at_fixed = 0;
        for (const Index d : p.bc.dofs) at_fixed = std::max(at_fixed, std::abs(u[d]));
        EXPECT_GT(at_fixed, 1e-3 * u.cwiseAbs().maxCoeff()) << "level " << k;
    }
}

TEST_P(MraBoundaryBlind, WaveletSolvesAreRefused) {
    const test::GridProblem p = problem();
    const Hierarchy h = build_hierarchy(p.mesh, p.K, p.bc.dofs, options());
    MultilevelSolver solver(h);
    EXPECT_NO_THROW(solver.solve_levels(p.f, 1));
    EXPECT_THROW(solver.solve(p.f), Error);
}

INSTANTIATE_TEST_SUITE_P(Mra, MraBoundaryBlind,
                         ::testing::Combine(::testing::Values(2, 3),
                                            ::testing::Values(Refinement::Dirac,
                                                              Refinement::Linear)),
                         [](const auto& p) { return test::dim_refinement_label(p.param); });

}  // namespace
}  // namespace coarsegrain::mra
