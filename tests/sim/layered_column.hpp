#pragma once
/// @file The layered column of the coarse-mass study (tests/sim/test_coarse_mass_contrast.cpp and
/// bench/bench_coarse_mass.cpp, which prints the tables of docs/coarse-mass.md): a 2D bar whose
/// stiffness is homogeneous and whose density varies along its axis, so that its coarse models
/// differ only by their coarse mass.
///
/// The bar [0, 8] x [0, 1], E = 1, nu = 0, is clamped at x = 0 and its lateral displacements are
/// held (a laterally constrained column: its low modes are the axial ones of a 1D bar, without
/// the bending that a coarse triangle mesh gets wrong by its stiffness). Fine mesh: 64 x 8 cells
/// split into triangles (1170 DOFs); coarse mesh: 16 x 2 cells (102 DOFs), the fine grid
/// coarsened 4 times per axis, so that every fine triangle lies in one coarse triangle and the
/// barycentric map P carries the coarse fields exactly: with one stiffness the effective tensor
/// (and every average) is the material's tensor and the coarse stiffness is PᵀKP. The density is
/// 1, and `contrast` in fine layers 0.125 thick (4 per coarse cell) chosen by the pattern.
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/sim/modes.hpp"

namespace coarsegrain::test {

inline constexpr double kColumnLength = 8;
inline constexpr int kColumnFineCells = 64;    ///< fine cells along the axis (8 across)
inline constexpr int kColumnCoarseCells = 16;  ///< coarse cells along the axis (2 across)
inline constexpr int kColumnAxialModes = 5;    ///< axial modes the study compares

/// Where the heavy fine layers (density `contrast`) are.
enum class DensityPattern {
    Centred,    ///< the two middle layers of every coarse cell
    OffCentre,  ///< the first layer of every coarse cell (the one nearest the clamp)
    Tip,        ///< the last layer of the bar only: a tip mass inside the last coarse cell
};

inline const char* pattern_name(DensityPattern p) {
    return p == DensityPattern::Centred     ? "centred"
           : p == DensityPattern::OffCentre ? "off-centre"
                                            : "tip";
}

/// The column's scene; `mass` is its coarse.mass.
inline scene::Scene column_scene(DensityPattern pattern, double contrast, const std::string& mass) {
    const auto grid = [](int nx, int ny) {
        return nlohmann::json{{"grid",
                               {{"min", {0, 0}},
                                {"max", {kColumnLength, 1}},
                                {"cells", {nx, ny}},
                                {"element", "tri"}}}};
    };
    std::vector<int> ids = {1, 2, 2, 1};  // material ids of the fine layers, cyclic
    if (pattern == DensityPattern::OffCentre) ids = {2, 1, 1, 1};
    if (pattern == DensityPattern::Tip) {
        ids.assign(kColumnFineCells, 1);
        ids.back() = 2;
    }
    return scene::parse_scene(
        {{"mesh", grid(kColumnFineCells, 8)},
         {"material_field",
          {{"layers",
            {{"axis", "x"}, {"thickness", kColumnLength / kColumnFineCells}, {"ids", ids}}}}},
         {"materials",
          {{"1", {{"E", 1.0}, {"nu", 0.0}, {"density", 1.0}}},
           {"2", {{"E", 1.0}, {"nu", 0.0}, {"density", contrast}}}}},
         {"dirichlet", {{{"box", {{"min", {-1e-9, -1}}, {"max", {1e-9, 2}}}}}}},
         {"coarse", {{"mesh", grid(kColumnCoarseCells, 2)}, {"mass", mass}}}},
        "column.json", "");
}

/// The scene's fine model with every node's lateral displacement held as well.
inline scene::FineModel column_fine_model(const scene::Scene& scene) {
    scene::FineModel fine = scene::build_fine_model(scene);
    std::vector<Index> all(static_cast<std::size_t>(fine.mesh.num_nodes()));
    for (Index v = 0; v < fine.mesh.num_nodes(); ++v) all[static_cast<std::size_t>(v)] = v;
    fine.bc.fix_component(all, 2, 1, 0.0);
    return fine;
}

/// Columns of `modes` (fine DOFs) that are axial: u_x uniform over each section x = const, its
/// deviation from the section's mean below 5% of |u_x| (measured among the 24 lowest fine modes
/// of every pattern and contrast: at most 0.6% for the 5 lowest axial ones, at least 6% for the
/// others, about 99% for the shear modes of a heavy layer).
inline std::vector<Index> axial_modes(const mesh::Mesh& mesh, const Matrix& modes) {
    const Index n = mesh.num_nodes();
    std::vector<Index> section(static_cast<std::size_t>(n));
    for (Index v = 0; v < n; ++v)
        section[static_cast<std::size_t>(v)] = static_cast<Index>(
            std::lround(mesh.rest_positions(v, 0) * kColumnFineCells / kColumnLength));
    std::vector<Index> axial;
    for (Index j = 0; j < modes.cols(); ++j) {
        Vector sum = Vector::Zero(kColumnFineCells + 1), count = Vector::Zero(kColumnFineCells + 1);
        for (Index v = 0; v < n; ++v) {
            sum[section[static_cast<std::size_t>(v)]] += modes(2 * v, j);
            count[section[static_cast<std::size_t>(v)]] += 1;
        }
        double deviation = 0, norm = 0;
        for (Index v = 0; v < n; ++v) {
            const Index s = section[static_cast<std::size_t>(v)];
            deviation += std::pow(modes(2 * v, j) - sum[s] / count[s], 2);
            norm += modes(2 * v, j) * modes(2 * v, j);
        }
        if (deviation < 0.05 * 0.05 * norm) axial.push_back(j);
    }
    return axial;
}

/// A coarse model's frequencies paired with the fine axial modes.
struct PairedFrequencies {
    std::vector<double> hz;   ///< the paired coarse mode's frequency, per fine axial mode
    std::vector<double> mac;  ///< MAC of the pair
};

/// The lowest axial fine frequencies and, for each coarse mass, the coarse ones paired with them.
struct ColumnStudy {
    std::vector<double> fine_hz;                      ///< kColumnAxialModes, ascending
    std::map<std::string, PairedFrequencies> coarse;  ///< by coarse.mass
    /// (f_coarse - f_fine) / f_fine of axial mode i (0-based) with coarse mass `mass`.
    double error(const std::string& mass, std::size_t i) const {
        return (coarse.at(mass).hz[i] - fine_hz[i]) / fine_hz[i];
    }
};

/// Fine model (consistent mass) and the coarse model of `method` with each coarse mass; their
/// modes are paired by MAC on the fine nodes (coarse modes carried by the model's map).
inline ColumnStudy column_study(DensityPattern pattern, double contrast,
                                const std::string& method = "effective-tensor") {
    const scene::FineModel fine = column_fine_model(column_scene(pattern, contrast, "lumped"));
    const SparseMatrix M = fem::mass_matrix(fine.mesh, fine.materials, fem::MassType::Consistent);
    const sim::Modes mf = sim::modes(fine.K, M, fine.bc, 24);
    std::vector<Index> axial = axial_modes(fine.mesh, mf.vectors);
    CG_VERIFY(axial.size() >= kColumnAxialModes,
              "column ({}, contrast {}): {} axial modes among the lowest 24", pattern_name(pattern),
              contrast, axial.size());
    axial.resize(kColumnAxialModes);
    ColumnStudy study;
    Matrix reference(mf.vectors.rows(), kColumnAxialModes);
    for (Index i = 0; i < kColumnAxialModes; ++i) {
        reference.col(i) = mf.vectors.col(axial[static_cast<std::size_t>(i)]);
        study.fine_hz.push_back(mf.frequencies_hz[axial[static_cast<std::size_t>(i)]]);
    }
    for (const char* mass : {"lumped", "consistent", "galerkin"}) {
        const coarsen::CoarseModel c =
            coarsen::build_coarse_model(column_scene(pattern, contrast, mass), fine, method);
        const sim::Modes mc = sim::modes(c.K, c.mass(M), c.bc, static_cast<int>(c.K.rows()));
        PairedFrequencies& p = study.coarse[mass];
        for (const sim::ModePair& pair : sim::pair_modes(reference, c.to_fine * mc.vectors)) {
            p.hz.push_back(mc.frequencies_hz[pair.coarse]);
            p.mac.push_back(pair.mac);
        }
    }
    return study;
}

}  // namespace coarsegrain::test
