// The incompatible-mode element (fem::Formulation::Incompatible, Quad4 / Hex8): element
// properties, the patch test, convergence to the standard element's answer under refinement,
// and the formulation's checks. CalculiX agreement: test_calculix.cpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../../src/fem/element_kernels.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

/// A distorted Q1 element: the unit square / cube scaled, sheared, each corner moved by up to
/// 0.2 (fixed seed). Not a parallelogram / parallelepiped.
Matrix distorted_q1(ElementType type, unsigned seed) {
    const int dim = mesh::element_dim(type);
    const int npe = mesh::nodes_per_element(type);
    static const int corners[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                      {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    Matrix X(npe, dim);
    for (int a = 0; a < npe; ++a)
        for (int d = 0; d < dim; ++d)
            X(a, d) = (d == 0 ? 1.6 : 1.0) * corners[a][d] + (d == 0 ? 0.3 * corners[a][1] : 0.0) +
                      0.2 * U(rng) + 1.0;
    return X;
}

double element_volume(ElementType type, const Matrix& X) {
    mesh::Mesh m;
    m.type = type;
    m.rest_positions = X;
    m.elements = IndexMatrix(1, X.rows());
    for (Index a = 0; a < X.rows(); ++a) m.elements(0, a) = a;
    return mesh::element_measure(m, 0);
}

class IncompatibleElement : public ::testing::TestWithParam<ElementType> {};

// K_e is exactly symmetric, PSD, and its kernel is exactly the rigid motions (3 in 2D, 6 in
// 3D), on distorted elements, for a generic anisotropic tensor and a near-incompressible
// isotropic one (nu = 0.4999).
TEST_P(IncompatibleElement, SymmetricPsdWithExactlyTheRigidKernel) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    const int rigid = dim == 3 ? 6 : 3;
    for (unsigned seed = 1; seed <= 5; ++seed) {
        const Matrix X = distorted_q1(type, seed);
        for (const bool anisotropic : {true, false}) {
            const Matrix C =
                anisotropic
                    ? test::random_spd_tensor(mandel_size(dim), seed)
                    : Matrix(material::tensor(material::isotropic(dim, 1.0, 0.4999, 1), dim));
            const Matrix K = fem::element_stiffness(type, X, C, fem::Formulation::Incompatible);
            EXPECT_EQ((K - K.transpose()).norm(), 0.0);  // symmetrized in the kernel
            // Rigid motions: K R is round-off (1e-12 relative to |K| |R|; the condensation
            // K_uu - K_ua K_aa^-1 K_au costs a little more than the plain element's 1e-13).
            const Matrix R = test::rigid_modes(X);
            EXPECT_LT((K * R).norm(), 1e-12 * K.norm() * R.norm());
            // Eigenvalues: the rigid ones are round-off (|lambda| < 1e-12 of the largest, and
            // none below that: PSD); the next is a deformation mode, which for nu = 0.4999 is
            // a shear mode with about mu / lambda = 2e-4 of the largest, times a geometric
            // factor of these elements' shapes; the bound 1e-7 leaves room for that factor.
            const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Matrix>(K).eigenvalues();
            const double lmax = lambda.maxCoeff();
            EXPECT_GT(lambda.minCoeff(), -1e-12 * lmax);
            EXPECT_EQ((lambda.array().abs() < 1e-12 * lmax).count(), rigid);
            EXPECT_GT(lambda[rigid], 1e-7 * lmax);
        }
    }
}

// Element patch test: for a linear field u = A x (uniform strain e) the condensed element's
// energy is exactly vol e^T C e, which holds only if the modes' amplitudes are zero (the
// condensed energy minimizes over them, and the modes' strain is orthogonal to uniform strains
// only with Taylor's j0 / j): the enriched strain is then e at every point, constant stress.
// 1e-12 relative: round-off. CalculiX's mapping (no j0 / j) fails it on the same distorted
// element (the energy drops by more than 1e-5 relative), and passes on a
// parallelepiped, where the two are the same element (test_calculix.cpp).
TEST_P(IncompatibleElement, UniformStrainEnergyIsExactOnDistortedElements) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    for (unsigned seed = 1; seed <= 5; ++seed) {
        const Matrix X = distorted_q1(type, seed);
        const Matrix C = test::random_spd_tensor(mandel_size(dim), seed + 10);
        Matrix A(dim, dim);
        A.setRandom();
        const Vector u = test::linear_field(X, A, Eigen::VectorXd::Ones(dim));
        const Eigen::VectorXd e = test::mandel_strain(A);
        const double expected = element_volume(type, X) * e.dot(C * e);
        const Matrix K = fem::element_stiffness(type, X, C, fem::Formulation::Incompatible);
        EXPECT_NEAR(u.dot(K * u), expected, 1e-12 * expected);

        double calculix = 0;
        if (dim == 3) {
            using S = fem::kernels::Q1<3>;
            const auto Kc =
                fem::kernels::incompatible_stiffness<S, fem::kernels::ModeMapping::CalculiX>(X, C);
            calculix = u.dot(Kc * u);
        } else {
            using S = fem::kernels::Q1<2>;
            const auto Kc =
                fem::kernels::incompatible_stiffness<S, fem::kernels::ModeMapping::CalculiX>(X, C);
            calculix = u.dot(Kc * u);
        }
        EXPECT_LT(calculix, (1 - 1e-5) * expected) << "CalculiX's mapping passes on seed " << seed;
    }
}

