// CalculiX decks of element models (io::write_calculix_deck): the ANISO constants are the tensor
// components D_ijkl in CalculiX's order (checked against a rotated orthotropic tensor built
// component by component), and ccx, run on the exported deck of a coarse model, reproduces
// coarsegrain's own coarse solution.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/io/inp_export.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/dynamics.hpp"
#include "io/ccx_output.hpp"
#include "test_util.hpp"

using namespace coarsegrain;

namespace {

using Tensor4 = std::array<std::array<std::array<std::array<double, 3>, 3>, 3>, 3>;

/// An orthotropic tensor from its axis components (D_1111, D_2222, D_3333, D_1122, D_1133,
/// D_2233, D_2323, D_1313, D_1212), with all its minor and major symmetries.
Tensor4 orthotropic() {
    Tensor4 D{};
    const auto set = [&](int i, int j, int k, int l, double v) {
        for (const auto& [a, b] : {std::pair{i, j}, std::pair{j, i}})
            for (const auto& [c, d] : {std::pair{k, l}, std::pair{l, k}}) {
                D[a][b][c][d] = v;
                D[c][d][a][b] = v;
            }
    };
    set(0, 0, 0, 0, 200);
    set(1, 1, 1, 1, 90);
    set(2, 2, 2, 2, 40);
    set(0, 0, 1, 1, 30);
    set(0, 0, 2, 2, 12);
    set(1, 1, 2, 2, 9);
    set(1, 2, 1, 2, 7);
    set(0, 2, 0, 2, 11);
    set(0, 1, 0, 1, 25);
    return D;
}

TEST(CalculixAniso, ConstantsAreTheRotatedTensorsComponentsInCalculixOrder) {
    // D'_ijkl = Q_ia Q_jb Q_kc Q_ld D_abcd for a rotation Q about the axis (1, 2, 3) by 0.7 rad,
    // so that every one of the 21 constants is nonzero; its Mandel form is built here from the
    // components (shear rows and columns times √2), independently of the library's mappings.
    const Tensor4 D = orthotropic();
    const Eigen::Matrix3d Q =
        Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    Tensor4 R{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l)
                    for (int a = 0; a < 3; ++a)
                        for (int b = 0; b < 3; ++b)
                            for (int c = 0; c < 3; ++c)
                                for (int d = 0; d < 3; ++d)
                                    R[i][j][k][l] +=
                                        Q(i, a) * Q(j, b) * Q(k, c) * Q(l, d) * D[a][b][c][d];
    const std::array<std::pair<int, int>, 6> mandel = {
        {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}}};
    Matrix C(6, 6);
    for (int I = 0; I < 6; ++I)
        for (int J = 0; J < 6; ++J) {
            const double w = (I > 2 ? std::sqrt(2.0) : 1.0) * (J > 2 ? std::sqrt(2.0) : 1.0);
            C(I, J) = w * R[mandel[I].first][mandel[I].second][mandel[J].first][mandel[J].second];
        }
    // The order of the CalculiX 2.20 manual, "*ELASTIC": D1111, D1122, D2222, D1133, D2233,
    // D3333, D1112, D2212, D3312, D1212, D1113, D2213, D3313, D1213, D1313, D1123, D2223, D3323,
    // D1223, D1323, D2323 (indices from 1).
    const std::array<std::array<int, 4>, 21> names = {{
        {1, 1, 1, 1}, {1, 1, 2, 2}, {2, 2, 2, 2}, {1, 1, 3, 3}, {2, 2, 3, 3}, {3, 3, 3, 3},
        {1, 1, 1, 2}, {2, 2, 1, 2}, {3, 3, 1, 2}, {1, 2, 1, 2}, {1, 1, 1, 3}, {2, 2, 1, 3},
        {3, 3, 1, 3}, {1, 2, 1, 3}, {1, 3, 1, 3}, {1, 1, 2, 3}, {2, 2, 2, 3}, {3, 3, 2, 3},
        {1, 2, 2, 3}, {1, 3, 2, 3}, {2, 3, 2, 3},
    }};
    const std::array<double, 21> d = io::calculix_aniso(C);
    for (std::size_t k = 0; k < names.size(); ++k) {
        const auto [i, j, l, m] = names[k];
        const double expected = R[i - 1][j - 1][l - 1][m - 1];
        EXPECT_NEAR(d[k], expected, 1e-12 * 200) << "constant " << k;
        EXPECT_GT(std::abs(expected), 1e-3) << "constant " << k;  // the rotation mixed them all
    }
}

