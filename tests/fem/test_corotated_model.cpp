// Corotated linear elasticity of a whole mesh (fem::CorotatedModel): at rest it is the linear
// model, a rigid rotation of any angle stores no energy and exerts no force, a rotated small
// strain gives the rotated linear force, its tangent is the force's derivative where the frames
// are stationary, and a DOF map acts as Tᵀ f(T w). Every element type, on regular grids (one
// K^e per material) and distorted meshes (one per element), with anisotropic materials.
#include <gtest/gtest.h>

#include <cmath>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/corotation.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "fem/fem_test_util.hpp"
#include "test_util.hpp"

using namespace coarsegrain;
using mesh::ElementType;

namespace {

struct CorotatedMesh {
    mesh::Mesh mesh;
    material::ElementMaterials mats;
};

/// A 3 x 2 (x 2) grid of `type` on [0, 1.5] x [0, 1] (x [0, 0.8]) with two anisotropic materials
/// in alternating cells, distorted (one K^e per element) or regular (one per material).
CorotatedMesh corotated_mesh(ElementType type, bool distorted) {
    const int dim = mesh::element_dim(type);
    const Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim);
    Eigen::VectorXd hi(dim);
    Eigen::VectorXi cells(dim);
    hi.head(2) << 1.5, 1.0;
    cells.head(2) << 3, 2;
    if (dim == 3) {
        hi[2] = 0.8;
        cells[2] = 2;
    }
    CorotatedMesh c{mesh::make_grid(type, lo, hi, cells), {}};
    if (distorted) test::distort_interior(c.mesh, 0.2);
    const int n = mandel_size(dim);
    c.mats.dim = dim;
    c.mats.table = {material::anisotropic(dim, test::random_spd_tensor(n, 3), 1.0),
                    material::anisotropic(dim, 20.0 * test::random_spd_tensor(n, 4), 2.0)};
    c.mats.index.resize(c.mesh.num_elements());
    for (Index e = 0; e < c.mesh.num_elements(); ++e) c.mats.index[e] = e % 2;
    return c;
}

/// A rotation by `angle` about (1, 2, 3) (3D) or in the plane (2D).
Matrix mesh_rotation(int dim, double angle) {
    if (dim == 2)
        return (Matrix(2, 2) << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle))
            .finished();
    return Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

/// The displacement that moves every node X to Q X + t + ε U(X), U a fixed smooth field.
Vector rotated_field(const mesh::Mesh& m, const Matrix& Q, double eps) {
    const int dim = m.dim();
    Vector u(m.num_dofs());
    for (Index v = 0; v < m.num_nodes(); ++v) {
        const Eigen::VectorXd X = m.rest_positions.row(v).transpose();
        Eigen::VectorXd U(dim);
        for (int d = 0; d < dim; ++d) U[d] = std::sin(1.3 * X[d] + 0.7 * d) + X.sum() * X[0];
        u.segment(dim * v, dim) = Q * (X + eps * U) + Eigen::VectorXd::Constant(dim, 0.3) - X;
    }
    return u;
}

/// v with every node block multiplied by Q.
Vector blocks_times(const Matrix& Q, const Vector& v) {
    Vector out(v.size());
    const Index dim = Q.rows();
    for (Index a = 0; a < v.size() / dim; ++a)
        out.segment(a * dim, dim) = Q * v.segment(a * dim, dim);
    return out;
}

struct ModelCase {
    ElementType type;
    bool distorted;
    fem::CorotationFrame frame;
};

class CorotatedModelTest : public ::testing::TestWithParam<ModelCase> {};

TEST_P(CorotatedModelTest, AtRestItIsTheLinearModel) {
    const auto [type, distorted, frame] = GetParam();
    const CorotatedMesh c = corotated_mesh(type, distorted);
    const fem::CorotatedModel model(c.mesh, c.mats, fem::Formulation::Standard, frame);
    const fem::CorotatedModel::State s = model.evaluate(Vector::Zero(c.mesh.num_dofs()));
    const SparseMatrix K = fem::stiffness_matrix(c.mesh, c.mats);
    // The frames are the identity up to the SVD's round-off (~1e-16), and so is û / h.
    const double scale = Matrix(K).norm();
    EXPECT_LE(s.energy, 1e-28 * scale);
    EXPECT_LE(s.force.norm(), 1e-13 * scale);
    EXPECT_LE((Matrix(model.tangent(s)) - Matrix(K)).norm(), 1e-13 * scale);
    EXPECT_LE((Matrix(model.jacobian(s)) - Matrix(K)).norm(), 1e-13 * scale);
}

