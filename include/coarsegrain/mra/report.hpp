#pragma once
/// @file Figures of the material-adapted hierarchy as a coarse model (mra::coarse_model,
/// mra::compare_levels), which the CLI writes to summary.json "coarse" under the names of the
/// fields.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "coarsegrain/mra/diagnostics.hpp"
#include "coarsegrain/mra/options.hpp"

namespace coarsegrain::mra {

/// Build figures of one level k < q.
struct LevelReport {
    int level = 0;           ///< k
    std::vector<int> cells;  ///< grid cells per axis (dim entries; empty on level meshes)
    Index nodes = 0;         ///< nodes of the level's grid or mesh
    Index elements = 0;      ///< cells of the level's grid or elements of its mesh
    Index dofs = 0;          ///< present DOFs (rows of A^k)
    Index wavelets = 0;      ///< rows of W^k
    double radius = 0;       ///< Level::radius (infinite: global solves)
    double build_seconds = 0;
    /// Nonzeros and density (nonzeros over rows x cols) of C̃^k and of the whole A^k and B^k.
    std::int64_t C_nnz = 0, A_nnz = 0, B_nnz = 0;
    double C_density = 0, A_density = 0, B_density = 0;
    /// Mean and largest Level::region_rings over the nodes with a localized solve; none without
    /// (global solves, cell localization).
    std::optional<double> region_rings_mean;
    std::optional<int> region_rings_max;
    /// The file the level's mesh was written to (automatic level meshes), else empty.
    std::string mesh_file;
};

/// Figures of the fine level q, which has no refinement and no wavelets.
struct FineLevelReport {
    int level = 0;           ///< q
    std::vector<int> cells;  ///< grid cells per axis (empty on level meshes)
    Index nodes = 0;
    std::int64_t A_nnz = 0;  ///< stored nonzeros of Hierarchy::A_fine
};

/// Figures of a hierarchy's build (coarse_model).
struct HierarchyReport {
    Options options;
    std::vector<LevelReport> levels;  ///< levels[k-1] is level k, k = 1..q-1
    FineLevelReport fine_level;
    Index fine_dofs = 0;  ///< size of Hierarchy::fine_dofs
};

/// Young's moduli of the effective tensor of one coarsest cell.
struct CellYoungs {
    std::vector<double> E_axes;   ///< along the axes (dim entries)
    double E_min = 0, E_max = 0;  ///< over youngs_directions
};

/// Sec. 5.6: the effective tensors of the coarsest cells (compare_levels).
struct CoarsestCellsReport {
    Index cells = 0;
    std::string skipped;  ///< why they were not computed; empty if they were
    // Computed only:
    std::string vtu;              ///< the file, coarsest_cells.vtu
    double E_min = 0, E_max = 0;  ///< over all cells and directions
    std::vector<CellYoungs> per_cell;
};

/// Figures of every level against the fine solution (compare_levels).
struct ComparisonReport {
    std::vector<LevelDiagnostics> levels;  ///< levels[k-1] is level k, k = 1..q
    Index spectrum_max_dofs = 0;           ///< CompareOptions::max_spectrum_dofs
    CoarsestCellsReport coarsest_cells;
};

}  // namespace coarsegrain::mra
