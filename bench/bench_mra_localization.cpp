// Localization study of the material-adapted hierarchy (Chen et al. 2019, Sec. 3.5, Figs. 5, 6):
// coarsest-level energy error and density against the localization radius rho (rings counted on
// either grid), the truncation threshold, the material contrast and the invariance correction,
// on a hung bimaterial square (inclusions, contrast 2000), a layered composite (Fig. 9: layers
// along the hanging direction) and the same layers across it ("across": stiff slabs spanning
// the width, each coarse cell of the finest step one layer at 16x16).
//
//   bench_mra_localization [cells=32] [levels=3] [tables=rtc]
//     r: radius table (rho 1..8, fine/coarse rings, invariance on/off)
//     t: truncation table (0, 1e-7, 1e-5, 1e-4, 1e-2) for global and localized solves
//     c: contrast table (1e1..1e4), hung square only
//     l: node- against cell-wise localization (rho 1..6 coarse rings, invariance on/off)
//     m: canonical against stiffness-weighted measurements (global; cell-wise 2, 4, 6 coarse
//        rings; node-wise without invariance correction 4, 6)
//     d: Eq. 12 defect-driven radius (start 2 fine rings, doubled up to the grid) against the
//        defect tolerance 1e-1 .. 1e-5, and fixed radii 2, 4, 8, 16 fine rings
//
// Columns: err_u = ||u^1 - u||_A / ||u||_A, err_g = ||u^1 - u||_A / ||g||_2 (Fig. 6/9 metric),
// dens_C = nonzero fraction of C̃ of the finest step, dens_A = of A^1, defect = Eq. 12
// A-orthogonality defect of the finest step ||C̃ A W^T||_F / ||C^† A W^T||_F (0 for global
// solves, 1 for Z = 0), rings = mean / largest region rings of the finest step (fine grid),
// build = build_hierarchy wall seconds (shared machine).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "coarsegrain/mra/multilevel_solver.hpp"
#include "mra/mra_test_util.hpp"

namespace cg = coarsegrain;
using cg::mra::Options;
using cg::mra::RadiusGrid;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Row {
    double err_u = 0, err_g = 0, dens_C = 0, dens_A = 0, defect = 0, seconds = 0;
    double rings_mean = 0;
    int rings_max = 0;
};

template <class M>
double density(const M& m) {
    return static_cast<double>(m.nonZeros()) /
           (static_cast<double>(m.rows()) * static_cast<double>(m.cols()));
}

Row evaluate(const cg::test::GridProblem& p, const Options& o) {
    const auto t0 = std::chrono::steady_clock::now();
    const cg::mra::Hierarchy h = cg::mra::build_hierarchy(p.mesh, p.K, p.bc.dofs, o, &p.materials);
    Row r;
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    cg::mra::MultilevelSolver s(h);
    const cg::Vector e = s.solve_level(p.f, 1) - p.u;
    r.err_u = cg::test::energy_norm(p.K, e) / cg::test::energy_norm(p.K, p.u);
    r.err_g = cg::test::energy_norm(p.K, e) / p.f.norm();
    const cg::mra::Level& F = h.level(h.num_levels() - 1);
    r.dens_C = density(F.C_adapted);
    r.dens_A =
        static_cast<double>(cg::mra::symmetric_nonzeros(h.level(1).A)) /
        (static_cast<double>(h.level(1).A.rows()) * static_cast<double>(h.level(1).A.rows()));
    const cg::SparseMatrix AWt = h.A_fine * cg::SparseMatrix(F.W.transpose());
    r.defect = cg::SparseMatrix(F.C_adapted.sparse() * AWt).norm() /
               cg::SparseMatrix(F.C_dagger * AWt).norm();
    int count = 0;
    for (const int k : F.region_rings)
        if (k > 0) {
            r.rings_mean += k;
            r.rings_max = std::max(r.rings_max, k);
            ++count;
        }
    if (count > 0) r.rings_mean /= count;
    return r;
}

std::string radius_label(double rho, RadiusGrid g) {
    if (rho == kInf) return "inf";
    return std::to_string(static_cast<int>(rho)) + (g == RadiusGrid::Fine ? "f" : "c");
}

void header() {
    std::printf("%-10s %-6s %-7s %-4s %-4s %-9s %-7s %-8s %8s %9s %7s %7s %8s %9s %7s\n", "problem",
                "rho", "tol", "loc", "inv", "measure", "trunc", "contrast", "err_u", "err_g",
                "dens_C", "dens_A", "defect", "rings", "build");
}

void print(const char* name, const Options& o, double contrast, const Row& r) {
    const std::string rings =
        std::to_string(r.rings_mean).substr(0, 4) + "/" + std::to_string(r.rings_max);
    std::printf(
        "%-10s %-6s %-7.0e %-4s %-4d %-9s %-7.0e %-8.0e %8.4f %9.4g %7.3f %7.3f %8.2g %9s %7.2f\n",
        name, radius_label(o.radius[0], o.radius_grid).c_str(), o.defect_tolerance,
        cg::mra::localization_name(o.localization).c_str(), o.invariance ? 1 : 0,
        cg::mra::measurement_name(o.measurement).c_str(), o.truncation, contrast, r.err_u, r.err_g,
        r.dens_C, r.dens_A, r.defect, rings.c_str(), r.seconds);
    std::fflush(stdout);
}