TEST_P(CorotatedModelTest, RigidRotationsOfAnyAngleExertNoForce) {
    const auto [type, distorted, frame] = GetParam();
    const CorotatedMesh c = corotated_mesh(type, distorted);
    const fem::CorotatedModel model(c.mesh, c.mats, fem::Formulation::Standard, frame);
    const SparseMatrix K = fem::stiffness_matrix(c.mesh, c.mats);
    for (const double degrees : {30.0, 90.0, 179.0, 180.0}) {
        const Vector u =
            rotated_field(c.mesh, mesh_rotation(c.mesh.dim(), degrees * M_PI / 180), 0);
        const fem::CorotatedModel::State s = model.evaluate(u);
        // Relative to the force the linear model exerts for the same displacement.
        const double linear = (K * u).norm();
        EXPECT_LE(s.force.norm(), 1e-10 * linear) << degrees << " degrees";
        EXPECT_LE(s.energy, 1e-20 * u.dot(K * u)) << degrees << " degrees";
    }
}

TEST_P(CorotatedModelTest, RotatedSmallStrainGivesTheRotatedLinearForce) {
    // x = Q (X + ε U) + t: the force is Q K (ε U) blockwise up to O(ε²) (frames are Q + O(ε)).
    const auto [type, distorted, frame] = GetParam();
    const CorotatedMesh c = corotated_mesh(type, distorted);
    const int dim = c.mesh.dim();
    const fem::CorotatedModel model(c.mesh, c.mats, fem::Formulation::Standard, frame);
    const SparseMatrix K = fem::stiffness_matrix(c.mesh, c.mats);
    const Matrix Q = mesh_rotation(dim, 2.0);
    std::vector<double> eps = {1e-3, 1e-4}, error;
    for (const double e : eps) {
        const Vector strain = (rotated_field(c.mesh, Matrix::Identity(dim, dim), e) -
                               rotated_field(c.mesh, Matrix::Identity(dim, dim), 0));
        const Vector expected = blocks_times(Q, K * strain);
        const Vector force = model.evaluate(rotated_field(c.mesh, Q, e)).force;
        error.push_back((force - expected).norm() / expected.norm());
    }
    EXPECT_LE(error[0], 0.05);
    // Relative error O(ε): one decade of ε, one decade of error (first order, ±20%).
    EXPECT_NEAR(std::log10(error[0] / error[1]), 1.0, 0.2);
}

TEST_P(CorotatedModelTest, TangentIsTheForceDerivativeAtARotatedRestState) {
    // At a rigidly rotated rest state û = 0 and the frames' derivative only rotates the rest
    // shape, which K^e annihilates: the tangent R K Rᵀ is the exact derivative there.
    const auto [type, distorted, frame] = GetParam();
    const CorotatedMesh c = corotated_mesh(type, distorted);
    const fem::CorotatedModel model(c.mesh, c.mats, fem::Formulation::Standard, frame);
    const Vector u = rotated_field(c.mesh, mesh_rotation(c.mesh.dim(), 1.2), 0);
    const Matrix T = Matrix(model.tangent(model.evaluate(u)));
    const double h = 1e-6;
    for (const Index j : {Index(0), c.mesh.num_dofs() / 2 + 1, c.mesh.num_dofs() - 1}) {
        const Vector ej = Vector::Unit(c.mesh.num_dofs(), j);
        const Vector fd =
            (model.evaluate(u + h * ej).force - model.evaluate(u - h * ej).force) / (2 * h);
        // Central differences: O(h²) ≈ 1e-12 of the column; round-off ~1e-16/h = 1e-10.
        EXPECT_LE((fd - T.col(j)).norm(), 1e-8 * T.col(j).norm()) << "DOF " << j;
    }
}

TEST_P(CorotatedModelTest, JacobianIsTheForceDerivativeAtLargeDeformations) {
    // A rotation by 2 rad plus a strain of ~10% (ε = 0.1 of a field of slope ~2): the frames'
    // derivative matters; without it the tangent misses the force's derivative by far more.
    const auto [type, distorted, frame] = GetParam();
    const CorotatedMesh c = corotated_mesh(type, distorted);
    const fem::CorotatedModel model(c.mesh, c.mats, fem::Formulation::Standard, frame);
    const Vector u = rotated_field(c.mesh, mesh_rotation(c.mesh.dim(), 2.0), 0.05);
    const fem::CorotatedModel::State s = model.evaluate(u);
    const Matrix J = Matrix(model.jacobian(s)), T = Matrix(model.tangent(s));
    const double h = 1e-6;
    double error = 0, fixed_frame_error = 0, norm = 0;
    for (Index j = 0; j < c.mesh.num_dofs(); ++j) {
        const Vector ej = Vector::Unit(c.mesh.num_dofs(), j);
        const Vector fd =
            (model.evaluate(u + h * ej).force - model.evaluate(u - h * ej).force) / (2 * h);
        error = std::max(error, (fd - J.col(j)).norm());
        fixed_frame_error = std::max(fixed_frame_error, (fd - T.col(j)).norm());
        norm = std::max(norm, fd.norm());
    }
    // Central differences: truncation O(h²) ~1e-12 and round-off ~1e-16 |f| / h ~1e-10 of the
    // column; 1e-7 leaves room for the conditioning of the frames' SVD.
    EXPECT_LE(error, 1e-7 * norm);
    EXPECT_GT(fixed_frame_error, 1e-3 * norm);
}

