// The effective tensors of Kharevych et al. 2009 (Eq. 5, 8, App. A), the coarse mass, and the
// coarse model a scene gets from build_coarse_model.
#include <gtest/gtest.h>

#include <cmath>
#include <variant>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/homogenize/homogenize.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "fem/fem_test_util.hpp"
#include "homogenize/homogenize_test_util.hpp"
#include "mesh/drop_elements.hpp"
#include "test_util.hpp"

namespace coarsegrain {
namespace {

/// Total mass of a consistent or lumped mass matrix M (its entries' sum over one component).
double total_mass(const SparseMatrix& M, int dim) { return M.sum() / dim; }

using nlohmann::json;
using test::box;
using test::grid;
using test::iso;

/// Mandel matrix (rows of numbers) as scene JSON.
json matrix_json(const Matrix& C) {
    json rows = json::array();
    for (Index i = 0; i < C.rows(); ++i) {
        json row = json::array();
        for (Index j = 0; j < C.cols(); ++j) row.push_back(C(i, j));
        rows.push_back(row);
    }
    return rows;
}

/// Eq. 5 on every coarse element: sum over overlaps |T_p ∩ 𝕋_q| G_p^T C_p G_p equals
/// |𝕋_q| 𝔾_q^T ℂ_q 𝔾_q, assembled here from the coarsening's pieces. Returns the worst relative
/// difference.
double eq5_defect(const homogenize::Coarsening& c) {
    const int dim = c.coarse.dim(), n = mandel_size(dim);
    std::vector<Matrix> fine_energy(c.coarse.num_elements(), Matrix::Zero(n, n));
    std::vector<char> fell_back(c.coarse.num_elements(), 0);
    for (Index q : c.fallback) fell_back[q] = 1;
    for (const mesh::Overlap& o : c.overlaps) {
        const Mandel6& Gp = fell_back[o.coarse] ? c.G_fine_neumann[o.fine] : c.G_fine[o.fine];
        const Matrix G = Gp.topLeftCorner(n, n);
        fine_energy[o.coarse] +=
            o.measure * G.transpose() * material::tensor(c.fine_materials.of(o.fine), dim) * G;
    }
    double worst = 0;
    for (Index q = 0; q < c.coarse.num_elements(); ++q) {
        const Matrix Gq = c.G_coarse[q].topLeftCorner(n, n);
        const Matrix coarse_energy =
            mesh::element_measure(c.coarse, q) * Gq.transpose() * c.C[q].topLeftCorner(n, n) * Gq;
        worst = std::max(worst, (coarse_energy - fine_energy[q]).norm() / fine_energy[q].norm());
    }
    return worst;
}

/// Smallest eigenvalue over largest, and the worst relative asymmetry, over all coarse tensors.
std::pair<double, double> spd_figures(const homogenize::Coarsening& c) {
    const int n = mandel_size(c.coarse.dim());
    double min_ratio = std::numeric_limits<double>::infinity(), asym = 0;
    for (const Mandel6& C6 : c.C) {
        const Matrix C = C6.topLeftCorner(n, n);
        asym = std::max(asym, (C - C.transpose()).norm() / C.norm());
        const Eigen::SelfAdjointEigenSolver<Matrix> eig(C);
        min_ratio = std::min(min_ratio, eig.eigenvalues()[0] / eig.eigenvalues()[n - 1]);
    }
    return {min_ratio, asym};
}

/// A heterogeneous scene (spheres of a stiff material in a soft one, contrast 100) whose coarse
/// mesh is larger than the fine one: coarse nodes outside the object take extrapolated fields.
json spheres_scene(int dim) {
    const std::vector<double> lo(dim, 0.0), hi(dim, 1.0), clo(dim, -0.1), chi(dim, 1.1);
    json centres = dim == 3 ? json{{0.3, 0.3, 0.3}, {0.7, 0.6, 0.4}, {0.4, 0.7, 0.75}}
                            : json{{0.3, 0.3}, {0.7, 0.6}, {0.4, 0.75}};
    return {
        {"mesh", grid(lo, hi, std::vector<int>(dim, dim == 3 ? 6 : 12), dim == 3 ? "tet" : "tri")},
        {"material_field",
         {{"spheres", {{"centres", centres}, {"radius", 0.2}, {"inside", 2}, {"outside", 1}}}}},
        {"materials", {{"1", iso(1.0, 0.3)}, {"2", iso(100.0, 0.35, 3.0)}}},
        {"coarse", {{"mesh", grid(clo, chi, std::vector<int>(dim, 2), dim == 3 ? "tet" : "tri")}}}};
}

class EffectiveTensorDim : public ::testing::TestWithParam<int> {};

// Eq. 5 holds to round-off on every coarse element for every pair of harmonic displacements
// (NOTES.md: it is what Eq. 8 is built to satisfy); the tensors are symmetric positive definite.
TEST_P(EffectiveTensorDim, Eq5HoldsAndTensorsAreSymmetricPositiveDefinite) {
    const int dim = GetParam();
    const test::Setup s = test::setup(spheres_scene(dim));
    const homogenize::Coarsening c = homogenize::coarsening(s.scene, s.fine, "effective-tensor");
    EXPECT_GT(c.report.coarse_nodes_outside, 0);  // extrapolation is exercised
    // 1e-10: two 6x6 products and an inverse of a matrix with condition number < 1e3.
    EXPECT_LT(eq5_defect(c), 1e-10);
    const auto [min_ratio, asym] = spd_figures(c);
    EXPECT_GT(min_ratio, 0.0);
    EXPECT_LT(asym, 1e-14);  // symmetrized by construction
}

INSTANTIATE_TEST_SUITE_P(EffectiveTensor, EffectiveTensorDim, ::testing::Values(2, 3));

// A homogeneous (anisotropic) object coarsens to its own tensor on every coarse element, for a
// distorted coarse mesh that is not nested in the fine one: H is linear, so 𝔾_q = G_p = C^{-1}
// and Eq. 8 gives C back (NOTES.md).
TEST_P(EffectiveTensorDim, HomogeneousObjectCoarsensToItsOwnTensor) {
    const int dim = GetParam(), n = mandel_size(dim);
    const Matrix C = test::random_spd_tensor(n, 11, 3.0) * 50.0;
    const std::vector<double> lo(dim, 0.0);
    std::vector<double> hi(dim, 1.0);
    hi[0] = 2.0;
    test::Setup s = test::setup(
        {{"mesh", grid(lo, hi, dim == 3 ? std::vector<int>{8, 4, 4} : std::vector<int>{16, 8},
                       dim == 3 ? "tet" : "tri")},
         {"materials", {{"0", {{"C_mandel", matrix_json(C)}, {"density", 2.0}}}}},
         {"coarse",
          {{"mesh", grid(lo, hi, dim == 3 ? std::vector<int>{3, 2, 2} : std::vector<int>{5, 3},
                         dim == 3 ? "tet" : "tri")}}}});
    test::distort_interior(*s.scene.coarse.mesh, 0.2, 3);
    const homogenize::Coarsening c = homogenize::coarsening(s.scene, s.fine, "effective-tensor");
    double worst = 0;
    for (const Mandel6& Cq : c.C) worst = std::max(worst, (Cq.topLeftCorner(n, n) - C).norm());
    // Round-off of the harmonic solves (condition ~1e4 here) carried through Eq. 8's 6x6
    // products and inverse: measured ~1e-13, bound 1e-8 for other BLAS and orderings.
    EXPECT_LT(worst, 1e-8 * C.norm());
}

// ... and its coarse solution is then identical to the naive baseline's (the same tensor on
// every coarse element gives the same coarse stiffness).
TEST_P(EffectiveTensorDim, HomogeneousSolutionEqualsTheNaiveOne) {
    const int dim = GetParam();
    const std::vector<double> lo(dim, 0.0);
    std::vector<double> hi(dim, 1.0), clamp_hi(dim, 2.0), clamp_lo(dim, -1.0), g(dim, 0.0);
    hi[0] = 3.0;
    clamp_lo[0] = -1e-9;
    clamp_hi[0] = 1e-9;
    g[dim - 1] = -9.81;
    const test::Setup s = test::setup(
        {{"mesh", grid(lo, hi, dim == 3 ? std::vector<int>{9, 3, 3} : std::vector<int>{18, 6},
                       dim == 3 ? "hex" : "quad")},
         {"materials", {{"0", iso(1e3, 0.3, 1.5)}}},
         {"dirichlet", json::array({box(clamp_lo, clamp_hi)})},
         {"loads", {{"gravity", g}}},
         {"coarse",
          {{"mesh", grid(lo, hi, dim == 3 ? std::vector<int>{4, 2, 2} : std::vector<int>{5, 2},
                         dim == 3 ? "tet" : "tri")}}}});
    const Vector u_et =
        test::solve_coarse(homogenize::build_coarse_model(s.scene, s.fine, "effective-tensor"));
    const Vector u_naive =
        test::solve_coarse(homogenize::build_coarse_model(s.scene, s.fine, "naive"));
    // 1e-8: tensors equal to ~1e-13, a direct solve with condition number ~1e4.
    EXPECT_LT((u_et - u_naive).norm(), 1e-8 * u_naive.norm());
}

// App. A in 3D: a bar of two materials in series (nu = 0, contrast 100) coarsened to one coarse
// cell along its axis (3 x 3 across) has the series stiffness 1/k = 1/k1 + 1/k2 within 5% (the
// fine model has it exactly: uniaxial stress); averaging the Lamé parameters is 25x too stiff.
// Measured: 0.963 of the series stiffness. With a single coarse cell (6 Kuhn tets) it is 0.83:
// each tet holds the two materials in a different proportion (7/8, 1/2 or 1/8 of it stiff), so
// its Eq. 8 tensor differs, and the coarse solve does not average them like springs in parallel
// (their volume average is the series modulus to 0.5%).
TEST(EffectiveTensor, SpringsInSeriesGiveTheSeriesStiffness) {
    const double E1 = 100.0, E2 = 1.0;
    const json j = {
        {"mesh", grid({0, 0, 0}, {2, 1, 1}, {16, 6, 6}, "hex")},
        {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 1.0}, {"ids", {1, 2}}}}}},
        {"materials", {{"1", iso(E1, 0.0)}, {"2", iso(E2, 0.0)}}},
        {"dirichlet", json::array({box({-1e-9, -1, -1}, {1e-9, 2, 2})})},
        {"loads",
         {{"traction", json::array({box({2 - 1e-9, -1, -1}, {2 + 1e-9, 2, 2}, {1, 0, 0})})}}},
        {"coarse", {{"mesh", grid({0, 0, 0}, {2, 1, 1}, {1, 3, 3}, "tet")}}}};
    const test::Setup s = test::setup(j);
    const double k_series = 1.0 / (1.0 / E1 + 1.0 / E2);  // k_i = E_i A / L_i with A = L_i = 1
    // Axial stiffness: total force 1 over the mean axial displacement of the loaded end.
    auto stiffness = [](const mesh::Mesh& m, const Vector& u) {
        double tip = 0;
        int count = 0;
        for (Index v = 0; v < m.num_nodes(); ++v)
            if (m.rest_positions(v, 0) > 2 - 1e-9) {
                tip += u[3 * v];
                ++count;
            }
        return count / tip;
    };
    const double k_fine = stiffness(s.fine.mesh, scene::solve_static(s.fine, {}).u);
    EXPECT_NEAR(k_fine, k_series, 1e-9 * k_series);  // uniaxial stress: exact up to round-off
    auto coarse = [&](const std::string& method) {
        return stiffness(*s.scene.coarse.mesh, test::solve_coarse(homogenize::build_coarse_model(
                                                   s.scene, s.fine, method)));
    };
    const double k_et = coarse("effective-tensor"), k_naive = coarse("naive");
    std::printf("series stiffness %.6g, effective-tensor %.6g, naive %.6g\n", k_series, k_et,
                k_naive);
    EXPECT_NEAR(k_et / k_series, 1.0, 0.05);
    EXPECT_GT(k_naive / k_series, 10.0);
}

