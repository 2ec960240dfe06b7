#include <gtest/gtest.h>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

struct PatchCase {
    ElementType type;
    bool anisotropic;
};

class PatchTest : public ::testing::TestWithParam<PatchCase> {};

// Patch test: with u = A x + b imposed on the boundary of a distorted mesh and no load, the
// exact solution is that linear field, which P1 and Q1 reproduce; the computed interior
// displacements match it to 1e-10 relative (direct solve of a few hundred DOFs: round-off
// times a modest condition number), for an isotropic and a generic anisotropic material.
// Every element then carries the uniform strain sym(A) and stress C sym(A) (1e-10 relative).
TEST_P(PatchTest, LinearFieldIsReproduced) {
    const auto [type, anisotropic] = GetParam();
    const int dim = mesh::element_dim(type);
    mesh::Mesh m = dim == 2 ? mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1),
                                              Eigen::Vector2i(6, 5))
                            : mesh::make_grid(type, Eigen::Vector3d(0, 0, 0),
                                              Eigen::Vector3d(1, 1.5, 1), Eigen::Vector3i(4, 5, 4));
    test::distort_interior(m, mesh::is_simplex(type) ? 0.12 : 0.25);
    const material::Material mat =
        anisotropic ? material::anisotropic(dim, test::random_spd_tensor(mandel_size(dim), 9), 1)
                    : material::isotropic(dim, 2.0, 0.3, 1);
    const material::ElementMaterials mats = material::uniform(m, mat);
    const auto [A, exact, bc] = test::affine_patch(m);
    ASSERT_LT(static_cast<Index>(bc.dofs.size()), m.num_dofs());  // there is an interior
    const SparseMatrix K = fem::stiffness_matrix(m, mats);
    const Vector u = test::solve_dirichlet(K, Vector::Zero(m.num_dofs()), bc);
    EXPECT_LT((u - exact).lpNorm<Eigen::Infinity>(), 1e-10 * exact.lpNorm<Eigen::Infinity>());

    const Eigen::VectorXd e = test::mandel_strain(A);
    const fem::ElementStress s = fem::element_stress(m, mats, u);
    const Eigen::VectorXd sigma = material::tensor(mat, dim) * e;
    for (Index el = 0; el < m.num_elements(); ++el) {
        EXPECT_LT((s.strain.row(el).transpose() - e).norm(), 1e-10 * e.norm());
        EXPECT_LT((s.stress.row(el).transpose() - sigma).norm(), 1e-10 * sigma.norm());
    }
}

std::string case_name(const ::testing::TestParamInfo<PatchCase>& param_info) {
    return mesh::element_name(param_info.param.type) +
           (param_info.param.anisotropic ? "_anisotropic" : "_isotropic");
}

INSTANTIATE_TEST_SUITE_P(
    AllTypes, PatchTest,
    ::testing::Values(PatchCase{ElementType::Tri3, false}, PatchCase{ElementType::Tri3, true},
                      PatchCase{ElementType::Quad4, false}, PatchCase{ElementType::Quad4, true},
                      PatchCase{ElementType::Tet4, false}, PatchCase{ElementType::Tet4, true},
                      PatchCase{ElementType::Hex8, false}, PatchCase{ElementType::Hex8, true}),
    case_name);

}  // namespace