/// A bar of stiff and soft layers across its axis (contrast 100), clamped at x = 0 under
/// gravity and an oblique load, with a coarse mesh of `coarse_element`s (2D: plane `plane`).
nlohmann::json layered_bar(int dim, const std::string& plane) {
    nlohmann::json j = nlohmann::json::parse(R"({
      "material_field": { "layers": { "axis": "x", "thickness": 0.25, "ids": [1, 2] } },
      "materials": { "1": { "E": 1000, "nu": 0.3, "density": 1 },
                     "2": { "E": 10, "nu": 0.4, "density": 2 } } })");
    if (dim == 3) {
        j["dimension"] = 3;
        j["mesh"] = {
            {"grid",
             {{"min", {0, 0, 0}}, {"max", {2, 1, 1}}, {"cells", {8, 4, 4}}, {"element", "hex"}}}};
        j["coarse"] = {{"mesh",
                        {{"grid",
                          {{"min", {0, 0, 0}},
                           {"max", {2, 1, 1}},
                           {"cells", {4, 2, 2}},
                           {"element", "tet"}}}}}};
        j["dirichlet"] = {{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 2, 2}}}}}};
        j["loads"] = {{"gravity", {0.3, -0.5, -1}}};
    } else {
        j["dimension"] = 2;
        j["plane"] = plane;
        j["mesh"] = {
            {"grid", {{"min", {0, 0}}, {"max", {2, 1}}, {"cells", {16, 8}}, {"element", "quad"}}}};
        j["coarse"] = {
            {"mesh",
             {{"grid",
               {{"min", {0, 0}}, {"max", {2, 1}}, {"cells", {4, 2}}, {"element", "tri"}}}}}};
        j["dirichlet"] = {{{"box", {{"min", {-1e-9, -1}}, {"max", {1e-9, 2}}}}}};
        j["loads"] = {{"gravity", {0.3, -1}}};
    }
    return j;
}

struct DeckCase {
    std::string name;
    int dim;
    std::string plane;
    std::string method;
};

class CalculixDeckTest : public ::testing::TestWithParam<DeckCase> {};

TEST_P(CalculixDeckTest, CcxReproducesTheCoarseSolution) {
    // ccx solves the exported deck with its own elements and solver; it prints displacements with
    // 7 significant digits (a rounding of at most 5e-7 of each value), so the two solutions of
    // the same discrete problem agree to 1e-6 of the largest displacement.
    const DeckCase& c = GetParam();
    const scene::Scene sc = scene::parse_scene(layered_bar(c.dim, c.plane), "bar.json", ".");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const coarsen::CoarseModel model = coarsen::build_coarse_model(sc, fine, c.method);
    ASSERT_TRUE(model.element_model.has_value());
    const coarsen::ElementModel& e = *model.element_model;
    ASSERT_EQ(e.dof_map.size(), 0);  // coarse nodes on the clamp: the DOFs are nodal
    const Vector u = coarsen::solve_coarse(model, sc.solver).u;

    const std::string dir = test::temp_dir("calculix_deck_" + c.name);
    io::write_calculix_deck(dir + "/coarse.inp", e.mesh, e.materials, model.f, model.bc, sc.plane,
                            c.name);
    std::string output;
    ASSERT_EQ(test::run(fmt::format("cd {} && ccx -i coarse", dir), &output), 0) << output;
    const std::vector<Matrix> blocks = test::read_ccx_displacements(dir + "/coarse.dat");
    ASSERT_EQ(blocks.size(), 1u) << output;
    const Vector u_ccx = test::interleaved(blocks[0], c.dim);
    ASSERT_EQ(u_ccx.size(), u.size()) << output;
    ASSERT_TRUE(u_ccx.allFinite()) << "ccx printed no displacement for some node:\n" << output;
    const double rel = (u - u_ccx).cwiseAbs().maxCoeff() / u.cwiseAbs().maxCoeff();
    EXPECT_LT(rel, 1e-6);
    std::printf("  %s: max|u - u_ccx| / max|u| = %.2e (max|u| %.3g)\n", c.name.c_str(), rel,
                u.cwiseAbs().maxCoeff());
}