TEST_P(CorotatedModelTest, DofMapGivesTheMappedForceAndTangent) {
    const auto [type, distorted, frame] = GetParam();
    const CorotatedMesh c = corotated_mesh(type, distorted);
    const Index n = c.mesh.num_dofs();
    // T: keep every DOF but tie DOF 0 to DOF 1 (u_0 = u_1 = w_0), a carried condition's shape.
    std::vector<Eigen::Triplet<double>> t = {{0, 0, 1.0}, {1, 0, 1.0}};
    for (Index i = 2; i < n; ++i) t.emplace_back(i, i - 1, 1.0);
    SparseMatrix T(n, n - 1);
    T.setFromTriplets(t.begin(), t.end());
    const fem::CorotatedModel full(c.mesh, c.mats, fem::Formulation::Standard, frame);
    const fem::CorotatedModel mapped(c.mesh, c.mats, fem::Formulation::Standard, frame, T);
    ASSERT_EQ(mapped.num_dofs(), n - 1);
    const Vector w = 0.3 * Vector::LinSpaced(n - 1, -1.0, 1.0);
    const Vector u = T * w;
    const fem::CorotatedModel::State s_full = full.evaluate(u), s_mapped = mapped.evaluate(w);
    EXPECT_DOUBLE_EQ(s_mapped.energy, s_full.energy);
    EXPECT_LE((s_mapped.force - T.transpose() * s_full.force).norm(), 1e-14 * s_full.force.norm());
    const Matrix expected = Matrix(T.transpose()) * Matrix(full.tangent(s_full)) * Matrix(T);
    EXPECT_LE((Matrix(mapped.tangent(s_mapped)) - expected).norm(), 1e-13 * expected.norm());
    const Matrix expected_j = Matrix(T.transpose()) * Matrix(full.jacobian(s_full)) * Matrix(T);
    EXPECT_LE((Matrix(mapped.jacobian(s_mapped)) - expected_j).norm(), 1e-13 * expected_j.norm());
}

std::vector<ModelCase> model_cases() {
    std::vector<ModelCase> cases;
    for (const ElementType type :
         {ElementType::Tri3, ElementType::Quad4, ElementType::Tet4, ElementType::Hex8})
        for (const bool distorted : {false, true})
            for (const fem::CorotationFrame frame :
                 {fem::CorotationFrame::DeVeubeke, fem::CorotationFrame::Polar})
                cases.push_back({type, distorted, frame});
    return cases;
}

INSTANTIATE_TEST_SUITE_P(Meshes, CorotatedModelTest, ::testing::ValuesIn(model_cases()),
                         [](const ::testing::TestParamInfo<ModelCase>& p) {
                             return mesh::element_name(p.param.type) +
                                    (p.param.distorted ? "_distorted_" : "_grid_") +
                                    fem::corotation_frame_name(p.param.frame);
                         });

TEST(CorotatedModel, RejectsMismatchedInput) {
    const CorotatedMesh c = corotated_mesh(ElementType::Tri3, false);
    const fem::CorotatedModel model(c.mesh, c.mats, fem::Formulation::Standard,
                                    fem::CorotationFrame::DeVeubeke);
    test::expect_error([&] { model.evaluate(Vector::Zero(3)); }, "displacement of size 3");
    Vector nan = Vector::Zero(c.mesh.num_dofs());
    nan[4] = std::nan("");
    test::expect_error([&] { model.evaluate(nan); }, "non-finite");
    test::expect_error(
        [&] {
            fem::CorotatedModel(c.mesh, c.mats, fem::Formulation::Standard,
                                fem::CorotationFrame::DeVeubeke, SparseMatrix(5, 2));
        },
        "DOF map has 5 rows");
    test::expect_error(
        [&] {
            fem::CorotatedModel(c.mesh, c.mats, fem::Formulation::Incompatible,
                                fem::CorotationFrame::DeVeubeke);
        },
        "incompatible");
}

}  // namespace