// Patch test on a patch of distorted elements: u = A x + b imposed on the boundary, no load;
// the interior displacements are the linear field to 1e-10 relative (direct solve, round-off
// times the condition number, as in test_patch.cpp) and every element has the strain and stress
// of the field. Isotropic nu = 0.45 and a generic anisotropic tensor.
TEST_P(IncompatibleElement, PatchTestOnADistortedMesh) {
    const ElementType type = GetParam();
    const int dim = mesh::element_dim(type);
    mesh::Mesh m = dim == 2 ? mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1),
                                              Eigen::Vector2i(6, 5))
                            : mesh::make_grid(type, Eigen::Vector3d(0, 0, 0),
                                              Eigen::Vector3d(1, 1.5, 1), Eigen::Vector3i(4, 5, 4));
    test::distort_interior(m, 0.25);
    for (const bool anisotropic : {false, true}) {
        const material::Material mat =
            anisotropic
                ? material::anisotropic(dim, test::random_spd_tensor(mandel_size(dim), 9), 1)
                : material::isotropic(dim, 2.0, 0.45, 1);
        const material::ElementMaterials mats = material::uniform(m, mat);
        const auto [A, exact, bc] = test::affine_patch(m);
        const SparseMatrix K = fem::stiffness_matrix(m, mats, fem::Formulation::Incompatible);
        const Vector u = test::solve_dirichlet(K, Vector::Zero(m.num_dofs()), bc);
        EXPECT_LT((u - exact).lpNorm<Eigen::Infinity>(), 1e-10 * exact.lpNorm<Eigen::Infinity>());
        const Eigen::VectorXd e = test::mandel_strain(A);
        const Eigen::VectorXd sigma = material::tensor(mat, dim) * e;
        const fem::ElementStress s = fem::element_stress(m, mats, u);
        for (Index el = 0; el < m.num_elements(); ++el)
            EXPECT_LT((s.stress.row(el).transpose() - sigma).norm(), 1e-10 * sigma.norm());
    }
}

INSTANTIATE_TEST_SUITE_P(Q1, IncompatibleElement,
                         ::testing::Values(ElementType::Quad4, ElementType::Hex8),
                         [](const auto& param_info) {
                             return mesh::element_name(param_info.param);
                         });

// Tip deflection of the 4 x 1 (x 1) cantilever of bench/bench_locking (E = 1000, density 1,
// gravity 1, clamped at x = 0) at the centre of the free end.
double cantilever_tip(ElementType type, const Eigen::VectorXi& cells, double nu,
                      fem::Formulation f) {
    const int dim = mesh::element_dim(type);
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim);
    Eigen::VectorXd hi = Eigen::VectorXd::Ones(dim);
    hi[0] = 4;
    const mesh::Mesh m = mesh::make_grid(type, lo, hi, cells);
    const material::ElementMaterials mats =
        material::uniform(m, material::isotropic(dim, 1000.0, nu, 1.0));
    Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
    g[dim - 1] = -1;
    const Vector force = fem::gravity_load(m, mats, g);
    Eigen::VectorXd box_lo = Eigen::VectorXd::Constant(dim, -1),
                    box_hi = Eigen::VectorXd::Constant(dim, 2);
    box_lo[0] = -1e-9;
    box_hi[0] = 1e-9;
    fem::Dirichlet bc;
    bc.fix_nodes(mesh::nodes_in_box(m, box_lo, box_hi), Eigen::VectorXd::Zero(dim));
    const Vector u = test::solve_dirichlet(fem::stiffness_matrix(m, mats, f), force, bc);
    Eigen::VectorXd tip = Eigen::VectorXd::Constant(dim, 0.5);
    tip[0] = 4;
    const auto loc = mesh::PointLocator(m).locate(tip);
    return -mesh::interpolate(m, *loc, u, dim)[dim - 1];
}

