// The coarse-model runtime: solve, carry to the fine mesh, compare (coarsen/runtime.hpp).
#include <gtest/gtest.h>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

// A 2D layered plate (contrast 100) clamped on the left, under gravity: 8x4 quads.
scene::Scene plate() {
    const nlohmann::json j = {
        {"mesh",
         {{"grid", {{"min", {0, 0}}, {"max", {2, 1}}, {"cells", {8, 4}}, {"element", "quad"}}}}},
        {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.25}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 100.0}, {"nu", 0.3}, {"density", 1.0}}},
          {"2", {{"E", 1.0}, {"nu", 0.3}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1, -1}}, {"max", {1e-9, 2}}}}}}},
        {"loads", {{"gravity", {0, -1}}}}};
    return scene::parse_scene(j, "plate", "");
}

// Interpolation of the nodes of `coarse` (a grid covering the same box) at the fine nodes.
SparseMatrix embedding(const mesh::Mesh& coarse, const mesh::Mesh& fine) {
    const int dim = fine.dim();
    const mesh::PointLocator locator(coarse);
    std::vector<Eigen::Triplet<double>> t;
    for (Index v = 0; v < fine.num_nodes(); ++v) {
        const auto loc = locator.locate(fine.rest_positions.row(v).transpose());
        EXPECT_TRUE(loc.has_value());
        for (Index a = 0; a < loc->weights.size(); ++a)
            for (int d = 0; d < dim; ++d)
                t.emplace_back(dim * v + d, dim * coarse.elements(loc->element, a) + d,
                               loc->weights[a]);
    }
    SparseMatrix P(fine.num_dofs(), coarse.num_dofs());
    P.setFromTriplets(t.begin(), t.end());
    return P;
}

TEST(CoarseRuntime, FineModelAsItsOwnCoarseModelHasNoError) {
    const scene::Scene sc = plate();
    const scene::FineModel fine = scene::build_fine_model(sc);
    coarsen::CoarseModel m;
    m.K = fine.K;
    m.f = fine.f;
    m.bc = fine.bc;
    SparseMatrix identity(fine.K.rows(), fine.K.cols());
    identity.setIdentity();
    m.to_fine = identity;
    const coarsen::CoarseSolution uc = coarsen::solve_coarse(m, sc.solver);
    const Vector u = scene::solve_static(fine, sc.solver).u;
    const coarsen::Errors e = coarsen::compare(fine, u, uc.u_fine);
    // Same matrix, same solver: only round-off of two identical factorizations differs.
    EXPECT_LT(e.l2_rel, 1e-12);
    EXPECT_LT(e.energy_rel, 1e-12);
    EXPECT_NEAR(e.compliance_ratio, 1.0, 1e-12);
    EXPECT_LT(e.max_displacement_rel, 1e-12);
    EXPECT_LT(e.stress_rel, 1e-12);
}

TEST(CoarseRuntime, ErrorsOfAScaledSolutionAreExact) {
    const scene::Scene sc = plate();
    const scene::FineModel fine = scene::build_fine_model(sc);
    const Vector u = scene::solve_static(fine, sc.solver).u;
    const coarsen::Errors e = coarsen::compare(fine, u, 0.5 * u);
    EXPECT_NEAR(e.l2_rel, 0.5, 1e-14);
    EXPECT_NEAR(e.energy_rel, 0.5, 1e-14);
    EXPECT_NEAR(e.max_displacement_rel, 0.5, 1e-14);
    EXPECT_NEAR(e.compliance_ratio, 0.5, 1e-14);
    EXPECT_NEAR(e.stress_rel, 0.5, 1e-14);  // stress is linear in u
    // ||u||_K^2 = f.u at equilibrium (the conditions are homogeneous), so the paper's
    // normalisation by |f| is energy_rel * sqrt(f.u) / |f|. Equilibrium holds up to the solve's
    // residual r: f.u - ||u||_K^2 = u.r, 2.5e-13 relative here (it depends on the ordering's
    // round-off), so the bound is 1e-12 relative.
    // The load at the clamped DOFs does no work: |f| counts the free DOFs only.
    Vector f_free = fine.f;
    for (const Index dof : fine.bc.dofs) f_free[dof] = 0;
    ASSERT_GT(fine.f.norm(), f_free.norm());  // gravity loads the clamped nodes too
    const double expected = 0.5 * std::sqrt(fine.f.dot(u)) / f_free.norm();
    EXPECT_NEAR(e.energy_over_load, expected, 1e-12 * expected);
}

