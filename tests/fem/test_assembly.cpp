#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <random>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

/// A small grid of the type over a non-cubic box (about 100-250 DOFs).
mesh::Mesh small_grid(ElementType type) {
    const int dim = mesh::element_dim(type);
    if (dim == 2)
        return mesh::make_grid(type, Eigen::Vector2d(0, 0), Eigen::Vector2d(2, 1),
                               Eigen::Vector2i(7, 5));
    return mesh::make_grid(type, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1.5, 1, 0.7),
                           Eigen::Vector3i(4, 3, 3));
}

/// Two materials in layers: an isotropic one and a generic anisotropic one.
material::ElementMaterials two_materials(mesh::Mesh& m) {
    const int dim = m.dim();
    material::layers(m, 0, 0.0, 0.5, {1, 2});
    return material::assign(
        m,
        {{1, material::isotropic(dim, 100.0, 0.3, 2.0)},
         {2, material::anisotropic(dim, 7.0 * test::random_spd_tensor(mandel_size(dim), 3), 0.5)}});
}

/// Reference assembly: element by element into triplets, serial, through the public element
/// kernels.
SparseMatrix triplet_assembly(const mesh::Mesh& m, const material::ElementMaterials& mats,
                              int what /* 0 stiffness, 1 consistent mass, 2 lumped */) {
    const int dim = m.dim(), npe = mesh::nodes_per_element(m.type);
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index e = 0; e < m.num_elements(); ++e) {
        const Matrix X = m.element_positions(e);
        const material::Material& mat = mats.of(e);
        const Matrix Ke = what == 0 ? fem::element_stiffness(m.type, X, material::tensor(mat, dim))
                                    : fem::element_mass(m.type, X, mat.density, what == 2);
        for (int a = 0; a < npe; ++a)
            for (int b = 0; b < npe; ++b)
                for (int i = 0; i < dim; ++i)
                    for (int j = 0; j < dim; ++j)
                        t.emplace_back(dim * m.elements(e, a) + i, dim * m.elements(e, b) + j,
                                       Ke(dim * a + i, dim * b + j));
    }
    SparseMatrix A(m.num_dofs(), m.num_dofs());
    A.setFromTriplets(t.begin(), t.end());
    return A;
}

/// max |A - B| / max |B| over the stored entries.
double relative_difference(const SparseMatrix& A, const SparseMatrix& B) {
    const SparseMatrix D = A - B;
    const auto max_abs = [](const SparseMatrix& S) {
        return S.nonZeros() ? Eigen::Map<const Eigen::VectorXd>(S.valuePtr(), S.nonZeros())
                                  .cwiseAbs()
                                  .maxCoeff()
                            : 0.0;
    };
    return max_abs(D) / max_abs(B);
}

class AssemblyTest : public ::testing::TestWithParam<ElementType> {};

// Parallel assembly straight into compressed storage equals a serial triplet assembly to
// round-off (1e-14 relative: only the summation order differs), on the grid (cached element
// matrices for quad/hex) and on the distorted mesh (coloured scatter), for K and both masses.
TEST_P(AssemblyTest, EqualsSerialTripletAssembly) {
    for (const bool distorted : {false, true}) {
        mesh::Mesh m = small_grid(GetParam());
        if (distorted) test::distort_interior(m, 0.25);
        const material::ElementMaterials mats = two_materials(m);
        const SparseMatrix K = fem::stiffness_matrix(m, mats);
        EXPECT_TRUE(K.isCompressed());
        EXPECT_LT(relative_difference(K, triplet_assembly(m, mats, 0)), 1e-14);
        EXPECT_LT(relative_difference(fem::mass_matrix(m, mats, fem::MassType::Consistent),
                                      triplet_assembly(m, mats, 1)),
                  1e-14);
        EXPECT_LT(relative_difference(fem::mass_matrix(m, mats, fem::MassType::Lumped),
                                      triplet_assembly(m, mats, 2)),
                  1e-14);
    }
}

// The assembled K (no Dirichlet condition) is symmetric and has exactly 3 (2D) / 6 (3D) zero
// eigenvalues, and the rigid motions lie in its kernel: so the kernel is exactly the rigid
// motions. Dense eigen-solve on ~100-250 DOFs; zero means < 1e-11 of the largest eigenvalue
// (round-off), and the first non-zero one is far above (> 1e-6 of the largest).
TEST_P(AssemblyTest, KernelIsExactlyTheRigidMotions) {
    mesh::Mesh m = small_grid(GetParam());
    test::distort_interior(m, 0.25);
    const material::ElementMaterials mats = two_materials(m);
    const SparseMatrix K = fem::stiffness_matrix(m, mats);
    const Matrix Kd(K);
    EXPECT_EQ((Kd - Kd.transpose()).cwiseAbs().maxCoeff(), 0.0);
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(Kd);
    const Eigen::VectorXd lambda = eig.eigenvalues();
    const double lmax = lambda.maxCoeff();
    const int rigid = m.dim() == 3 ? 6 : 3;
    EXPECT_EQ((lambda.array().abs() < 1e-11 * lmax).count(), rigid);
    EXPECT_GT(lambda[rigid], 1e-6 * lmax);
    const Matrix R = test::rigid_modes(m.rest_positions);
    EXPECT_LT((Kd * R).norm(), 1e-12 * Kd.norm() * R.norm());
}