// Under refinement both formulations converge to the same answer: the difference of their
// cantilever tip deflections (nu = 0.3) shrinks by a factor of at least 3 per halving of h.
// Expected: Q1's deflection error is O(h^2), lowered to about h^1.3 for each element by the
// clamp's corner singularity, which the two share, so their difference converges at about h^2
// (measured factors: 2D 3.43, 3.67, 3.68; 3D 3.39, 3.62); 3 leaves room. At the finest grid
// they agree within 1% (measured 0.27% in 2D at 64x16, 0.93% in 3D at 32x8x8).
TEST(IncompatibleConvergence, BothFormulationsConvergeToTheSameAnswer) {
    struct Case {
        ElementType type;
        std::vector<Eigen::VectorXi> grids;
    };
    const std::vector<Case> cases = {
        {ElementType::Quad4,
         {Eigen::Vector2i(8, 2), Eigen::Vector2i(16, 4), Eigen::Vector2i(32, 8),
          Eigen::Vector2i(64, 16)}},
        {ElementType::Hex8,
         {Eigen::Vector3i(8, 2, 2), Eigen::Vector3i(16, 4, 4), Eigen::Vector3i(32, 8, 8)}}};
    for (const Case& c : cases) {
        std::vector<double> diff;
        double last_incompatible = 0;
        for (const Eigen::VectorXi& g : c.grids) {
            const double s = cantilever_tip(c.type, g, 0.3, fem::Formulation::Standard);
            last_incompatible = cantilever_tip(c.type, g, 0.3, fem::Formulation::Incompatible);
            diff.push_back(std::abs(last_incompatible - s));
        }
        for (std::size_t i = 1; i < diff.size(); ++i) {
            RecordProperty(fmt::format("{}_ratio_{}", mesh::element_name(c.type), i),
                           fmt::format("{:.3f}", diff[i - 1] / diff[i]));
            EXPECT_GT(diff[i - 1] / diff[i], 3.0) << mesh::element_name(c.type) << " refinement "
                                                  << i << ": " << diff[i - 1] << " -> " << diff[i];
        }
        EXPECT_LT(diff.back(), 0.01 * last_incompatible);
    }
}

// Near incompressibility (nu = 0.499) the incompatible element converges from the first grids
// while the standard one locks: on the 2D cantilever at 32x8 within 2% of the converged answer
// 0.3025 (bench/bench_locking: -1.6%) while the standard element is off by more than half
// (-66%); both move toward the same answer under refinement.
TEST(IncompatibleConvergence, DoesNotLockNearIncompressibility) {
    const double converged = 0.302480;  // bench/bench_locking, Richardson on 64x16..256x64
    const double inc = cantilever_tip(ElementType::Quad4, Eigen::Vector2i(32, 8), 0.499,
                                      fem::Formulation::Incompatible);
    const double std32 = cantilever_tip(ElementType::Quad4, Eigen::Vector2i(32, 8), 0.499,
                                        fem::Formulation::Standard);
    const double std64 = cantilever_tip(ElementType::Quad4, Eigen::Vector2i(64, 16), 0.499,
                                        fem::Formulation::Standard);
    EXPECT_LT(std::abs(inc / converged - 1), 0.02);
    EXPECT_LT(std32 / converged, 0.5);
    EXPECT_GT(std64, std32);  // the standard element creeps toward it
    // One element through the depth: bending without shear locking (see cantilever_tip).
    const double one = cantilever_tip(ElementType::Quad4, Eigen::Vector2i(16, 1), 0.3,
                                      fem::Formulation::Incompatible);
    EXPECT_LT(std::abs(one / 0.370366 - 1), 0.01);  // 0.370366: converged at nu = 0.3
}

// The formulation applies to Quad4 / Hex8 only; names parse and print.
TEST(IncompatibleFormulation, NamesAndElementTypes) {
    EXPECT_EQ(fem::parse_formulation("incompatible"), fem::Formulation::Incompatible);
    EXPECT_EQ(fem::parse_formulation("standard"), fem::Formulation::Standard);
    EXPECT_EQ(fem::formulation_name(fem::Formulation::Incompatible), "incompatible");
    test::expect_error([] { fem::parse_formulation("bbar"); },
                       "expected \"standard\" or \"incompatible\"");
    EXPECT_TRUE(fem::formulation_applies(fem::Formulation::Incompatible, ElementType::Hex8));
    EXPECT_TRUE(fem::formulation_applies(fem::Formulation::Incompatible, ElementType::Quad4));
    EXPECT_FALSE(fem::formulation_applies(fem::Formulation::Incompatible, ElementType::Tet4));
    EXPECT_FALSE(fem::formulation_applies(fem::Formulation::Incompatible, ElementType::Tri3));
    const mesh::Mesh tets = mesh::make_grid(ElementType::Tet4, Eigen::Vector3d(0, 0, 0),
                                            Eigen::Vector3d(1, 1, 1), Eigen::Vector3i(1, 1, 1));
    const material::ElementMaterials mats =
        material::uniform(tets, material::isotropic(3, 1.0, 0.3, 1.0));
    test::expect_error([&] { fem::stiffness_matrix(tets, mats, fem::Formulation::Incompatible); },
                       "fem.formulation \"incompatible\" does not apply to tet elements");
    test::expect_error(
        [&] {
            fem::element_stiffness(ElementType::Tri3, Matrix::Identity(3, 2),
                                   Matrix::Identity(3, 3), fem::Formulation::Incompatible);
        },
        "does not apply to tri elements");
}

}  // namespace