// Mass: with a coarse mesh that covers the fine one, every coarse mass (coarse.mass) has the
// fine total mass; the lumped and Galerkin ones also its first moments, since the barycentric
// map P is a partition of unity that reproduces affine fields (Σ_a P_ia x_a = x_i), to
// round-off (1e-12 relative).
TEST_P(EffectiveTensorDim, CoarseMassHasTheFineMassAndMoments) {
    const int dim = GetParam();
    for (const char* type : {"lumped", "consistent", "galerkin"}) {
        json j = spheres_scene(dim);
        j["coarse"]["mass"] = type;
        const test::Setup s = test::setup(j);
        const coarsen::CoarseModel m =
            homogenize::build_coarse_model(s.scene, s.fine, "effective-tensor");
        const SparseMatrix M =
            fem::mass_matrix(s.fine.mesh, s.fine.materials, fem::MassType::Consistent);
        const SparseMatrix Mc = m.mass(M);
        ASSERT_EQ(Mc.rows(), m.K.rows());
        const mesh::Mesh& coarse = *s.scene.coarse.mesh;
        for (int d = 0; d < dim; ++d) {
            const Vector e_f = sim::uniform_field(M.rows(), Eigen::VectorXd::Unit(dim, d));
            const Vector e_c = sim::uniform_field(Mc.rows(), Eigen::VectorXd::Unit(dim, d));
            const double fine_mass = e_f.dot(M * e_f), coarse_mass = e_c.dot(Mc * e_c);
            EXPECT_NEAR(coarse_mass, fine_mass, 1e-12 * fine_mass) << type;
            if (std::string(type) == "consistent") continue;  // element-mean densities
            for (int a = 0; a < dim; ++a) {  // first moment ∫ρ x_a along component d
                Vector x_f = Vector::Zero(M.rows()), x_c = Vector::Zero(Mc.rows());
                for (Index v = 0; v < s.fine.mesh.num_nodes(); ++v)
                    x_f[dim * v + d] = s.fine.mesh.rest_positions(v, a);
                for (Index v = 0; v < coarse.num_nodes(); ++v)
                    x_c[dim * v + d] = coarse.rest_positions(v, a);
                const double fine_moment = e_f.dot(M * x_f), coarse_moment = e_c.dot(Mc * x_c);
                EXPECT_NEAR(coarse_moment, fine_moment, 1e-12 * fine_mass) << type;
            }
        }
        EXPECT_NEAR(std::get<homogenize::Report>(m.report).coarse_mass, total_mass(M, dim),
                    1e-12 * total_mass(M, dim));
    }
}

