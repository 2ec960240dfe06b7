// Effective tensors and directional Young's modulus of coarsest cells (Chen 2019, Sec. 5.6).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mra/cell_tensors.hpp"
#include "test_util.hpp"

namespace coarsegrain::mra {
namespace {

mesh::Mesh unit_grid(int dim, int n) {
    if (dim == 2)
        return mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d(0, 0),
                               Eigen::Vector2d(1, 1), Eigen::Vector2i(n, n));
    return mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                           Eigen::Vector3d(1, 1, 1), Eigen::Vector3i(n, n, n));
}

/// Mandel strain vector of the symmetric part of A.
Vector mandel_strain(const Matrix& A) {
    const Matrix e = 0.5 * (A + A.transpose());
    if (A.rows() == 2) return Eigen::Vector3d(e(0, 0), e(1, 1), kSqrt2 * e(0, 1));
    Vector v(6);
    v << e(0, 0), e(1, 1), e(2, 2), kSqrt2 * e(1, 2), kSqrt2 * e(0, 2), kSqrt2 * e(0, 1);
    return v;
}

/// Free-body solutions K u = F with the rigid motions removed by pinning dim(dim+1)/2 DOFs in
/// a statically determinate way (node 0 fully, the x-corner node in y (and z), the y-corner
/// node in z): F is self-equilibrated, so the pins carry no force and u is the free-body
/// solution up to a rigid motion. Dense LDL^T: an independent solve for small grids.
Matrix free_body_solve(const mesh::Mesh& mesh, const SparseMatrix& K, const Matrix& F) {
    const int dim = mesh.dim();
    const int n = mesh.grid->cells[0];
    const Index x_corner = n, y_corner = static_cast<Index>(n + 1) * n;
    std::vector<Index> pinned = {0, 1};
    if (dim == 2) {
        pinned.push_back(2 * x_corner + 1);
    } else {
        pinned.insert(pinned.end(), {2, 3 * x_corner + 1, 3 * x_corner + 2, 3 * y_corner + 2});
    }
    std::vector<Index> free;
    for (Index i = 0; i < K.rows(); ++i)
        if (std::find(pinned.begin(), pinned.end(), i) == pinned.end()) free.push_back(i);
    const Matrix Kd(K);
    Matrix Kf(free.size(), free.size()), Ff(free.size(), F.cols());
    for (std::size_t i = 0; i < free.size(); ++i) {
        Ff.row(static_cast<Index>(i)) = F.row(free[i]);
        for (std::size_t j = 0; j < free.size(); ++j)
            Kf(static_cast<Index>(i), static_cast<Index>(j)) = Kd(free[i], free[j]);
    }
    const Matrix uf = Kf.ldlt().solve(Ff);
    Matrix U = Matrix::Zero(K.rows(), F.cols());
    for (std::size_t i = 0; i < free.size(); ++i) U.row(free[i]) = uf.row(static_cast<Index>(i));
    return U;
}

Options exact_options() {
    Options o;
    o.radius = {std::numeric_limits<double>::infinity()};
    o.truncation = 0;
    return o;
}

/// Checks, for one free body, the fine compliance against `S_fine_expected` (if given) and
/// the Galerkin identity S_fine - S = (U - U^1)^T K (U - U^1) / |cell| against a second
/// computation of the coarsest solve (the hierarchy rebuilt here, A^1 pseudo-inverted by a
/// complete orthogonal decomposition). Returns {S_fine, S}.
std::pair<Matrix, Matrix> check_cell(const mesh::Mesh& mesh,
                                     const material::ElementMaterials& mats) {
    const SparseMatrix K = fem::stiffness_matrix(mesh, mats);
    const Matrix F = uniform_stress_loads(mesh);
    const Matrix U = free_body_solve(mesh, K, F);
    const Matrix S_fine = F.transpose() * U;  // unit volume
    const CellTensor t = coarsest_cell_tensor(mesh, mats, exact_options());

    Options o = exact_options();
    int levels = 1;
    while ((1 << (levels - 1)) < mesh.grid->cells[0]) ++levels;
    o.levels = levels;
    const Hierarchy h = build_hierarchy(mesh, K, {}, o);
    const Matrix A1(symmetric_from_lower(h.level(1).A));
    // Rank decision relative to the largest pivot: the rigid-motion eigenvalues of A^1 are
    // round-off (their size depends on the order of the Galerkin products), the elastic ones
    // are above 1e-4 of the largest here.
    Eigen::CompleteOrthogonalDecomposition<Matrix> cod(A1.rows(), A1.cols());
    cod.setThreshold(1e-10);
    cod.compute(A1);
    const Matrix A1_pinv = cod.pseudoInverse();
    Matrix U1(U.rows(), U.cols());
    for (Index a = 0; a < F.cols(); ++a)
        U1.col(a) = reconstruct(h, A1_pinv * coarse_grain(h, F.col(a), 1), 1);
    const Matrix E = U - U1;
    const Matrix gap = E.transpose() * (K * E);
    // 1e-8 of |S_fine|: the compliances are sums of O(1e3) products of a well-conditioned
    // small problem; the COD's rank decision and the eigen-based pseudo-inverse agree to
    // round-off.
    EXPECT_LT((S_fine - t.S - gap).norm(), 1e-8 * S_fine.norm());
    // The coarse cell is stiffer (Galerkin): S_fine - S is positive semi-definite.
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix>(S_fine - t.S).eigenvalues().minCoeff(),
              -1e-10 * S_fine.norm());
    return {S_fine, t.S};
}