/// Vertical layers of thickness 1/8 (stiff first), as in the Fig. 9 tests.
int layered(const Eigen::VectorXd& x) { return static_cast<int>(std::floor(8 * x[0])) % 2 == 0; }

/// The same layers across the hanging direction.
int layered_across(const Eigen::VectorXd& x) {
    return static_cast<int>(std::floor(8 * x[1])) % 2 == 0;
}

struct Problem {
    const char* name;
    double E_soft, contrast;
    cg::test::MaterialPattern pattern;
};

cg::test::GridProblem make(const Problem& pr, int cells, double contrast) {
    return cg::test::hung_problem(2, Eigen::Vector3i(cells, cells, 1), pr.E_soft,
                                  pr.E_soft * contrast, pr.pattern, Eigen::Vector3d::Ones(), false);
}

}  // namespace

int main(int argc, char** argv) {
    const int cells = argc > 1 ? std::atoi(argv[1]) : 32;
    const int levels = argc > 2 ? std::atoi(argv[2]) : 3;
    const std::string tables = argc > 3 ? argv[3] : "rtc";
    std::printf("%dx%d grid, %d levels, bilinear refinement, constrained Dirichlet\n", cells, cells,
                levels);
    const std::vector<Problem> problems = {{"square", 1.0, 2000.0, cg::test::checker_pattern},
                                           {"layered", 100.0, 5e4, layered},
                                           {"across", 100.0, 5e4, layered_across}};
    Options base;
    base.levels = levels;
    base.refinement = cg::mra::Refinement::Linear;
    base.truncation = 0;
    base.radius = {std::numeric_limits<double>::infinity()};  // the global row
    header();
    for (const Problem& pr : problems) {
        const cg::test::GridProblem p = make(pr, cells, pr.contrast);
        Options o = base;
        print(pr.name, o, pr.contrast, evaluate(p, o));
        if (tables.find('r') != std::string::npos)
            for (const bool inv : {true, false})
                for (const RadiusGrid grid : {RadiusGrid::Fine, RadiusGrid::Coarse})
                    for (int rho = 1; rho <= 8; ++rho) {
                        o = base;
                        o.radius = {static_cast<double>(rho)};
                        o.radius_grid = grid;
                        o.invariance = inv;
                        print(pr.name, o, pr.contrast, evaluate(p, o));
                    }
        if (tables.find('t') != std::string::npos)
            for (const double rho : {kInf, 4.0})
                for (const double tau : {1e-7, 1e-5, 1e-4, 1e-2}) {
                    o = base;
                    o.radius = {rho};
                    o.radius_grid = RadiusGrid::Coarse;
                    o.truncation = tau;
                    print(pr.name, o, pr.contrast, evaluate(p, o));
                }
        if (tables.find('l') != std::string::npos)
            for (const bool inv : {true, false})
                for (int rho = 1; rho <= 6; ++rho)
                    for (const auto loc :
                         {cg::mra::Localization::Node, cg::mra::Localization::Cell}) {
                        o = base;
                        o.radius = {static_cast<double>(rho)};
                        o.radius_grid = RadiusGrid::Coarse;
                        o.invariance = inv;
                        o.localization = loc;
                        print(pr.name, o, pr.contrast, evaluate(p, o));
                    }
        if (tables.find('m') != std::string::npos)
            for (const auto m :
                 {cg::mra::Measurement::Canonical, cg::mra::Measurement::Stiffness}) {
                o = base;
                o.measurement = m;
                print(pr.name, o, pr.contrast, evaluate(p, o));
                o.radius_grid = RadiusGrid::Coarse;
                o.localization = cg::mra::Localization::Cell;
                for (const double rho : {2.0, 4.0, 6.0}) {
                    o.radius = {rho};
                    print(pr.name, o, pr.contrast, evaluate(p, o));
                }
                o.localization = cg::mra::Localization::Node;
                o.invariance = false;
                for (const double rho : {4.0, 6.0}) {
                    o.radius = {rho};
                    print(pr.name, o, pr.contrast, evaluate(p, o));
                }
            }
        if (tables.find('d') != std::string::npos) {
            for (const double rho : {2.0, 4.0, 8.0, 16.0}) {
                o = base;
                o.radius = {rho};
                print(pr.name, o, pr.contrast, evaluate(p, o));
            }
            for (const double tol : {1e-1, 1e-2, 1e-3, 1e-4, 1e-5}) {
                o = base;
                o.radius = {2.0};
                o.max_radius = 2.0 * cells;
                o.defect_tolerance = tol;
                print(pr.name, o, pr.contrast, evaluate(p, o));
            }
        }
    }
    if (tables.find('c') != std::string::npos)
        for (const double contrast : {1e1, 1e2, 1e3, 1e4}) {
            const cg::test::GridProblem p = make(problems[0], cells, contrast);
            for (const double rho : {kInf, 2.0, 4.0, 6.0}) {
                Options o = base;
                o.radius = {rho};
                o.radius_grid = RadiusGrid::Coarse;
                print("square", o, contrast, evaluate(p, o));
            }
        }
}
