// Which coarse mass gets which frequencies right, against the density contrast: prints the tables
// of docs/coarse-mass.md.
//
//   build/release/bench/bench_coarse_mass
//
// The layered column of tests/sim/layered_column.hpp (homogeneous stiffness, density 1 and
// `contrast` in fine layers across the axis, lateral displacements held, 64x8 fine and 16x2
// coarse cells of triangles): for each density pattern and contrast, the 5 lowest axial fine
// frequencies and the relative error of the effective-tensor model's paired frequency with each
// coarse mass (coarse.mass), and the smallest MAC of the pairs. Contrast 1 is the control: the
// coarse discretization's error alone. Last, the largest relative difference between the
// frequencies of the naive average and those of the effective tensors over every row (their
// stiffness is the same with one material), and the lowest frequency of the same bar without its
// lateral hold, a bending mode, whose error is the coarse triangles' bending stiffness.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/layered_column.hpp"

using namespace coarsegrain;
using test::DensityPattern;

namespace {

double print_rows(DensityPattern pattern, double contrast) {
    const test::ColumnStudy s = test::column_study(pattern, contrast);
    const char* name = contrast == 1 ? "uniform" : test::pattern_name(pattern);
    std::string fine = fmt::format("| {} | {:g} | fine (Hz) |", name, contrast);
    for (double f : s.fine_hz) fine += fmt::format(" {:.5f} |", f);
    fmt::print("{} |\n", fine);
    for (const char* mass : {"lumped", "consistent", "galerkin"}) {
        std::string row = fmt::format("| {} | {:g} | {} |", name, contrast, mass);
        for (std::size_t i = 0; i < s.fine_hz.size(); ++i)
            row += fmt::format(" {:+.2f}% |", 100 * s.error(mass, i));
        const std::vector<double>& mac = s.coarse.at(mass).mac;
        fmt::print("{} {:.3f} |\n", row, *std::min_element(mac.begin(), mac.end()));
    }
    const test::ColumnStudy naive = test::column_study(pattern, contrast, "naive");
    double difference = 0;
    for (const auto& [mass, p] : s.coarse)
        for (std::size_t i = 0; i < p.hz.size(); ++i)
            difference =
                std::max(difference, std::abs(naive.coarse.at(mass).hz[i] - p.hz[i]) / p.hz[i]);
    return difference;
}

/// The same bar without its lateral hold (off-centre pattern): the relative error of its lowest
/// frequency, the first bending mode, per coarse mass.
void print_free_bar(double contrast) {
    const auto scene = [contrast](const char* mass) {
        return test::column_scene(DensityPattern::OffCentre, contrast, mass);
    };
    const scene::FineModel fine = scene::build_fine_model(scene("lumped"));
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const double f = sim::modes(fine.K, M, fine.bc, 1).frequencies_hz[0];
    std::string row = fmt::format("| {:g} | {:.3e} |", contrast, f);
    for (const char* mass : {"lumped", "consistent", "galerkin"}) {
        const coarsen::CoarseModel c =
            coarsen::build_coarse_model(scene(mass), fine, "effective-tensor");
        const double fc = sim::modes(c.K, c.mass(M), c.bc, 1).frequencies_hz[0];
        row += fmt::format(" {:+.1f}% |", 100 * (fc - f) / f);
    }
    fmt::print("{}\n", row);
}

}  // namespace

int main() {
    std::string header = "| density | contrast | coarse mass |", rule = "|---|---|---|";
    for (int n = 1; n <= test::kColumnAxialModes; ++n) {
        header += fmt::format(" axial {} |", n);
        rule += "---|";
    }
    fmt::print("{} min MAC |\n{}---|\n", header, rule);
    double naive = print_rows(DensityPattern::Centred, 1);
    for (DensityPattern pattern :
         {DensityPattern::Centred, DensityPattern::OffCentre, DensityPattern::Tip})
        for (double contrast : {10.0, 100.0})
            naive = std::max(naive, print_rows(pattern, contrast));
    fmt::print("\nnaive against effective-tensor: largest relative frequency difference {:.1e}\n",
               naive);
    fmt::print(
        "\nWithout the lateral hold (off-centre layers), lowest (bending) frequency:\n\n"
        "| contrast | fine (Hz) | lumped | consistent | galerkin |\n|---|---|---|---|---|\n");
    for (double contrast : {1.0, 10.0, 100.0}) print_free_bar(contrast);
    return 0;
}