// A cavity weighs nothing: a cube with a cubic cavity of 1/27 of its volume, coarsened to the 6
// Kuhn tets of one cell. The cavity is symmetric under axis permutations, so each tet holds 1/6
// of it and weighs rho (1 - 1/27) / 6.
TEST(EffectiveTensor, CavityWeighsNothing) {
    const double rho = 2.5;
    scene::Scene sc =
        scene::parse_scene({{"mesh", grid({0, 0, 0}, {1, 1, 1}, {6, 6, 6}, "tet")},
                            {"materials", {{"0", iso(10.0, 0.3, rho)}}},
                            {"coarse", {{"mesh", grid({0, 0, 0}, {1, 1, 1}, {1, 1, 1}, "tet")}}}},
                           "cavity.json", "");
    sc.mesh = test::drop_elements(sc.mesh, [](const Eigen::VectorXd& c) {
        return (c.array() > 1.0 / 3).all() && (c.array() < 2.0 / 3).all();
    });
    const scene::FineModel fine = scene::build_fine_model(sc);
    const homogenize::Coarsening c = homogenize::coarsening(sc, fine, "effective-tensor");
    ASSERT_EQ(c.element_mass.size(), 6);
    for (Index q = 0; q < 6; ++q)
        EXPECT_NEAR(c.element_mass[q], rho * (1 - 1.0 / 27) / 6, 1e-13);  // exact overlaps
    // The lumped coarse mass has the fine total and the fine first moment, whose centre is the
    // cube's by symmetry.
    const coarsen::CoarseModel m = homogenize::coarse_model(sc, fine, c);
    const Vector masses =
        m.mass(fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Lumped)).diagonal();
    const mesh::Mesh& coarse = *sc.coarse.mesh;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (Index v = 0; v < coarse.num_nodes(); ++v)
        moment += masses[3 * v] * coarse.rest_positions.row(v).transpose();
    EXPECT_NEAR(masses.sum() / 3, rho * (1 - 1.0 / 27), 1e-13);
    EXPECT_LT((moment - Eigen::Vector3d::Constant(0.5 * rho * (1 - 1.0 / 27))).norm(), 1e-13);
}

