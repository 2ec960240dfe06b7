/// Intersection measures |T_p ∩ 𝕋_q| (mesh::intersect) of a fine Tet4 grid of 32^3 cells
/// (196,608 tets) with a jittered coarse Tet4 grid of 5x5x4 cells (600 tets) over the same box,
/// the sizes of the effective-tensor build (Kharevych et al. 2009, Eq. 8); then the same in 2D
/// (512^2 cells, 524,288 triangles, against 20x20 cells). Prints the best wall time of a few
/// runs, the number of overlaps, and the largest relative defect of the sum identities
/// (sum over coarse = |T_p|, sum over fine = |𝕋_q|).
/// Run: ./build/release/bench/bench_intersection
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/intersection.hpp"

using namespace coarsegrain;

namespace {

/// Moves every interior node by up to `amount` grid spacings (deterministic).
void jitter(mesh::Mesh& m, double amount) {
    const Eigen::Vector3d h = m.grid->spacing();
    const Matrix box = mesh::bounding_box(m);
    for (Index v = 0; v < m.num_nodes(); ++v) {
        auto x = m.rest_positions.row(v);
        bool interior = true;
        for (int d = 0; d < m.dim(); ++d)
            interior = interior && x[d] > box(0, d) + 1e-12 && x[d] < box(1, d) - 1e-12;
        if (interior)
            for (int d = 0; d < m.dim(); ++d)
                x[d] += amount * h[d] * std::sin(12.9898 * v + 78.233 * d);
    }
    m.grid.reset();
}

double max_defect(const Eigen::VectorXd& sum, const mesh::Mesh& m) {
    double worst = 0;
    for (Index e = 0; e < m.num_elements(); ++e) {
        const double ref = mesh::element_measure(m, e);
        worst = std::max(worst, std::abs(sum[e] - ref) / ref);
    }
    return worst;
}

void run(mesh::ElementType type, int fine_cells, const Eigen::VectorXi& coarse_cells) {
    const int dim = mesh::element_dim(type);
    Eigen::VectorXd lo = Eigen::VectorXd::Zero(dim), hi(dim);
    hi << 1.0, 0.8, 0.6;
    hi.conservativeResize(dim);
    const mesh::Mesh fine =
        mesh::make_grid(type, lo, hi, Eigen::VectorXi::Constant(dim, fine_cells));
    mesh::Mesh coarse = mesh::make_grid(type, lo, hi, coarse_cells.head(dim));
    jitter(coarse, 0.2);
    mesh::validate(coarse, "jittered coarse grid");

    double best = std::numeric_limits<double>::infinity();
    std::vector<mesh::Overlap> overlaps;
    for (int repeat = 0; repeat < 3; ++repeat) {
        const auto t0 = std::chrono::steady_clock::now();
        overlaps = mesh::intersect(fine, coarse);
        const auto t1 = std::chrono::steady_clock::now();
        best = std::min(best, std::chrono::duration<double>(t1 - t0).count());
    }
    Eigen::VectorXd fine_sum = Eigen::VectorXd::Zero(fine.num_elements());
    Eigen::VectorXd coarse_sum = Eigen::VectorXd::Zero(coarse.num_elements());
    for (const auto& o : overlaps) {
        fine_sum[o.fine] += o.measure;
        coarse_sum[o.coarse] += o.measure;
    }
    std::printf("%s: fine %d elements, coarse %d elements, %d threads\n",
                mesh::element_name(type).c_str(), fine.num_elements(), coarse.num_elements(),
                omp_get_max_threads());
    std::printf("  intersect: %.3f s (best of 3), %zu overlaps (%.2f per fine element)\n", best,
                overlaps.size(), static_cast<double>(overlaps.size()) / fine.num_elements());
    std::printf("  max relative defect: per fine %.2e, per coarse %.2e\n",
                max_defect(fine_sum, fine), max_defect(coarse_sum, coarse));
}

}  // namespace

int main() {
    run(mesh::ElementType::Tet4, 32, Eigen::Vector3i(5, 5, 4));
    run(mesh::ElementType::Tri3, 512, Eigen::Vector3i(20, 20, 1));
    return 0;
}