// The cached grid path and the general path agree on the same geometry (1e-14 relative), and
// every component block of the mass matrix sums to the total mass (1e-13 relative).
TEST_P(AssemblyTest, GridCacheAndMassTotals) {
    mesh::Mesh m = small_grid(GetParam());
    const material::ElementMaterials mats = two_materials(m);
    mesh::Mesh general = m;
    general.grid.reset();
    EXPECT_LT(
        relative_difference(fem::stiffness_matrix(m, mats), fem::stiffness_matrix(general, mats)),
        1e-14);
    double total = 0;
    for (Index e = 0; e < m.num_elements(); ++e)
        total += mats.of(e).density * mesh::element_measure(m, e);
    const int dim = m.dim();
    for (const auto type : {fem::MassType::Consistent, fem::MassType::Lumped}) {
        const SparseMatrix M = fem::mass_matrix(m, mats, type);
        for (int d = 0; d < dim; ++d) {
            Vector ones = Vector::Zero(m.num_dofs());
            for (Index v = 0; v < m.num_nodes(); ++v) ones[dim * v + d] = 1.0;
            EXPECT_NEAR(ones.dot(M * ones), total, 1e-13 * total);
        }
    }
}

/// Renumbers the nodes by a random permutation (fixed seed): a numbering without locality.
void shuffle_nodes(mesh::Mesh& m, unsigned seed) {
    std::vector<Index> perm = test::all_indices(m.num_nodes());
    std::shuffle(perm.begin(), perm.end(), std::mt19937(seed));
    Matrix X(m.rest_positions.rows(), m.rest_positions.cols());
    for (Index v = 0; v < m.num_nodes(); ++v) X.row(perm[v]) = m.rest_positions.row(v);
    m.rest_positions = X;
    for (Index e = 0; e < m.num_elements(); ++e)
        for (Index a = 0; a < m.elements.cols(); ++a) m.elements(e, a) = perm[m.elements(e, a)];
}

/// Runs f with OpenMP set to `threads` threads, then restores the previous setting.
template <class F>
void with_threads(int threads, F&& f) {
    const int before = omp_get_max_threads();
    omp_set_num_threads(threads);
    f();
    omp_set_num_threads(before);
}

// Meshes large enough that every parallel loop runs on 2 threads (node loops, the owner-computes
// scatter with 4 node ranges; with shuffled node numbers the coloured scatter, each colour above
// detail::kMinParallel = 512 elements): the result equals the serial triplet assembly to
// round-off (1e-14 relative), so neither scheme leaves a race.
TEST(AssemblyParallel, MediumMeshesEqualSerialAssembly) {
    with_threads(2, [] {
        for (const ElementType type : {ElementType::Hex8, ElementType::Tet4, ElementType::Tri3})
            for (const bool shuffled : {false, true}) {
                const int n = type == ElementType::Hex8 ? 18 : type == ElementType::Tet4 ? 14 : 100;
                const int dim = mesh::element_dim(type);
                mesh::Mesh m =
                    mesh::make_grid(type, Eigen::VectorXd::Zero(dim), Eigen::VectorXd::Ones(dim),
                                    Eigen::VectorXi::Constant(dim, n));
                if (shuffled) shuffle_nodes(m, 4);
                const material::ElementMaterials grid_mats = two_materials(m);
                if (type == ElementType::Hex8) {
                    EXPECT_LT(relative_difference(fem::stiffness_matrix(m, grid_mats),
                                                  triplet_assembly(m, grid_mats, 0)),
                              1e-14);
                }
                test::distort_interior(m, type == ElementType::Hex8 ? 0.25 : 0.1);
                const material::ElementMaterials mats = two_materials(m);
                EXPECT_LT(relative_difference(fem::stiffness_matrix(m, mats),
                                              triplet_assembly(m, mats, 0)),
                          1e-14)
                    << mesh::element_name(type) << (shuffled ? " shuffled" : "");
                EXPECT_LT(relative_difference(fem::mass_matrix(m, mats, fem::MassType::Consistent),
                                              triplet_assembly(m, mats, 1)),
                          1e-14);
            }
    });
}

TEST(AssemblyErrors, MismatchedMaterials) {
    mesh::Mesh m = small_grid(ElementType::Tet4);
    material::ElementMaterials mats = material::uniform(m, material::isotropic(3, 1, 0.3, 1));
    mats.index.conservativeResize(3);
    EXPECT_THROW(fem::stiffness_matrix(m, mats), Error);
    mats = material::uniform(m, material::isotropic(2, 1, 0.3, 1));
    mats.dim = 2;
    EXPECT_THROW(fem::mass_matrix(m, mats, fem::MassType::Lumped), Error);
    // An inverted element is reported (from inside the parallel loop).
    mesh::Mesh bad = small_grid(ElementType::Tet4);
    std::swap(bad.elements(5, 1), bad.elements(5, 2));
    mats = material::uniform(bad, material::isotropic(3, 1, 0.3, 1));
    try {
        fem::stiffness_matrix(bad, mats);
        ADD_FAILURE() << "no error for an inverted element";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("element 5: element is inverted"), std::string::npos)
            << e.what();
    }
}

INSTANTIATE_TEST_SUITE_P(AllTypes, AssemblyTest,
                         ::testing::Values(ElementType::Tri3, ElementType::Quad4, ElementType::Tet4,
                                           ElementType::Hex8),
                         [](const auto& param_info) {
                             return mesh::element_name(param_info.param);
                         });

}  // namespace