// The coarse model's file (coarse_model.vtu) carries everything a simulation needs: read back as
// a scene mesh it gives the same stiffness, load and solution without the fine mesh. (The coarse
// model carries the fine load, P^T f; the file's scene puts gravity on the coarse mass again. The
// two agree where the density is constant in each coarse element, here everywhere.)
TEST(EffectiveTensor, CoarseModelFileSimulatesWithoutTheFineMesh) {
    const json clamp = json::array({box({-1e-9, -1, -1}, {1e-9, 2, 2})});
    json j = spheres_scene(3);
    j["materials"]["2"]["density"] = 1.0;
    j["coarse"]["mesh"] = grid({0, 0, 0}, {1, 1, 1}, {2, 2, 2}, "tet");
    j["dirichlet"] = clamp;
    j["loads"] = {{"gravity", {0, -1, -9.81}}};
    const test::Setup s = test::setup(j);
    const coarsen::CoarseModel m =
        homogenize::build_coarse_model(s.scene, s.fine, "effective-tensor");
    ASSERT_EQ(m.outputs.front().file, "coarse_model.vtu");
    // harmonic.vtu: the fine mesh with the six harmonic displacements as point vectors.
    ASSERT_EQ(m.outputs.size(), 2u);
    EXPECT_EQ(m.outputs[1].file, "harmonic.vtu");
    EXPECT_EQ(m.outputs[1].mesh.num_nodes(), s.fine.mesh.num_nodes());
    std::vector<std::string> names;
    for (const io::Field& f : m.outputs[1].fields.point_data) names.push_back(f.name);
    EXPECT_EQ(names, (std::vector<std::string>{"h_xx", "h_yy", "h_zz", "h_yz", "h_xz", "h_xy"}));
    // coarse_model.vtu: the directional Young's moduli are those of the stored tensors.
    const io::VtuFields& fields = m.outputs[0].fields;
    auto cell = [&](const std::string& name) -> const Matrix& {
        for (const io::Field& f : fields.cell_data)
            if (f.name == name) return f.values;
        ADD_FAILURE() << "no cell field " << name;
        return fields.cell_data.front().values;
    };
    for (Index q = 0; q < m.elements; ++q) {
        Matrix C_voigt(6, 6);
        for (int I = 0; I < 6; ++I)
            for (int J = I; J < 6; ++J)
                C_voigt(I, J) = C_voigt(J, I) =
                    cell(fmt::format("C_voigt_{}{}", I + 1, J + 1))(q, 0);
        const Matrix C = material::voigt_to_mandel(C_voigt);
        EXPECT_NEAR(cell("E_z")(q, 0), material::directional_young(C, Eigen::Vector3d(0, 0, 1)),
                    1e-12 * cell("E_z")(q, 0));
    }
    const std::string dir = test::temp_dir("coarse_model_file");
    io::write_vtu(dir + "/coarse_model.vtu", m.outputs.front().mesh, m.outputs.front().fields);
    const test::Setup back = test::setup({{"mesh", {{"file", dir + "/coarse_model.vtu"}}},
                                          {"dirichlet", clamp},
                                          {"loads", {{"gravity", {0, -1, -9.81}}}}});
    ASSERT_EQ(back.fine.mesh.num_elements(), m.elements);
    // The tensors pass through Voigt form and back: round-off.
    EXPECT_LT((back.fine.K - m.K).norm(), 1e-12 * m.K.norm());
    EXPECT_LT((back.fine.f - m.f).norm(), 1e-12 * m.f.norm());
    const Vector u_back = scene::solve_static(back.fine, {}).u;
    const Vector u = test::solve_coarse(m);
    EXPECT_LT((u_back - u).norm(), 1e-10 * u.norm());
    // Materials cannot be given twice.
    test::expect_error(
        [&] {
            scene::parse_scene({{"mesh", {{"file", dir + "/coarse_model.vtu"}}},
                                {"materials", {{"1", iso(1.0, 0.3)}}}},
                               "again.json", "");
        },
        "carries one elasticity tensor per element");
}

