// Corotated statics: how Newton's method converges with the tangent R K Rᵀ (the frames' derivative
// left out, as sim::solve_corotated_static does) against the exact Jacobian of the corotated
// force (central differences, dense LU), and how far the de Veubeke and polar frames' solutions
// are apart on regular and distorted elements. Prints the tables of docs/guide.md,
// "Large rotations".
//
//   build/release/bench/bench_corotation
//
// The problem: a cantilever [0, 10] x [0, 0.5] x [0, 0.5] (E = 1e5, nu = 0.3, density 1) of
// 20 x 2 x 2 hexes (2:1 elements), clamped at x = 0, under gravity -z scaled so that the linear
// tip deflection is `sag` times the length; the distorted variant moves interior nodes by up to
// 0.2 cell widths.
#include <fmt/format.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/corotational.hpp"

using namespace coarsegrain;

namespace {

scene::FineModel cantilever(double gravity, const char* element = "hex") {
    const nlohmann::json j = {
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}},
            {"max", {10, 0.5, 0.5}},
            {"cells", {20, 2, 2}},
            {"element", element}}}}},
        {"materials", {{"0", {{"E", 1e5}, {"nu", 0.3}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 1, 1}}}}}}},
        {"loads", {{"gravity", {0, 0, -gravity}}}}};
    return scene::build_fine_model(scene::parse_scene(j, "cantilever", "."));
}

/// Gravity whose linear tip deflection is `sag` times the length.
double gravity_for(double sag) {
    const scene::FineModel unit = cantilever(1.0);
    const Vector u = fem::solve_static(unit.K, unit.f, unit.bc, {});
    double tip = 0;
    for (Index v = 0; v < unit.mesh.num_nodes(); ++v) tip = std::max(tip, std::abs(u[3 * v + 2]));
    return sag * 10 / tip;
}

/// Newton with the exact Jacobian of the corotated force (central differences) and the same
/// line search; returns the relative residual after each iteration.
std::vector<double> exact_newton(const fem::CorotatedModel& model, const scene::FineModel& m) {
    const IndexVector free = fem::free_dofs(m.mesh.num_dofs(), m.bc);
    const auto residual = [&](const Vector& u) -> Vector {
        return (m.f - model.evaluate(u).force)(free);
    };
    Vector u = Vector::Zero(m.mesh.num_dofs());
    const double r0 = residual(u).norm();
    std::vector<double> history;
    Vector r = residual(u);
    for (int it = 0; it < 40 && r.norm() > 1e-12 * r0; ++it) {
        Matrix J(free.size(), free.size());
        const double h = 1e-7 * std::max(1.0, u.lpNorm<Eigen::Infinity>());
        for (Index j = 0; j < free.size(); ++j) {
            Vector up = u, um = u;
            up[free[j]] += h;
            um[free[j]] -= h;
            J.col(j) = -(residual(up) - residual(um)) / (2 * h);
        }
        const Vector d = J.partialPivLu().solve(r);
        double step = 1;
        Vector trial;
        for (; step >= 1.0 / 64; step /= 2) {
            trial = u;
            trial(free) += step * d;
            if (residual(trial).norm() <= (1 - step / 4) * r.norm()) break;
        }
        u = trial;
        r = residual(u);
        history.push_back(r.norm() / r0);
    }
    return history;
}

std::string residuals(const std::vector<double>& h) {
    std::string s;
    for (const double r : h) s += fmt::format("{}{:.1e}", s.empty() ? "" : ", ", r);
    return s;
}

void convergence_table() {
    fmt::print("| linear tip sag / L | tangent | iterations | relative residual after each |\n");
    fmt::print("|---|---|---|---|\n");
    for (const double sag : {0.05, 0.15, 0.33}) {
        const scene::FineModel m = cantilever(gravity_for(sag));
        const fem::CorotatedModel model(m.mesh, m.materials, fem::Formulation::Standard,
                                        fem::CorotationFrame::DeVeubeke);
        sim::CorotationOptions o;
        o.tolerance = 1e-12;
        o.max_iterations = 200;
        const sim::CorotatedSolution s = sim::solve_corotated_static(model, m.f, m.bc, o, {});
        std::vector<double> fixed;
        for (const sim::NewtonIteration& it : s.report.history) fixed.push_back(it.residual);
        fmt::print("| {:.2f} | R K Rᵀ (frames held) | {} | {} |\n", sag, s.report.iterations,
                   residuals(fixed));
        const std::vector<double> exact = exact_newton(model, m);
        fmt::print("| {:.2f} | exact (differences) | {} | {} |\n", sag, exact.size(),
                   residuals(exact));
    }
}

void frame_table() {
    fmt::print(
        "\n| mesh | linear tip sag / L | tip displacement, de Veubeke | polar | "
        "difference / |u_tip| |\n");
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
    convergence_table();
    frame_table();
    return 0;
}