TEST(MraCellTensors, UniformStressLoadsIntegrateStressTimesStrain) {
    // f(σ_a) · u = ∫ σ_a : ε(u) = |Ω| ε_a for every linear field u = A x + b.
    for (const int dim : {2, 3}) {
        const mesh::Mesh m =
            dim == 2 ? mesh::make_grid(mesh::ElementType::Quad4, Eigen::Vector2d(0, 0),
                                       Eigen::Vector2d(2, 1), Eigen::Vector2i(4, 3))
                     : mesh::make_grid(mesh::ElementType::Hex8, Eigen::Vector3d(0, 0, 0),
                                       Eigen::Vector3d(2, 1, 3), Eigen::Vector3i(2, 2, 3));
        const double volume = dim == 2 ? 2.0 : 6.0;
        const Matrix F = uniform_stress_loads(m);
        Matrix A(dim, dim);
        A.setZero();
        for (int i = 0; i < dim; ++i)
            for (int j = 0; j < dim; ++j) A(i, j) = 0.3 * (i + 1) - 0.7 * j + 0.1 * i * j;
        const Vector u = test::linear_field(m.rest_positions, A, Eigen::VectorXd::Ones(dim));
        // Exact quadrature of constant tractions on straight facets: round-off only.
        EXPECT_LT((F.transpose() * u - volume * mandel_strain(A)).norm(), 1e-12) << dim;
    }
}

TEST(MraCellTensors, HomogeneousCellGivesItsOwnModulus) {
    for (const int dim : {2, 3}) {
        SCOPED_TRACE(dim);
        const mesh::Mesh m = unit_grid(dim, dim == 2 ? 8 : 4);
        const material::Material mat = material::isotropic(dim, 1000.0, 0.3, 1.0);
        const auto [S_fine, S] = check_cell(m, material::uniform(m, mat));
        // The linear field is the exact fine solution of a uniform stress: S_fine = C^{-1}
        // (1e-10: round-off of the dense solve).
        const Matrix C = material::tensor(mat, dim);
        EXPECT_LT((S_fine - C.inverse()).norm(), 1e-10 * S_fine.norm());
        // Coarse: E(d) >= E(d)_fine (2D plane strain: E / (1 - nu^2)), and by the identity
        // the excess is e^2 / (1 - e^2) with e the relative energy error of the coarsest solve
        // of that uniform-stress load. e is not small: the adapted basis reproduces the rigid
        // motions (invariance correction) but not linear fields, and a single coarse cell keeps
        // 2^dim nodes. Measured excess: 2D 8x8 (4 levels) 10.5% along the axes to 22% along
        // the diagonals, 3D 4^3 (3 levels) about 20%; bounded here by 25%.
        const double E_fine = dim == 2 ? 1000.0 / (1 - 0.09) : 1000.0;
        const Matrix D = youngs_directions(dim);
        Vector E(D.rows());
        for (Index j = 0; j < D.rows(); ++j) {
            E[j] = material::directional_young(S.inverse(), D.row(j).transpose());
            EXPECT_GE(E[j], E_fine * (1 - 1e-10)) << D.row(j);
            EXPECT_LT(E[j], E_fine * 1.25) << D.row(j);
        }
        std::printf("homogeneous dim %d: E(d) / E_fine - 1 from %.4f to %.4f\n", dim,
                    E.minCoeff() / E_fine - 1, E.maxCoeff() / E_fine - 1);
        // The symmetries of the square / cube survive: the axes are equivalent, and so are the
        // diagonals (1e-8: round-off of the hierarchy's solves).
        if (dim == 2) {
            EXPECT_NEAR(E[0], E[18], 1e-8 * E[0]);  // x, y
            EXPECT_NEAR(E[9], E[27], 1e-8 * E[9]);  // 45°, 135°
        } else {
            for (const int j : {1, 2}) EXPECT_NEAR(E[j], E[0], 1e-8 * E[0]);
            for (int j = 4; j < 9; ++j) EXPECT_NEAR(E[j], E[3], 1e-8 * E[3]);
            for (int j = 10; j < 13; ++j) EXPECT_NEAR(E[j], E[9], 1e-8 * E[9]);
        }
    }
}