// In 2D the coarse model file carries the 6 Voigt entries of a 3x3 tensor, the density and the
// directional Young's moduli along x and y (no z), and harmonic.vtu the 3 harmonic fields.
TEST(EffectiveTensor, CoarseModelFieldsIn2D) {
    const test::Setup s = test::setup(spheres_scene(2));
    const coarsen::CoarseModel m =
        homogenize::build_coarse_model(s.scene, s.fine, "effective-tensor");
    ASSERT_EQ(m.outputs.size(), 2u);
    std::vector<std::string> cells, points;
    for (const io::Field& f : m.outputs[0].fields.cell_data) cells.push_back(f.name);
    for (const io::Field& f : m.outputs[1].fields.point_data) points.push_back(f.name);
    EXPECT_EQ(cells, (std::vector<std::string>{"C_voigt_11", "C_voigt_12", "C_voigt_13",
                                               "C_voigt_22", "C_voigt_23", "C_voigt_33", "density",
                                               "E_x", "E_y", "G_condition"}));
    EXPECT_EQ(points, (std::vector<std::string>{"h_xx", "h_yy", "h_xy"}));
}

// On a simplicial fine mesh the mixed boundary's harmonic solve factorizes the fine stiffness
// without the scene's Dirichlet DOFs, the very operator of the fine static solve: given that
// solve's factorization it is not factorized again. Given the factorization of 2 K_ff instead,
// the harmonic fields halve, which shows which one was used. A hex mesh is split into tets for
// the harmonic solve (another operator), so there the runtime keeps no factorization for it.
TEST(EffectiveTensor, MixedHarmonicSolveUsesTheFineFactorization) {
    const auto scene = [](const char* element) {
        return json{
            {"mesh", grid({0, 0, 0}, {4, 1, 1}, {8, 2, 2}, element)},
            {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.5}, {"ids", {1, 2}}}}}},
            {"materials", {{"1", iso(1e3, 0.3)}, {"2", iso(1.0, 0.45)}}},
            {"dirichlet", json::array({box({-1e-9, -1, -1}, {1e-9, 2, 2})})},
            {"loads", {{"gravity", {0, 0, -1}}}},
            {"coarse",
             {{"mesh", grid({0, 0, 0}, {4, 1, 1}, {2, 1, 1}, "tet")}, {"boundary", "mixed"}}}};
    };
    const test::Setup s = test::setup(scene("tet"));
    EXPECT_TRUE(coarsen::uses_fine_factorization(s.scene, s.fine, {"effective-tensor"}));
    const test::Setup hex = test::setup(scene("hex"));
    EXPECT_FALSE(coarsen::uses_fine_factorization(hex.scene, hex.fine, {"effective-tensor"}));

    const scene::StaticSolution u = scene::solve_static(s.fine, s.scene.solver, nullptr, true);
    const homogenize::Coarsening own = homogenize::coarsening(s.scene, s.fine, "effective-tensor");
    const homogenize::Coarsening shared =
        homogenize::coarsening(s.scene, s.fine, "effective-tensor", u.factorization.get());
    // Two factorizations of the same matrix (other orderings): round-off, 1e-10.
    EXPECT_LT((shared.h - own.h).norm(), 1e-10 * own.h.norm());
    solve::SpdSolver twice;
    twice.compute(SparseMatrix(2.0 * fem::reduce(s.fine.K, s.fine.f, s.fine.bc).K));
    const homogenize::Coarsening halved =
        homogenize::coarsening(s.scene, s.fine, "effective-tensor", &twice);
    EXPECT_LT((2.0 * halved.h - own.h).norm(), 1e-10 * own.h.norm());
}

