// Corotated statics: how Newton's method converges with the consistent Jacobian of the corotated
// force (the frames' derivative included; tests/fem/test_corotated_model.cpp checks it against
// differences of the force) against the tangent R K Rᵀ (frames held fixed), and how far the de
// Veubeke and polar frames' solutions are apart on regular and distorted elements. Prints the
// tables of docs/guide.md, "Large rotations".
//
//   build/release/bench/bench_corotation
//
// The problem: a cantilever [0, 10] x [0, 0.5] x [0, 0.5] (E = 1e5, nu = 0.3, density 1) of
// 20 x 2 x 2 hexes (2:1 elements; also 80 x 8 x 8, 17K DOFs, for the cost of an iteration),
// clamped at x = 0, under gravity -z scaled so that the linear tip deflection is `sag` times the
// length; the distorted variant moves interior nodes by up to 0.2 cell widths.
#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/corotational.hpp"

using namespace coarsegrain;

namespace {

/// The cantilever with `refine` times the cells per axis.
scene::FineModel cantilever(double gravity, int refine = 1) {
    const nlohmann::json j = {
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}},
            {"max", {10, 0.5, 0.5}},
            {"cells", {20 * refine, 2 * refine, 2 * refine}},
            {"element", "hex"}}}}},
        {"materials", {{"0", {{"E", 1e5}, {"nu", 0.3}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 1, 1}}}}}}},
        {"loads", {{"gravity", {0, 0, -gravity}}}}};
    return scene::build_fine_model(scene::parse_scene(j, "cantilever", "."));
}

/// Gravity whose linear tip deflection is `sag` times the length.
double gravity_for(double sag, int refine = 1) {
    const scene::FineModel unit = cantilever(1.0, refine);
    const Vector u = fem::solve_static(unit.K, unit.f, unit.bc, {});
    double tip = 0;
    for (Index v = 0; v < unit.mesh.num_nodes(); ++v) tip = std::max(tip, std::abs(u[3 * v + 2]));
    return sag * 10 / tip;
}

/// "1.0e+00, 2.0e-03, ..." (a negative entry: "...").
std::string residuals(const std::vector<double>& h) {
    std::string s;
    for (const double r : h)
        s += (s.empty() ? "" : ", ") + (r < 0 ? std::string("...") : fmt::format("{:.1e}", r));
    return s;
}

void convergence_table(int refine, const std::vector<double>& sags) {
    fmt::print(
        "| cells | linear tip sag / L | tangent | iterations | increments | seconds | "
        "relative residual after each iteration |\n");
    fmt::print("|---|---|---|---|---|---|---|\n");
    for (const double sag : sags) {
        const scene::FineModel m = cantilever(gravity_for(sag, refine), refine);
        const fem::CorotatedModel model(m.mesh, m.materials, fem::Formulation::Standard,
                                        fem::CorotationFrame::DeVeubeke);
        for (const sim::Tangent tangent : {sim::Tangent::Consistent, sim::Tangent::FixedFrame}) {
            sim::CorotationOptions o;
            o.tangent = tangent;
            o.tolerance = 1e-10;
            o.max_iterations = 400;
            Timings t;
            const sim::CorotatedSolution s =
                sim::solve_corotated_static(model, m.f, m.bc, o, {}, &t);
            std::vector<double> history;
            for (const sim::NewtonIteration& it : s.report.history) history.push_back(it.residual);
            // The fixed frame's long linear tail: its first 6 and last 6 iterations.
            if (history.size() > 12) {
                history.erase(history.begin() + 6, history.end() - 6);
                history.insert(history.begin() + 6, -1);
            }
            fmt::print("| {}x{}x{} | {:.2f} | {} | {} | {} | {:.2f} | {} |\n", 20 * refine,
                       2 * refine, 2 * refine, sag, sim::tangent_name(tangent), s.report.iterations,
                       s.report.increments, t["newton"] + t["factorize"] + t["solve"],
                       residuals(history));
        }
    }
}

void frame_table() {
    fmt::print(
        "\n| mesh | linear tip sag / L | tip displacement, de Veubeke | polar | "
        "relative difference |\n");
    fmt::print("|---|---|---|---|---|\n");
    for (const bool distorted : {false, true}) {
        for (const double sag : {0.05, 0.33}) {
            scene::FineModel m = cantilever(gravity_for(sag));
            if (distorted) {
                // Interior nodes of the 21 x 3 x 3 grid: only the middle line (y = z = 0.25);
                // shift them along x and y by up to 0.2 cell widths.
                for (Index v = 0; v < m.mesh.num_nodes(); ++v) {
                    Eigen::RowVectorXd X = m.mesh.rest_positions.row(v);
                    if (std::abs(X[1] - 0.25) < 1e-9 && std::abs(X[2] - 0.25) < 1e-9 &&
                        X[0] > 1e-9 && X[0] < 10 - 1e-9) {
                        m.mesh.rest_positions(v, 0) += 0.1 * std::sin(3.0 * v);
                        m.mesh.rest_positions(v, 1) += 0.05 * std::cos(5.0 * v);
                    }
                }
                m.mesh.grid.reset();
            }
            Eigen::Vector3d tip[2];
            for (const fem::CorotationFrame frame :
                 {fem::CorotationFrame::DeVeubeke, fem::CorotationFrame::Polar}) {
                const fem::CorotatedModel model(m.mesh, m.materials, fem::Formulation::Standard,
                                                frame);
                sim::CorotationOptions o;
                o.frame = frame;
                o.tolerance = 1e-10;
                o.max_iterations = 200;
                const Vector u = sim::solve_corotated_static(model, m.f, m.bc, o, {}).u;
                Index far = 0;  // the node (10, 0.25, 0.25)
                for (Index v = 0; v < m.mesh.num_nodes(); ++v)
                    if ((m.mesh.rest_positions.row(v) - Eigen::RowVector3d(10, 0.25, 0.25)).norm() <
                        1e-9)
                        far = v;
                tip[frame == fem::CorotationFrame::Polar] = u.segment<3>(3 * far);
            }
            fmt::print("| {} | {:.2f} | ({:.4f}, {:.4f}) | ({:.4f}, {:.4f}) | {:.2e} |\n",
                       distorted ? "distorted" : "regular", sag, tip[0][0], tip[0][2], tip[1][0],
                       tip[1][2], (tip[0] - tip[1]).norm() / tip[0].norm());
        }
    }
}

}  // namespace

int main() {
    convergence_table(1, {0.05, 0.15, 0.33});
    fmt::print("\n");
    convergence_table(4, {0.33});
    frame_table();
    return 0;
}