INSTANTIATE_TEST_SUITE_P(Models, CalculixDeckTest,
                         ::testing::Values(DeckCase{"effective_tensor_tets", 3, "",
                                                    "effective-tensor"},
                                           DeckCase{"naive_tets", 3, "", "naive"},
                                           DeckCase{"effective_tensor_triangles_plane_strain", 2,
                                                    "strain", "effective-tensor"},
                                           DeckCase{"effective_tensor_triangles_plane_stress", 2,
                                                    "stress", "effective-tensor"}),
                         [](const auto& p) { return p.param.name; });

}  // namespace

namespace {

TEST(CalculixDynamicDeck, CcxReproducesTheCoarseTrajectory) {
    // The effective tensors' coarse bar released from rest under its load, 40 midpoint steps of
    // 0.02 (about a period of its lowest mode), its lumped coarse mass as *MASS elements:
    // CalculiX's α-method with α = 0 is the same integrator, so every saved frame agrees to
    // ccx's 7 printed digits, 1e-6 of the largest displacement. (With the elements' densities
    // instead, CalculiX integrates each C3D4's mass at its one Gauss point, ρV/16 between every
    // pair of nodes, not the consistent ρV(1 + δ_ab)/20: coarse.mass "consistent" then differs by
    // 4.5%, and that one-point mass reproduces ccx to 7e-6.)
    const scene::Scene sc = scene::parse_scene(layered_bar(3, ""), "bar.json", ".");
    const scene::FineModel fine = scene::build_fine_model(sc);
    const coarsen::CoarseModel model = coarsen::build_coarse_model(sc, fine, "effective-tensor");
    const coarsen::ElementModel& e = *model.element_model;
    const SparseMatrix M =
        model.mass(fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent));
    sim::DynamicsOptions o;
    o.dt = 0.02;
    o.steps = 40;
    o.output_every = 10;
    const auto [start, f] = sim::initial_state(model.K, model.f, model.bc, Vector(), o);
    const sim::Trajectory t = sim::simulate(model.K, M, model.bc, start, f, o);

    io::CalculixDynamics d;
    d.dt = o.dt;
    d.steps = o.steps;
    d.output_every = o.output_every;
    d.lumped_mass = M.diagonal();
    ASSERT_EQ(M.nonZeros(), M.rows());  // the default coarse mass is lumped
    const std::string dir = test::temp_dir("calculix_dynamic_deck");
    io::write_calculix_deck(dir + "/coarse.inp", e.mesh, e.materials, model.f, model.bc, sc.plane,
                            "dynamic", d);
    std::string output;
    ASSERT_EQ(test::run(fmt::format("cd {} && ccx -i coarse", dir), &output), 0) << output;
    std::vector<Vector> frames;
    for (const Matrix& block : test::read_ccx_displacements(dir + "/coarse.dat"))
        frames.push_back(test::interleaved(block, 3));
    ASSERT_EQ(frames.size(), t.u.size() - 1) << output;  // t = 0 is not printed
    double largest = 0, worst = 0;
    for (const Vector& u : t.u) largest = std::max(largest, u.cwiseAbs().maxCoeff());
    for (std::size_t i = 0; i < frames.size(); ++i)
        worst = std::max(worst, (t.u[i + 1] - frames[i]).cwiseAbs().maxCoeff());
    EXPECT_LT(worst / largest, 1e-6);
    std::printf("  max over frames |u - u_ccx| / max |u| = %.2e\n", worst / largest);
}

}  // namespace