// A Galerkin coarse model K_c = P^T K P, f_c = P^T f on a nested grid is the energy projection of
// the fine solution: ||u - P u_c||_K^2 = ||u||_K^2 - ||P u_c||_K^2 and f.P u_c = ||P u_c||_K^2,
// so the compliance ratio is 1 - energy_rel^2 (to round-off).
TEST(CoarseRuntime, GalerkinModelIsTheEnergyProjection) {
    const scene::Scene sc = plate();
    const scene::FineModel fine = scene::build_fine_model(sc);
    const mesh::Mesh coarse = mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d(0, 0),
                                              Eigen::Vector2d(2, 1), Eigen::Vector2i(4, 2));
    const SparseMatrix P = embedding(coarse, fine.mesh);
    coarsen::CoarseModel m;
    m.K = SparseMatrix(P.transpose() * fine.K * P);
    m.f = P.transpose() * fine.f;
    for (Index v = 0; v < coarse.num_nodes(); ++v)
        if (coarse.rest_positions(v, 0) < 1e-9) m.bc.fix_nodes({v}, Eigen::Vector2d::Zero());
    m.to_fine = P;
    const coarsen::CoarseSolution uc = coarsen::solve_coarse(m, sc.solver);
    const Vector u = scene::solve_static(fine, sc.solver).u;
    const coarsen::Errors e = coarsen::compare(fine, u, uc.u_fine);
    EXPECT_GT(e.energy_rel, 0.05);  // a real coarsening error, not a trivial case
    EXPECT_NEAR(e.compliance_ratio, 1.0 - e.energy_rel * e.energy_rel, 1e-10);
}

TEST(FineMap, AppliesItsMatrixOrItsFunctionAndChecksSizes) {
    SparseMatrix M(3, 2);
    M.insert(0, 0) = 2.0;
    M.insert(2, 1) = -1.0;
    const coarsen::FineMap by_matrix = M;
    const coarsen::FineMap by_function(3, 2, [&M](const Vector& u) { return Vector(M * u); });
    const Vector u = Vector::LinSpaced(2, 1.0, 3.0);
    const Matrix U = Matrix::Random(2, 4);
    for (const coarsen::FineMap* f : {&by_matrix, &by_function}) {
        EXPECT_EQ(f->rows(), 3);
        EXPECT_EQ(f->cols(), 2);
        EXPECT_EQ(*f * u, Vector(M * u));  // the same arithmetic: bit for bit
        EXPECT_EQ(*f * U, Matrix(M * U));
        test::expect_error([&] { (void)(*f * Vector::Ones(3)); }, "3 coarse values for 2");
    }
    const coarsen::FineMap short_output(3, 2, [](const Vector&) { return Vector::Ones(2); });
    test::expect_error([&] { (void)(short_output * u); }, "2 fine values for 3 fine DOFs");
}

TEST(CoarseRuntime, MismatchedSizesAreAnError) {
    coarsen::CoarseModel m;
    m.method = "broken";
    m.K = SparseMatrix(6, 6);
    m.f = Vector::Zero(4);
    m.to_fine = SparseMatrix(10, 6);
    test::expect_error([&] { coarsen::solve_coarse(m, {}); }, "coarse model broken");
}

}  // namespace
}  // namespace coarsegrain