TEST(MraCellTensors, LaminateAcrossTheLayersIsReuss) {
    // Layers normal to x, one fine cell thick, E 100 and 1e4, nu = 0: a uniform stress
    // sigma_xx is then compatible (no lateral contraction), so the fine modulus across the
    // layers is exactly the series (Reuss) mean.
    const mesh::Mesh m = unit_grid(2, 8);
    material::ElementMaterials mats;
    mats.dim = 2;
    mats.table = {material::isotropic(2, 100.0, 0.0, 1.0), material::isotropic(2, 1e4, 0.0, 1.0)};
    mats.index.resize(m.num_elements());
    for (Index e = 0; e < m.num_elements(); ++e) mats.index[e] = (e % 8) % 2;
    const auto [S_fine, S] = check_cell(m, mats);
    const double reuss = 1.0 / (0.5 / 100.0 + 0.5 / 1e4);
    const Eigen::Vector2d x(1, 0);
    EXPECT_NEAR(material::directional_young(S_fine.inverse(), x), reuss, 1e-10 * reuss);
    const double E = material::directional_young(S.inverse(), x);
    EXPECT_GE(E, reuss * (1 - 1e-10));
    // As for the homogeneous cell, the excess is the coarsest energy error's e^2 / (1 - e^2);
    // measured 10.9%.
    std::printf("laminate across: E/Reuss - 1 = %.4f\n", E / reuss - 1);
    EXPECT_LT(E, reuss * 1.15);
}

TEST(MraCellTensors, LocalizedAndTruncatedHierarchiesGiveATensor) {
    // Localized solves and truncation perturb A^1's rigid kernel (measured: eigenvalues up to
    // 6e-4 of the next one, some negative); the tensor must still come out symmetric positive
    // definite. (No Galerkin bound here: truncating A^1 breaks A^1 = Φ K Φ^T.)
    const mesh::Mesh m = unit_grid(2, 8);
    const material::Material mat = material::isotropic(2, 1000.0, 0.3, 1.0);
    for (const Refinement r : {Refinement::Linear, Refinement::Dirac}) {
        Options o;
        o.refinement = r;
        o.radius = {2};
        o.truncation = 1e-5;
        const CellTensor t = coarsest_cell_tensor(m, material::uniform(m, mat), o);
        EXPECT_LT((t.C - t.C.transpose()).norm(), 1e-12 * t.C.norm());
        EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix>(t.C).eigenvalues().minCoeff(), 0.0);
    }
}

TEST(MraCellTensors, CellLocalizationWithAFullRadiusGivesTheGlobalTensor) {
    // The cell tensor's own hierarchy needs the element materials for cell-wise localization
    // (a scene with coarse.localization "cell" failed here). Regions wider than the grid make
    // the localized solves global, so the tensor must equal the global one up to round-off.
    const mesh::Mesh m = unit_grid(2, 8);
    material::ElementMaterials mats = material::uniform(m, material::isotropic(2, 1.0, 0.3, 1.0));
    mats.table.push_back(material::isotropic(2, 100.0, 0.3, 1.0));
    for (Index e = 0; e < m.num_elements(); ++e) mats.index[e] = (e % 8 + e / 8) % 2;
    Options o = exact_options();
    o.localization = Localization::Cell;
    o.radius = {16};
    const CellTensor local = coarsest_cell_tensor(m, mats, o);
    const CellTensor global = coarsest_cell_tensor(m, mats, exact_options());
    EXPECT_LT((local.C - global.C).norm(), 1e-9 * global.C.norm());
}

}  // namespace
}  // namespace coarsegrain::mra