// Mixed boundary (Sec. 3.8): the harmonic displacements vanish on the clamped nodes. The P1
// interpolant of fields that vanish at two or more nodes of a coarse element has no strain along
// their edge (or face), so exactly the coarse elements with >= 2 clamped nodes have a singular
// mollifier and fall back to the pure-Neumann one; Eq. 5 still holds with each element's own
// mollifiers, and every tensor is symmetric positive definite.
TEST(EffectiveTensor, MixedBoundaryFallsBackWhereTheClampPinsAnEdge) {
    const test::Setup s = test::setup(
        {{"mesh", grid({0, 0, 0}, {4, 1, 1}, {16, 4, 4}, "hex")},
         {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.5}, {"ids", {1, 2}}}}}},
         {"materials", {{"1", iso(1e3, 0.3)}, {"2", iso(1.0, 0.45)}}},
         {"dirichlet", json::array({box({-1e-9, -1, -1}, {1e-9, 2, 2})})},
         {"loads", {{"gravity", {0, 0, -1}}}},
         {"coarse",
          {{"mesh", grid({0, 0, 0}, {4, 1, 1}, {4, 2, 2}, "tet")},
           {"boundary", "mixed"},
           {"map", "harmonic"}}}});
    const homogenize::Coarsening c = homogenize::coarsening(s.scene, s.fine, "effective-tensor");
    std::vector<Index> pinned;
    for (Index q = 0; q < c.coarse.num_elements(); ++q) {
        int clamped = 0;
        for (Index a = 0; a < 4; ++a)
            clamped += c.coarse.rest_positions(c.coarse.elements(q, a), 0) < 1e-9;
        if (clamped >= 2) pinned.push_back(q);
    }
    EXPECT_EQ(c.fallback, pinned);
    ASSERT_TRUE(c.report.effective_tensor.has_value());
    EXPECT_EQ(c.report.effective_tensor->fallback_elements, pinned);
    EXPECT_LT(eq5_defect(c), 1e-10);
    EXPECT_GT(spd_figures(c).first, 0.0);
    // The harmonic coarse-to-fine map (built from the pure-Neumann fields, since elements fell
    // back) carries rigid motions exactly.
    const coarsen::CoarseModel m = homogenize::coarse_model(s.scene, s.fine, c);
    const Matrix rigid_fine = test::rigid_modes(s.fine.mesh.rest_positions);
    EXPECT_LT((m.to_fine * test::rigid_modes(c.coarse.rest_positions) - rigid_fine).norm(),
              1e-10 * rigid_fine.norm());
}

// The guard of Eq. 8: a coarse mollifier with a direction it does not strain is singular relative
// to the fine mollifiers' scale, and inverting an exactly singular one names the element.
TEST(EffectiveTensor, SingularCoarseMollifierIsDetected) {
    Mandel6 G = Mandel6::Zero();
    G.topLeftCorner(6, 6) = test::random_spd_tensor(6, 2).inverse();
    const double scale = G.norm();
    EXPECT_FALSE(homogenize::mollifier_singular(3, G, scale));
    Mandel6 flat = G;
    flat.col(4).setZero();  // no response to the xz load
    EXPECT_TRUE(homogenize::mollifier_singular(3, flat, scale));
    flat.col(4) = 1e-12 * G.col(4);  // round-off sized
    EXPECT_TRUE(homogenize::mollifier_singular(3, flat, scale));
    std::vector<Mandel6> A(2, Mandel6::Identity()), Gs = {G, Mandel6::Zero()};
    test::expect_error([&] { homogenize::effective_tensors(3, A, Gs); },
                       "coarse mollifier of coarse element 1 is singular");
}

// Bad input: each error names what is wrong.
TEST(EffectiveTensor, BadInputIsNamed) {
    const json fine_part = {{"mesh", grid({0, 0, 0}, {1, 1, 1}, {4, 4, 4}, "tet")},
                            {"materials", {{"0", iso(10.0, 0.3)}}}};
    auto run = [&](const json& coarse, const std::string& method = "effective-tensor") {
        json j = fine_part;
        j["coarse"] = coarse;
        const test::Setup s = test::setup(j);
        homogenize::build_coarse_model(s.scene, s.fine, method);
    };
    const json cover = grid({0, 0, 0}, {1, 1, 1}, {1, 1, 1}, "tet");
    test::expect_error(
        [&] {
            run({{"mesh", grid({0, 0, 0}, {0.5, 1, 1}, {1, 1, 1}, "tet")}});
        },
        "misses part of the object");
    test::expect_error(
        [&] {
            run({{"mesh", grid({100, 0, 0}, {101, 1, 1}, {1, 1, 1}, "tet")}});
        },
        "does not overlap the fine mesh at all");
    test::expect_error(
        [&] {
            run({{"mesh", grid({0, 0, 0}, {1000, 1000, 1000}, {1, 1, 1}, "tet")}});
        },
        "same units");
    test::expect_error(
        [&] {
            run({{"mesh", grid({0, 0, 0}, {2, 2, 2}, {2, 2, 2}, "tet")}});
        },
        "contains no fine material");
    test::expect_error([&] { run({{"mesh", cover}}, "average"); }, "unknown coarsening method");
    test::expect_error([&] { run({{"mesh", cover}, {"normals", "outer"}}); }, "coarse.normals");
    test::expect_error(
        [&] {
            run({{"mesh", cover}, {"boundary", "dirichlet"}});
        },
        "coarse.boundary");
    test::expect_error([&] { run({{"mesh", cover}, {"map", "linear"}}); }, "coarse.map");
    test::expect_error([&] { run({{"mesh", cover}, {"boundary", "mixed"}}); }, "needs fixed nodes");
    test::expect_error([&] { run({{"levels", 2}}); }, "needs a coarse mesh");
    // A degenerate coarse element (a flat tet).
    test::Setup s = test::setup(fine_part);
    mesh::Mesh flat;
    flat.type = mesh::ElementType::Tet4;
    flat.rest_positions.resize(4, 3);
    flat.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0;
    flat.elements.resize(1, 4);
    flat.elements << 0, 1, 2, 3;
    s.scene.coarse.mesh = flat;
    test::expect_error([&] { homogenize::build_coarse_model(s.scene, s.fine, "voigt"); },
                       "coarse.mesh: element 0 is degenerate");
    // A box that selects no coarse node is no error: the coarse conditions come from the fine
    // ones (the plane x = 0.25 lies inside every coarse tet of the single cube, whose 24 DOFs it
    // holds in combination).
    json j = fine_part;
    j["coarse"] = {{"mesh", cover}};
    j["dirichlet"] = json::array({box({0.25 - 1e-9, -1, -1}, {0.25 + 1e-9, 2, 2})});
    const test::Setup sd = test::setup(j);
    const coarsen::CoarseModel voigt = homogenize::build_coarse_model(sd.scene, sd.fine, "voigt");
    EXPECT_EQ(std::get<homogenize::Report>(voigt.report).constrained_dofs, 24);
}

}  // namespace
}  // namespace coarsegrain
