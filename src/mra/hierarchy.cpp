#include "coarsegrain/mra/hierarchy.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mra/level_meshes.hpp"
#include "detail.hpp"
#include "products.hpp"

namespace coarsegrain::mra {

namespace {

using Triplet = Eigen::Triplet<double, Index>;
using detail::product;

/// Rows/columns `keep` of a square matrix (keep sorted).
SparseMatrix principal_submatrix(const SparseMatrix& K, const IndexVector& keep) {
    std::vector<Index> map(static_cast<std::size_t>(K.rows()), -1);
    for (Index k = 0; k < keep.size(); ++k) map[static_cast<std::size_t>(keep[k])] = k;
    std::vector<Triplet> t;
    t.reserve(static_cast<std::size_t>(K.nonZeros()));
    for (Index c = 0; c < keep.size(); ++c)
        for (SparseMatrix::InnerIterator it(K, keep[c]); it; ++it) {
            const Index r = map[static_cast<std::size_t>(it.row())];
            if (r >= 0) t.emplace_back(r, c, it.value());
        }
    SparseMatrix out(keep.size(), keep.size());
    out.setFromTriplets(t.begin(), t.end());
    return out;
}

/// Side, in nodes, of the blocks of coarse nodes the Galerkin product A^k = C̃ A^{k+1} C̃^T takes
/// together (index: dim): 2x2x2 nodes (24 DOFs) in 3D, 3x3 (18 DOFs) in 2D.
constexpr int kGroupSide[4] = {0, 0, 3, 2};

/// The groups of level L's DOFs the Galerkin product takes together (detail::congruence): blocks
/// of kGroupSide nodes per axis on grids; on level meshes, the nodes bucketed by position in
/// cubes of kGroupSide mean edge lengths, each bucket cut into groups of at most kMaxGroup DOFs.
std::vector<IndexVector> dof_groups(const Hierarchy& h, const Level& L) {
    const int side = kGroupSide[h.dim];
    if (h.on_grid()) return detail::node_blocks(L.dofs, L.cells, h.dim, side);
    return detail::position_blocks(
        L.dofs, h.mesh_positions(L.k) / (side * h.edge_lengths[static_cast<std::size_t>(L.k - 1)]),
        h.dim);
}

/// Largest Chebyshev distance, in cells of level k, between the node of a row of Phi (Φ^k on the
/// present fine DOFs, rows h.level(k).dofs or h.fine_dofs for k = q) and the finest nodes of its
/// entries, rounded up.
int basis_reach(const Hierarchy& h, const SparseMatrix& Phi, int k) {
    const int q = h.num_levels();
    if (k == q) return 0;
    const int dim = h.dim;
    const IndexVector& rows = h.level(k).dofs;
    const int scale = 1 << (q - k);
    // Each row's node on the finest grid, looked up per entry (Φ^2 of the 80x20x20 accordion
    // has 3.5e8 entries: 6 s computing them per entry).
    std::vector<Eigen::Vector3i> row_node(static_cast<std::size_t>(rows.size()));
    for (Index r = 0; r < rows.size(); ++r)
        row_node[static_cast<std::size_t>(r)] =
            scale * node_coordinates(rows[r] / dim, h.cells(k), dim);
    int reach = 0;
#pragma omp parallel for reduction(max : reach) schedule(dynamic, 256)
    for (Index l = 0; l < Phi.outerSize(); ++l) {
        const Eigen::Vector3i x = node_coordinates(h.fine_dofs[l] / dim, h.fine_cells, dim);
        int d = 0;
        for (SparseMatrix::InnerIterator it(Phi, l); it; ++it)
            d = std::max(d,
                         (x - row_node[static_cast<std::size_t>(it.row())]).cwiseAbs().maxCoeff());
        reach = std::max(reach, (d + scale - 1) / scale);
    }
    return reach;
}

/// Φ^q: the selection of the present fine DOFs, #fine_dofs by fine grid DOFs.
SparseMatrix fine_selection(const Hierarchy& h) {
    SparseMatrix Phi(h.fine_dofs.size(), h.fine_grid_dofs());
    std::vector<Triplet> t;
    for (Index i = 0; i < h.fine_dofs.size(); ++i) t.emplace_back(i, h.fine_dofs[i], 1.0);
    Phi.setFromTriplets(t.begin(), t.end());
    return Phi;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::string refinement_name(Refinement r) { return r == Refinement::Dirac ? "dirac" : "linear"; }

std::string dirichlet_name(DirichletTreatment t) {
    switch (t) {
        case DirichletTreatment::Eliminate:
            return "eliminate";
        case DirichletTreatment::Penalty:
            return "penalty";
        case DirichletTreatment::DiagonalPenalty:
            return "diagonal_penalty";
        case DirichletTreatment::Constrain:
            return "constrain";
        case DirichletTreatment::Ignore:
            return "ignore";
    }
    return "?";
}

std::string operator_name(Operator o) { return o == Operator::Stiffness ? "stiffness" : "step"; }

std::string radius_grid_name(RadiusGrid g) { return g == RadiusGrid::Fine ? "fine" : "coarse"; }

std::string localization_name(Localization l) { return l == Localization::Node ? "node" : "cell"; }

std::string measurement_name(Measurement m) {
    return m == Measurement::Canonical ? "canonical" : "stiffness";
}

Index Hierarchy::fine_grid_dofs() const {
    return dim *
           (on_grid() ? grid_nodes(fine_cells, dim) : static_cast<Index>(fine_positions.rows()));
}

const Matrix& Hierarchy::mesh_positions(int k) const {
    CG_VERIFY(!on_grid() && k >= 1 && k <= num_levels(),
              "mra: mesh positions of level {} of a hierarchy {}", k,
              on_grid() ? "on grids" : "of fewer levels");
    return k == num_levels() ? fine_positions
                             : level_meshes[static_cast<std::size_t>(k - 1)].rest_positions;
}

const Level& Hierarchy::level(int k) const {
    CG_VERIFY(k >= 1 && k < num_levels(), "mra: level {} out of range 1..{}", k, num_levels() - 1);
    return levels[static_cast<std::size_t>(k - 1)];
}

Eigen::Vector3i Hierarchy::cells(int k) const {
    Eigen::Vector3i c = fine_cells;
    for (int d = 0; d < dim; ++d) c[d] >>= (num_levels() - k);
    return c;
}

Eigen::VectorXd Hierarchy::node_position(int k, Index v) const {
    if (!on_grid()) return mesh_positions(k).row(v).transpose();
    const Eigen::Vector3i x = node_coordinates(v, cells(k), dim);
    const double scale = std::ldexp(1.0, num_levels() - k);
    Eigen::VectorXd p(dim);
    for (int d = 0; d < dim; ++d) p[d] = origin[d] + x[d] * scale * spacing[d];
    return p;
}

const IndexVector& fixed_positions(const Hierarchy& h, int k) {
    return k == h.num_levels() ? h.fine_fixed : h.level(k).fixed;
}

IndexVector free_positions(const Hierarchy& h, int k) {
    const IndexVector& held = fixed_positions(h, k);
    const Index n = k == h.num_levels() ? h.fine_dofs.size() : h.level(k).dofs.size();
    IndexVector free(n - held.size());
    for (Index i = 0, f = 0, r = 0; i < n; ++i) {
        if (f < held.size() && held[f] == i)
            ++f;
        else
            free[r++] = i;
    }
    return free;
}

SparseMatrix free_operator(const Hierarchy& h, int k) {
    return principal_submatrix(k == h.num_levels() ? h.A_fine : h.level(k).A, free_positions(h, k));
}

std::size_t storage_bytes(const SparseMatrix& M) {
    return static_cast<std::size_t>(M.nonZeros()) * (sizeof(double) + sizeof(Index)) +
           static_cast<std::size_t>(M.outerSize() + 1) * sizeof(Index);
}

namespace {

/// The lower triangle of M (compressed), in M's storage: its entries moved down in place and the
/// pages past them returned to the system, so that M and its lower triangle are not held at once.
SparseMatrix lower_in_place(SparseMatrix&& M) {
    M.prune([](Index row, Index col, double) { return row >= col; });
    const auto size = static_cast<std::size_t>(M.nonZeros());
    const std::size_t allocated = M.data().allocatedSize();
    release_pages(M.valuePtr() + size, M.valuePtr() + allocated);
    release_pages(M.innerIndexPtr() + size, M.innerIndexPtr() + allocated);
    SparseMatrix lower;
    lower.swap(M);
    return lower;
}

}  // namespace

SparseMatrix symmetric_from_lower(const SparseMatrix& lower) {
    SparseMatrix full = lower.selfadjointView<Eigen::Lower>();
    full.makeCompressed();
    return full;
}

Index symmetric_nonzeros(const SparseMatrix& lower) {
    Index count = 0;
    for (Index j = 0; j < lower.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(lower, j); it; ++it)
            if (it.value() != 0.0) count += it.row() == j ? 1 : 2;
    return count;
}

namespace {

bool any_finite(const std::vector<double>& radius) {
    return std::any_of(radius.begin(), radius.end(), [](double r) { return !std::isinf(r); });
}

/// Some step is cell-wise: cell localization with a finite radius, or relaxed (whose infinite
/// radius is the cell-wise step spanning the level).
bool cell_wise(const Options& options) {
    return options.localization == Localization::Cell &&
           (options.relaxation > 0 || any_finite(options.radius));
}

/// The treatment keeps the fine operator the sum of the element matrices (no penalty), as the
/// parts of cell localization need.
bool element_operator(DirichletTreatment t) {
    return t == DirichletTreatment::Eliminate || t == DirichletTreatment::Constrain ||
           t == DirichletTreatment::Ignore;
}

}  // namespace

Options automatic_construction(Options options, const Eigen::Vector3i& cells, int dim,
                               bool cell_parts) {
    // Levels out of range are left to validate's message.
    if (!options.radius.empty() || options.levels < 2 || options.levels > kMaxLevels)
        return options;
    // DOFs of level k of q = options.levels (the fine grid: k = q), whose cells are halved q - k
    // times.
    const auto dofs_of = [&](int k) {
        Index dofs = dim;
        for (int d = 0; d < dim; ++d) dofs *= (cells[d] >> (options.levels - k)) + 1;
        return dofs;
    };
    const Index dofs = dofs_of(options.levels);
    const Options defaults;
    const bool localization_given =
        options.localization != defaults.localization || options.patch != defaults.patch ||
        options.patch_clip != defaults.patch_clip || options.relaxation != defaults.relaxation ||
        options.defect_tolerance != defaults.defect_tolerance;
    const bool localized = dim == 3 && cell_parts && dofs > kLocalizedMinDofs &&
                           !localization_given && element_operator(options.dirichlet) &&
                           options.refinement == Refinement::Linear &&
                           options.measurement == Measurement::Canonical &&
                           options.fine_operator == Operator::Stiffness;
    const double global = std::numeric_limits<double>::infinity();
    if (!localized) {
        options.radius = {global};
        return options;
    }
    options.localization = Localization::Cell;
    options.patch = kLocalizedPatch;
    options.relaxation = kLocalizedRelaxation;
    // Step k (radius[k - 1]) builds level k from level k + 1: the finest one (k = q - 1) in
    // rings, the coarser ones on their whole level where it is small, else in rings.
    options.radius.resize(static_cast<std::size_t>(options.levels - 1));
    for (int k = 1; k < options.levels - 1; ++k)
        options.radius[static_cast<std::size_t>(k - 1)] =
            dofs_of(k + 1) <= kWholeLevelMaxDofs ? global : kLocalizedCoarseRings;
    options.radius.back() = kLocalizedFineRings;
    return options;
}

void validate(const Options& options) {
    CG_VERIFY(options.levels >= 2 && options.levels <= kMaxLevels,
              "mra: levels = {} must be in 2..{}", options.levels, kMaxLevels);
    CG_VERIFY(
        options.radius.size() <= 1 || static_cast<int>(options.radius.size()) == options.levels - 1,
        "mra: radius has {} entries, expected 0 (automatic), 1 or levels - 1 = {}",
        options.radius.size(), options.levels - 1);
    for (const double r : options.radius)
        CG_VERIFY(r >= 1, "mra: radius {} must be at least 1 (or infinity)", r);
    CG_VERIFY(options.patch >= 1, "mra: patch = {} must be at least 1", options.patch);
    const bool by_cell = cell_wise(options);
    if (by_cell) {
        CG_VERIFY(options.patch == 1 || !options.patch_clip,
                  "mra: cell localization does not clip patches (patch_clip): each cell's share "
                  "of the right-hand side is solved on its whole patch");
        CG_VERIFY(element_operator(options.dirichlet),
                  "mra: cell localization needs the eliminate, constrain or ignore Dirichlet "
                  "treatment (the penalty is not part of the element matrices), got {}",
                  dirichlet_name(options.dirichlet));
        CG_VERIFY(options.fine_operator == Operator::Stiffness,
                  "mra: cell localization needs operator \"stiffness\" (its parts are the "
                  "element stiffness matrices, not those of a time step)");
    }
    CG_VERIFY(options.truncation >= 0 && options.truncation < 1,
              "mra: truncation = {} must be in [0, 1)", options.truncation);
    CG_VERIFY(options.penalty > 0, "mra: penalty = {} must be positive", options.penalty);
    CG_VERIFY(options.defect_tolerance >= 0 && std::isfinite(options.defect_tolerance),
              "mra: defect_tolerance = {} must be finite and at least 0 (0: fixed radius)",
              options.defect_tolerance);
    CG_VERIFY(std::isfinite(options.relaxation) && options.relaxation >= 0,
              "mra: relaxation = {} must be finite and at least 0 (0: exact measurements)",
              options.relaxation);
    CG_VERIFY(options.relaxation == 0 || options.localization == Localization::Cell,
              "mra: relaxation needs cell localization (its coarse coefficients are nodal values, "
              "those of the node-wise solves measurements)");
    CG_VERIFY(options.relaxation == 0 || options.refinement == Refinement::Linear ||
                  std::all_of(options.radius.begin(), options.radius.end(),
                              [](double r) { return std::isinf(r); }),
              "mra: relaxation with a finite radius needs the linear refinement (the Dirac "
              "refinement's canonical basis does not localize: 48x12x12 accordion, 3 levels, "
              "6 fine rings, energy error 0.97 against 0.014 with global solves)");
    CG_VERIFY(options.defect_tolerance == 0 || !by_cell,
              "mra: defect_tolerance needs node localization (cell localization has no "
              "per-node defect)");
    CG_VERIFY(options.max_radius >= 1, "mra: max_radius = {} must be at least 1",
              options.max_radius);
}

void validate_grid(const Options& options, const Eigen::Vector3i& cells, int dim) {
    const int factor = 1 << (options.levels - 1);
    for (int d = 0; d < dim; ++d)
        CG_VERIFY(cells[d] % factor == 0,
                  "mra: {} levels need cells per axis divisible by 2^{} = {}, but axis {} has {} "
                  "cells",
                  options.levels, options.levels - 1, factor, d, cells[d]);
}

namespace {

/// Mean edge length of a mesh's elements (every pair of an element's nodes for simplices, the
/// element's first dim edges otherwise: a scale, not a measurement).
double mean_edge_length(const mesh::Mesh& m) {
    const int n = static_cast<int>(m.elements.cols());
    const bool simplex = mesh::is_simplex(m.type);
    double sum = 0;
    Index count = 0;
    for (Index e = 0; e < m.num_elements(); ++e)
        for (int a = 0; a < (simplex ? n : 1); ++a)
            for (int b = a + 1; b < (simplex ? n : m.dim() + 1); ++b) {
                sum += (m.rest_positions.row(m.elements(e, a)) -
                        m.rest_positions.row(m.elements(e, b)))
                           .norm();
                ++count;
            }
    CG_VERIFY(count > 0 && sum > 0, "mra: a level mesh has no elements of positive size");
    return sum / static_cast<double>(count);
}

/// On level meshes, the support a localized row of C̃ of a coarse node with pivot `pivot` would
/// have (for the invariance correction's skip set, when the node's DOFs were eliminated and it
/// has no row): the finer nodes within `rings` rings of the pivot in `graph`, and those of every
/// wavelet (row of W, Wt = W^T) with a nonzero there. W's columns are the present DOFs
/// `dofs` (dim * node + d, sorted); `mark` (#nodes, all 0) is left so.
void mark_region_support(const detail::NodeGraph& graph, Index pivot, int rings,
                         const SparseMatrix& W, const SparseMatrix& Wt, const IndexVector& dofs,
                         int dim, std::vector<char>& mark, std::vector<char>& skip) {
    for (const Index j : detail::nodes_within(graph, pivot, rings, mark)) {
        skip[static_cast<std::size_t>(j)] = 1;
        const Index* first = std::lower_bound(dofs.data(), dofs.data() + dofs.size(), dim * j);
        for (Index l = first - dofs.data(); l < dofs.size() && dofs[l] / dim == j; ++l)
            for (SparseMatrix::InnerIterator w(W, l); w; ++w)
                for (SparseMatrix::InnerIterator it(Wt, w.row()); it; ++it)
                    skip[static_cast<std::size_t>(dofs[it.row()] / dim)] = 1;
    }
}

}  // namespace

void validate_level_mesh_options(const Options& options) {
    validate(options);
    const bool localized = any_finite(options.radius);
    CG_VERIFY(!cell_wise(options),
              "mra: on level meshes the localized solves are node-wise (localization \"node\", "
              "no relaxation); cell-wise and relaxed solves need grids");
    CG_VERIFY(!localized || options.patch == 1,
              "mra: on level meshes the localized solves take one region per node (patch 1), got "
              "patch {}",
              options.patch);
    CG_VERIFY(options.measurement == Measurement::Canonical,
              "mra: stiffness-weighted measurements need nested grids; on level meshes use "
              "canonical measurements");
}

void validate_level_meshes(const std::vector<mesh::Mesh>& coarser_levels,
                           const mesh::Mesh& fine_mesh, const Options& options) {
    const int dim = fine_mesh.dim();
    CG_VERIFY(static_cast<int>(coarser_levels.size()) + 1 == options.levels,
              "mra: {} coarser level meshes for levels = {} (the fine mesh is the last level)",
              coarser_levels.size(), options.levels);
    for (std::size_t k = 0; k < coarser_levels.size(); ++k) {
        const mesh::Mesh& m = coarser_levels[k];
        CG_VERIFY(m.dim() == dim, "mra: level mesh {} is {}D, the fine mesh {}D", k + 1, m.dim(),
                  dim);
        CG_VERIFY(mesh::is_simplex(m.type),
                  "mra: level mesh {} has {} elements; coarser levels must be simplicial "
                  "(triangles or tetrahedra)",
                  k + 1, mesh::element_name(m.type));
        const Index finer = k + 1 == coarser_levels.size() ? fine_mesh.num_nodes()
                                                           : coarser_levels[k + 1].num_nodes();
        CG_VERIFY(m.num_nodes() <= finer,
                  "mra: level mesh {} has {} nodes, more than the finer level's {}", k + 1,
                  m.num_nodes(), finer);
    }
    validate_level_mesh_options(options);
}

namespace {

/// build_hierarchy on the fine operator given either over all DOFs (K) or already without the
/// Dirichlet DOFs (A_free, read in place: Hierarchy::A_fine stays empty), on nested grids
/// (meshes null: `mesh` is a grid) or on level meshes (the coarser levels, coarsest first;
/// `mesh` is level q).
Hierarchy build(const mesh::Mesh& mesh, const std::vector<mesh::Mesh>* meshes,
                const SparseMatrix* K, const SparseMatrix* A_free,
                const std::vector<Index>& fixed_dofs, const Options& chosen,
                const material::ElementMaterials* materials) {
    const bool on_grid = meshes == nullptr;
    CG_VERIFY(!on_grid || mesh.grid.has_value(),
              "mra: the fine mesh must be a regular grid (mesh.grid), the material-adapted "
              "hierarchy is built on nested grids or given level meshes");
    const int dim = mesh.dim();
    const Options options =
        automatic_construction(chosen, on_grid ? mesh.grid->cells : Eigen::Vector3i::Zero(), dim,
                               on_grid && materials != nullptr);
    const int q = options.levels;
    validate(options);
    const Eigen::Vector3i cells = on_grid ? mesh.grid->cells : Eigen::Vector3i::Zero();
    if (on_grid) {
        validate_grid(options, cells, dim);
        CG_VERIFY(grid_nodes(cells, dim) == mesh.num_nodes(),
                  "mra: the mesh has {} nodes, its grid {}", mesh.num_nodes(),
                  grid_nodes(cells, dim));
    } else {
        validate_level_meshes(*meshes, mesh, options);
    }
    const Index n_dofs = mesh.num_dofs();
    const Index n_given = n_dofs - (K ? 0 : static_cast<Index>(fixed_dofs.size()));
    const SparseMatrix& given = K ? *K : *A_free;
    CG_VERIFY(given.rows() == n_given && given.cols() == n_given,
              "mra: the fine operator is {}x{}, the mesh has {} {}DOFs", given.rows(), given.cols(),
              n_given, K ? "" : "free ");
    // Checked once here: the localized solves factorize submatrices without input checks.
    for (Index j = 0; j < given.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(given, j); it; ++it)
            CG_VERIFY(std::isfinite(it.value()), "mra: K({}, {}) = {} is not finite", it.row(), j,
                      it.value());
    const bool by_cell = cell_wise(options);
    CG_VERIFY(!by_cell || materials != nullptr,
              "mra: cell localization needs the element materials (build_hierarchy argument)");

    Hierarchy h;
    h.dim = dim;
    h.options = options;
    h.fine_cells = cells;
    if (on_grid) {
        h.spacing = mesh.grid->spacing();
        h.origin = mesh.grid->min;
    } else {
        h.level_meshes = *meshes;
        h.fine_positions = mesh.rest_positions;
        for (const mesh::Mesh& m : *meshes) h.edge_lengths.push_back(mean_edge_length(m));
        h.edge_lengths.push_back(mean_edge_length(mesh));
    }

    // Level q: the fine operator with the Dirichlet DOFs eliminated or penalized (or, blind,
    // untouched).
    std::vector<char> fixed(static_cast<std::size_t>(n_dofs), 0);
    for (std::size_t k = 0; k < fixed_dofs.size(); ++k) {
        const Index d = fixed_dofs[k];
        CG_VERIFY(d >= 0 && d < n_dofs && (k == 0 || fixed_dofs[k - 1] < d),
                  "mra: Dirichlet DOFs must be sorted, unique and in 0..{}", n_dofs - 1);
        fixed[static_cast<std::size_t>(d)] = 1;
    }
    const bool blind = options.dirichlet == DirichletTreatment::Ignore;
    const bool penalize = options.dirichlet == DirichletTreatment::Penalty ||
                          options.dirichlet == DirichletTreatment::DiagonalPenalty;
    {
        const Phase phase("level " + std::to_string(q) + ": fine operator", &h.timings);
        const bool keep_fixed = penalize || blind;  // the fixed DOFs stay in A^q
        std::vector<Index> present;
        for (Index d = 0; d < n_dofs; ++d)
            if (keep_fixed || !fixed[static_cast<std::size_t>(d)]) present.push_back(d);
        h.fine_dofs =
            Eigen::Map<const IndexVector>(present.data(), static_cast<Index>(present.size()));
        if (blind)
            h.fine_fixed = Eigen::Map<const IndexVector>(fixed_dofs.data(),
                                                         static_cast<Index>(fixed_dofs.size()));
        CG_VERIFY(K || !keep_fixed,
                  "mra: the {} treatment keeps the Dirichlet DOFs; give the fine operator over all "
                  "DOFs",
                  dirichlet_name(options.dirichlet));
        if (keep_fixed) {
            h.A_fine = *K;
            if (penalize)
                for (const Index d : fixed_dofs)
                    h.A_fine.coeffRef(d, d) += options.dirichlet == DirichletTreatment::Penalty
                                                   ? options.penalty
                                                   : options.penalty * K->coeff(d, d);
            h.A_fine.makeCompressed();
        } else if (K) {
            h.A_fine = principal_submatrix(*K, h.fine_dofs);
        }
    }

    // Finest nodes with a fixed DOF, as the construction sees them (none when blind).
    std::vector<char> fixed_node(static_cast<std::size_t>(mesh.num_nodes()), 0);
    if (!blind)
        for (const Index d : fixed_dofs) fixed_node[static_cast<std::size_t>(d / dim)] = 1;

    SparseMatrix Phi = options.store_bases ? fine_selection(h) : SparseMatrix();
    // Cell localization: Φ^{k+1} on the present fine DOFs (Φ^q = I).
    SparseMatrix Phi_present;
    if (by_cell) {
        Phi_present.resize(h.fine_dofs.size(), h.fine_dofs.size());
        Phi_present.setIdentity();
    }

    h.levels.resize(static_cast<std::size_t>(q - 1));
    // Node positions of level k (#nodes by 3) in units of the largest fine spacing (grids) or the
    // finest mean edge length (level meshes), and the spacing of level k in that unit.
    const double unit = on_grid ? h.spacing.head(dim).maxCoeff() : h.edge_lengths.back();
    const auto positions_of = [&](int k) {
        if (!on_grid) {
            const Matrix& x = h.mesh_positions(k);
            Matrix out = Matrix::Zero(x.rows(), 3);
            out.leftCols(dim) = x / unit;
            return out;
        }
        const Eigen::Vector3i c = h.cells(k);
        const Eigen::Vector3d spacing = h.spacing * std::ldexp(1.0, q - k) / unit;
        Matrix out(grid_nodes(c, dim), 3);
        for (Index j = 0; j < out.rows(); ++j)
            out.row(j) =
                node_coordinates(j, c, dim).cast<double>().cwiseProduct(spacing).transpose();
        return out;
    };
    const auto spacing_of = [&](int k) {
        return on_grid ? std::ldexp(1.0, q - k)
                       : h.edge_lengths[static_cast<std::size_t>(k - 1)] / unit;
    };
    // Rigid motions on the present DOFs of the current finer level (invariance correction).
    Matrix positions = positions_of(q);
    Matrix rig_next = detail::rigid_modes(dim, positions, h.fine_dofs);
    // The finest node at the position of each node of the current finer level (through the
    // pivots: coincident nodes on grids).
    std::vector<Index> finest_next(static_cast<std::size_t>(mesh.num_nodes()));
    std::iota(finest_next.begin(), finest_next.end(), 0);

    // Radius of step k (building level k from k + 1).
    const auto radius_of = [&](int k) {
        return options.radius.size() == 1 ? options.radius[0]
                                          : options.radius[static_cast<std::size_t>(k - 1)];
    };
    // Step k is cell-wise: cell localization with a finite radius, or relaxed.
    const auto cell_wise_step = [&](int k) {
        return by_cell && (options.relaxation > 0 || !std::isinf(radius_of(k)));
    };
    const auto relaxed_step = [&](int k) { return cell_wise_step(k) && options.relaxation > 0; };
    // Rings of the finer level of step k (building level k) in a finite radius (an infinite
    // max_radius: 1e6); a radius on the coarser level's grid is scaled by the ratio of the
    // levels' spacings (2 on grids, the ratio of mean edge lengths on level meshes).
    const auto to_rings = [&](double radius, int k) {
        const int rings = static_cast<int>(std::min(std::floor(radius), 1e6));
        if (options.radius_grid == RadiusGrid::Fine) return rings;
        if (on_grid) return 2 * rings;
        const double ratio = spacing_of(k) / spacing_of(k + 1);
        return static_cast<int>(std::min(std::round(rings * ratio), 1e6));
    };
    // A^{k+1} as the next step reads it: the fine operator, then the level above, with both
    // triangles held only while a step that needs them runs (Level::A keeps the lower triangle,
    // which a relaxed step reads in place).
    const SparseMatrix* A_next = K ? &h.A_fine : A_free;
    detail::Stored A_next_stored = detail::Stored::Both;
    SparseMatrix A_full;
    bool runs_pending = false;  // C̃^{q-1} is still Phi_present, not yet L.C_adapted
    const auto store_pending_runs = [&] {
        h.levels[static_cast<std::size_t>(q - 2)].C_adapted = RunMatrix(std::move(Phi_present));
        runs_pending = false;
    };
    IndexVector dofs_next = h.fine_dofs;
    for (int k = q - 1; k >= 1; --k) {
        const auto t0 = std::chrono::steady_clock::now();
        const std::string tag = "level " + std::to_string(k) + ": ";
        Level& L = h.levels[static_cast<std::size_t>(k - 1)];
        L.k = k;
        L.cells = h.cells(k);
        const Eigen::Vector3i fine_cells = h.cells(k + 1);
        const Index fine_count = static_cast<Index>(positions.rows());
        L.radius = radius_of(k);
        detail::StepGeometry g;
        g.dim = dim;
        g.fine_cells = fine_cells;
        g.coarse_cells = L.cells;
        g.fine_spacing = h.spacing * std::ldexp(1.0, q - (k + 1));
        g.fine_dofs = dofs_next;
        // The node of level k+1 each node of level k refines to or is identified with.
        std::vector<Index> pivots;
        detail::NodeGraph finer_graph;  // of level k+1, on level meshes
        {
            const Phase phase(tag + "canonical", &h.timings);
            RefinementOperators ops;
            if (on_grid) {
                pivots = coincident_nodes(L.cells, dim);
                SparseMatrix C_node = canonical_refinement(L.cells, dim, options.refinement);
                if (k == q - 1 && options.measurement == Measurement::Stiffness) {
                    CG_VERIFY(K,
                              "mra: stiffness-weighted measurements need the fine operator over "
                              "all DOFs");
                    C_node = weighted_refinement(std::move(C_node), pivots,
                                                 stiffness_weights(*K, mesh.elements, dim));
                }
                ops = refinement_operators(C_node, pivots, dim, dofs_next,
                                           options.dirichlet != DirichletTreatment::Eliminate);
            } else {
                const mesh::Mesh& coarse = (*meshes)[static_cast<std::size_t>(k - 1)];
                const mesh::Mesh& finer =
                    k + 1 == q ? mesh : (*meshes)[static_cast<std::size_t>(k)];
                pivots = pivot_nodes(coarse.rest_positions, finer.rest_positions);
                finer_graph = detail::NodeGraph(finer.elements, finer.num_nodes());
                g.fine_graph = &finer_graph;
                g.pivots = pivots;
                ops = local_refinement_operators(
                    options.refinement == Refinement::Linear
                        ? linear_refinement(coarse, finer.rest_positions)
                        : selection_refinement(pivots, finer.num_nodes()),
                    pivots, finer.elements, dim, dofs_next,
                    options.dirichlet != DirichletTreatment::Eliminate);
            }
            L.dofs = std::move(ops.coarse_dofs);
            L.dropped_dofs = std::move(ops.dropped_dofs);
            L.C = std::move(ops.C);
            L.C_dagger = std::move(ops.C_dagger);
            L.W = std::move(ops.W);
        }
        CG_VERIFY(L.dofs.size() > 0, "mra: level {} has no degree of freedom left", k);
        g.coarse_dofs = L.dofs;
        const double rotation_scale = spacing_of(k + 1);
        // The relaxed cell-wise solves start from the canonical basis C^k Φ^{k+1} (its
        // coefficients are nodal values), the others from a left inverse of C^{k,T}; a relaxed
        // step on the whole level is taken in the basis of its measurements G.
        const bool step_by_cell = cell_wise_step(k);
        const bool relaxed = relaxed_step(k);
        Matrix rig_measured;  // G Rig^{k+1}, after a relaxed step on the whole level
        // Rig^k, the coefficients of the rigid motions at level k (invariance correction): their
        // measurements C^k Rig^{k+1} (C^k C̃^{k,T} = I) or G Rig^{k+1}, or with localized relaxed
        // solves their values at the nodes of level k (C^{k,T} interpolates them exactly).
        const auto rigid_coefficients = [&] {
            return rig_measured.size() > 0 ? rig_measured
                   : relaxed               ? detail::rigid_modes(dim, positions_of(k), L.dofs)
                                           : Matrix(L.C * rig_next);
        };
        if (step_by_cell && !relaxed && options.refinement == Refinement::Linear) {
            const Phase phase(tag + "rigid left inverse", &h.timings);
            L.C_dagger =
                detail::rigid_left_inverse(L.C, L.C_dagger, g, rig_next, positions, rotation_scale);
        }
        const SparseMatrix& A = *A_next;
        SparseMatrix R;
        if (!relaxed) {  // the relaxed solves do not read B^k: it is made after them, below
            const Phase phase(tag + "B", &h.timings);
            L.B =
                detail::symmetrized(detail::triple_product(L.W, A, SparseMatrix(L.W.transpose())));
            if (!step_by_cell)
                R = detail::triple_product(L.W, A, SparseMatrix(L.C_dagger.transpose()));
        }
        // An infinite radius of a relaxed step: rings that span the level (one factorization).
        const int rings = !std::isinf(L.radius) ? to_rings(L.radius, k)
                          : relaxed ? *std::max_element(fine_cells.data(), fine_cells.data() + dim)
                                    : 0;
        // Φ^k on the present fine DOFs for the next step if it is cell-localized (Φ^q = I: C̃
        // itself); none after the last, where a product would copy C̃ at the build's peak.
        const bool next_by_cell = k > 1 && cell_wise_step(k - 1);
        const bool phi_read_after = next_by_cell && k < q - 1;  // by Φ^k = C̃^k Φ^{k+1}
        // How far Φ^{k+1} reaches from its nodes, in level-(k+1) cells (the invariance's reach),
        // before the step may store it as runs.
        int phi_reach = 0;
        if (step_by_cell && options.invariance) {
            const Phase phase(tag + "invariance", &h.timings);
            phi_reach = basis_reach(h, Phi_present, k + 1);
        }
        SparseMatrix Ct;  // C̃^k while it is built and used here; kept as L.C_adapted (runs)
        if (!step_by_cell && std::isinf(L.radius)) {
            const Phase phase(tag + "Z and C adapted (B factorize + solves)", &h.timings);
            Ct = detail::global_adapted_refinement(L.B, R, L.C_dagger, L.W, options.truncation, g);
        } else if (step_by_cell) {
            const std::vector<detail::CellStiffness> parts = detail::cell_stiffness(
                mesh, *materials, h.fine_dofs, L.cells, options.patch, options.formulation);
            if (relaxed) {
                const Phase phase(tag + "C adapted (relaxed cell-localized solves)", &h.timings);
                // The penalty measures the correctors' fine functions: C^k C^{k+1} .. C^{q-1}
                // Φ^{k+1,T} (C^k at the finest step, where Φ^q = I), formed as the transpose of
                // Φ^{k+1} (C^k .. C^{q-1})^T so that Φ^{k+1} is not copied.
                SparseMatrix composed = L.C;
                for (int l = k + 1; l < q; ++l) composed = product(composed, h.level(l).C);
                if (k < q - 1)
                    composed = product(Phi_present, SparseMatrix(composed.transpose())).transpose();
                // A step whose regions span the level reads Φ^{k+1} no further: C̃^{q-1}, if
                // that is what it is, is stored as runs before the step's solves instead of
                // after the step (80x20x20 accordion, 3 levels: peak 13.7 -> 11.0 GB).
                if (detail::regions_span_level(parts, rings, g)) {
                    rig_measured = composed * rig_next;
                    if (runs_pending && !phi_read_after) {
                        store_pending_runs();
                        Phi_present = SparseMatrix();
                    }
                }
                Ct = detail::relaxed_adapted_refinement(A, L.C, composed, Phi_present, parts, g,
                                                        rings, options.relaxation, A_next_stored);
            } else {
                SparseMatrix Z;
                {
                    const Phase phase(tag + "Z (cell-localized solves)", &h.timings);
                    Z = detail::cell_localized_z(L.B, L.W, product(L.W, Phi_present),
                                                 product(L.C_dagger, Phi_present), parts, g, rings);
                }
                const Phase phase(tag + "C adapted", &h.timings);
                Ct = L.C_dagger + product(Z, L.W);
            }
            Ct.makeCompressed();
            // C̃^{q-1}, read by the solves, is stored as runs once they are done, unless Φ^k is
            // formed from it, before A^k and B^k are formed beside it (the 64^3 checker, 3
            // levels: 7.3 GB as CSC, about 4.9 GB as runs).
            if (runs_pending && !phi_read_after) store_pending_runs();
        } else {
            const Phase phase(tag + "C adapted (localized solves)", &h.timings);
            detail::LocalizationRings lr;
            lr.start = rings;
            lr.max = std::max(rings, to_rings(options.max_radius, k));
            lr.defect_tolerance = options.defect_tolerance;
            detail::LocalizedRefinement lz = detail::localized_refinement(
                L.B, R, L.C_dagger, L.W, g, lr, options.patch, options.patch_clip);
            Ct = std::move(lz.Ct);
            L.region_rings = std::move(lz.rings);
        }
        R = SparseMatrix();
        if (!relaxed) {  // a relaxed step made B^k as it is kept
            L.B = options.store_wavelet_stiffness ? SparseMatrix(L.B.triangularView<Eigen::Lower>())
                                                  : SparseMatrix();
            L.B.makeCompressed();
        }

        // Coarse nodes on the Dirichlet boundary: at the position of a fixed finest node (their
        // pivots' finest node); blind, the DOFs held at zero when this level is solved.
        const Index coarse_nodes = static_cast<Index>(pivots.size());
        std::vector<Index> finest(static_cast<std::size_t>(coarse_nodes));
        for (Index i = 0; i < coarse_nodes; ++i) finest[i] = finest_next[pivots[i]];
        L.dirichlet_nodes.assign(static_cast<std::size_t>(coarse_nodes), 0);
        {
            for (Index i = 0; i < coarse_nodes; ++i)
                L.dirichlet_nodes[static_cast<std::size_t>(i)] =
                    fixed_node[static_cast<std::size_t>(finest[i])];
            std::vector<Index> held;
            for (Index r = 0; blind && r < L.dofs.size(); ++r)
                if (fixed[static_cast<std::size_t>(dim * finest[L.dofs[r] / dim] +
                                                   L.dofs[r] % dim)])
                    held.push_back(r);
            L.fixed = Eigen::Map<const IndexVector>(held.data(), static_cast<Index>(held.size()));
        }

        if (options.truncation > 0) {
            const Phase phase(tag + "truncation", &h.timings);
            detail::truncate_rows(Ct, options.truncation, dofs_next, dim);
        }
        if (options.invariance) {
            const Phase phase(tag + "invariance", &h.timings);
            // Skip fine nodes with an absent DOF, and (Sec. 3.5) those in the support of a
            // coarse node on the Dirichlet boundary: the columns of C̃ with a nonzero in a row of
            // such a node (the paper's rule, read off the pattern after the solves and the
            // truncation). A boundary node whose DOFs were eliminated has no row: its support is
            // taken as geometric, within `reach` rings (the region R_i, plus one ring for the
            // wavelets of the linear refinement; every node for global solves); on level meshes
            // the region's nodes and those of its wavelets (mark_region_support).
            std::vector<char> skip(static_cast<std::size_t>(fine_count), 0);
            std::vector<int> present_count(static_cast<std::size_t>(fine_count), 0);
            for (Index l = 0; l < dofs_next.size(); ++l)
                ++present_count[static_cast<std::size_t>(dofs_next[l] / dim)];
            for (Index j = 0; j < fine_count; ++j)
                if (present_count[static_cast<std::size_t>(j)] != dim)
                    skip[static_cast<std::size_t>(j)] = 1;
            for (Index l = 0; l < Ct.outerSize(); ++l)
                for (SparseMatrix::InnerIterator it(Ct, l); it; ++it)
                    if (L.dirichlet_nodes[static_cast<std::size_t>(L.dofs[it.row()] / dim)])
                        skip[static_cast<std::size_t>(dofs_next[l] / dim)] = 1;
            std::vector<int> kept_count(static_cast<std::size_t>(coarse_nodes), 0);
            for (Index r = 0; r < L.dofs.size(); ++r)
                ++kept_count[static_cast<std::size_t>(L.dofs[r] / dim)];
            bool eliminated_boundary = false;  // a Dirichlet node of level k lost a DOF
            for (Index i = 0; i < coarse_nodes; ++i)
                eliminated_boundary =
                    eliminated_boundary || (L.dirichlet_nodes[static_cast<std::size_t>(i)] &&
                                            kept_count[static_cast<std::size_t>(i)] != dim);
            if (std::isinf(L.radius) && eliminated_boundary)  // its support: every node
                std::fill(skip.begin(), skip.end(), 1);
            // Cell localization: node i gets rows from the cells T that (C^† Φ^{k+1})[i, :]
            // touches, within phi_reach (+1 for the linear C^†) of node i, and a cell's region
            // reaches `rings` beyond the cell's patch (rings / kRegionSnap more where it is
            // extended to the grid's boundary), 2 patch rings beyond its nodes.
            const int linear = options.refinement == Refinement::Linear ? 1 : 0;
            const int max_region_rings =
                L.region_rings.empty()
                    ? rings
                    : *std::max_element(L.region_rings.begin(), L.region_rings.end());
            const int reach = step_by_cell
                                  ? rings + rings / detail::kRegionSnap + 2 * options.patch +
                                        phi_reach + 2 * linear
                                  : max_region_rings +
                                        (options.patch_clip ? 0 : 2 * (options.patch - 1)) + linear;
            const Eigen::Vector3i nf = node_counts(fine_cells, dim);
            std::vector<char> mark(on_grid ? 0 : static_cast<std::size_t>(fine_count), 0);
            SparseMatrix Wt;  // W by rows, on level meshes
            for (Index i = 0; i < coarse_nodes && !std::isinf(L.radius); ++i) {
                if (!L.dirichlet_nodes[static_cast<std::size_t>(i)] ||
                    kept_count[static_cast<std::size_t>(i)] == dim)
                    continue;
                if (!on_grid) {
                    if (Wt.size() == 0) Wt = L.W.transpose();
                    mark_region_support(finer_graph, pivots[i], max_region_rings, L.W, Wt,
                                        dofs_next, dim, mark, skip);
                    continue;
                }
                const Eigen::Vector3i c = 2 * node_coordinates(i, L.cells, dim);
                const Eigen::Vector3i lo = (c.array() - reach).max(0);
                const Eigen::Vector3i hi = (c.array() + reach).min(nf.array() - 1);
                for (int z = lo[2]; z <= hi[2]; ++z)
                    for (int y = lo[1]; y <= hi[1]; ++y)
                        for (int x = lo[0]; x <= hi[0]; ++x)
                            skip[static_cast<std::size_t>(x + nf[0] * (y + nf[1] * z))] = 1;
            }
            const Matrix rig = rigid_coefficients();
            L.invariance_applied =
                detail::correct_invariance(Ct, g, skip, rig, rig_next, positions, rotation_scale);
            rig_next = rig;
        } else {
            L.invariance_applied.assign(static_cast<std::size_t>(fine_count), 0);
            rig_next = rigid_coefficients();
        }
        {
            const Phase phase(tag + "A", &h.timings);
            L.A = detail::congruence(Ct, A, dof_groups(h, L), A_next_stored);
        }
        // A^{k+1} read with both triangles (not the fine operator) is kept as its lower triangle
        // from here on, in the storage of that copy, before C̃^{q-1} may be stored as runs below,
        // beside its sparse form (48^3 checker, 3 levels, coarse step in rings: the build's peak
        // 23.5 GB with both held there).
        if (k + 1 < q && A_next_stored == detail::Stored::Both) {
            h.levels[static_cast<std::size_t>(k)].A = lower_in_place(std::move(A_full));
            A_full = SparseMatrix();
        }
        if (relaxed && options.store_wavelet_stiffness) {
            // The relaxed solves do not read B^k, which is made as it is kept (its lower
            // triangle) after them, through which it was held (the 56^3 checker, 3 levels, 4
            // fine rings: the coarse step's peak 17.5 -> 12.6 GB), from A^{k+1} as the step read
            // it (the 64^3 checker, 3 levels: B^1's peak 21.2 GB beside A^2 with both triangles).
            const Phase phase(tag + "B", &h.timings);
            L.B = detail::congruence(L.W, A, detail::consecutive_groups(L.W.rows(), 8 * dim),
                                     A_next_stored);
        }
        if (options.store_bases) {
            const Phase phase(tag + "Phi Psi", &h.timings);
            L.Psi = product(L.W, Phi);
            L.Phi = product(Ct, Phi);
            Phi = L.Phi;
        }
        SparseMatrix Phi_next;
        if (phi_read_after) Phi_next = product(Ct, Phi_present);
        if (runs_pending) store_pending_runs();
        if (next_by_cell && k == q - 1) {
            // Φ^{q-1} = C̃^{q-1}: kept as it is while the next step reads it, and stored as runs
            // after (both at once held another copy of C̃ at the next step's peak: 80x20x20
            // accordion, 3 levels, 17.5 GB).
            Phi_present = std::move(Ct);
            runs_pending = true;
        } else {
            L.C_adapted = RunMatrix(std::move(Ct));
            Phi_present = std::move(Phi_next);
        }
        Ct = SparseMatrix();
        L.build_seconds = seconds_since(t0);
        // A^k as the next step reads it: a relaxed step its lower triangle in place (the 64^3
        // checker's coarse step: peak 19.1 -> 16.3 GB), the others a copy with both triangles,
        // alone, whose lower triangle is stored back after the step's Galerkin product.
        if (k > 1 && relaxed_step(k - 1)) {
            A_next = &L.A;
            A_next_stored = detail::Stored::Lower;
        } else if (k > 1) {
            A_full = symmetric_from_lower(L.A);
            L.A = SparseMatrix();
            A_next = &A_full;
            A_next_stored = detail::Stored::Both;
        }
        dofs_next = L.dofs;
        finest_next = std::move(finest);
        positions = positions_of(k);
    }
    return h;
}

}  // namespace

Hierarchy build_hierarchy(const mesh::Mesh& mesh, const SparseMatrix& K,
                          const std::vector<Index>& fixed_dofs, const Options& options,
                          const material::ElementMaterials* materials) {
    return build(mesh, nullptr, &K, nullptr, fixed_dofs, options, materials);
}

Hierarchy build_hierarchy_free(const mesh::Mesh& mesh, const SparseMatrix& A_free,
                               const std::vector<Index>& fixed_dofs, const Options& options,
                               const material::ElementMaterials* materials) {
    return build(mesh, nullptr, nullptr, &A_free, fixed_dofs, options, materials);
}

Hierarchy build_hierarchy(const std::vector<mesh::Mesh>& coarser_levels,
                          const mesh::Mesh& fine_mesh, const SparseMatrix& K,
                          const std::vector<Index>& fixed_dofs, const Options& options) {
    CG_VERIFY(!coarser_levels.empty(), "mra: no coarser level meshes");
    return build(fine_mesh, &coarser_levels, &K, nullptr, fixed_dofs, options, nullptr);
}

Hierarchy build_hierarchy_free(const std::vector<mesh::Mesh>& coarser_levels,
                               const mesh::Mesh& fine_mesh, const SparseMatrix& A_free,
                               const std::vector<Index>& fixed_dofs, const Options& options) {
    CG_VERIFY(!coarser_levels.empty(), "mra: no coarser level meshes");
    return build(fine_mesh, &coarser_levels, nullptr, &A_free, fixed_dofs, options, nullptr);
}

SparseMatrix basis(const Hierarchy& h, int k) {
    const int q = h.num_levels();
    CG_VERIFY(k >= 1 && k <= q, "mra: level {} out of range 1..{}", k, q);
    if (k < q && h.options.store_bases) return h.level(k).Phi;
    SparseMatrix Phi = fine_selection(h);
    for (int l = q - 1; l >= k; --l) Phi = product(h.level(l).C_adapted.sparse(), Phi);
    return Phi;
}

Vector reconstruct(const Hierarchy& h, const Vector& u_k, int k) {
    const int q = h.num_levels();
    CG_VERIFY(k >= 1 && k <= q, "mra: level {} out of range 1..{}", k, q);
    const Index n = k == q ? h.fine_dofs.size() : h.level(k).dofs.size();
    CG_VERIFY(u_k.size() == n, "mra: {} coefficients for the {} DOFs of level {}", u_k.size(), n,
              k);
    Vector u = u_k;
    for (int l = k; l < q; ++l) u = h.level(l).C_adapted.transpose_times(u);
    Vector out = Vector::Zero(h.fine_grid_dofs());
    for (Index i = 0; i < h.fine_dofs.size(); ++i) out[h.fine_dofs[i]] = u[i];
    return out;
}

SparseMatrix galerkin_operator(const Hierarchy& h, const SparseMatrix& X, int k) {
    return symmetric_from_lower(galerkin_operator_lower(h, X, k));
}

SparseMatrix galerkin_operator_lower(const Hierarchy& h, const SparseMatrix& X, int k) {
    const Index n = h.fine_grid_dofs();
    CG_VERIFY(X.rows() == n && X.cols() == n, "mra: a {}x{} operator on {} fine grid DOFs",
              X.rows(), X.cols(), n);
    CG_VERIFY(k >= 1 && k <= h.num_levels(), "mra: level {} out of range 1..{}", k, h.num_levels());
    SparseMatrix S(h.fine_dofs.size(), n);  // selects the hierarchy's fine DOFs
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index i = 0; i < h.fine_dofs.size(); ++i) t.emplace_back(i, h.fine_dofs[i], 1.0);
    S.setFromTriplets(t.begin(), t.end());
    SparseMatrix Y = S * X * SparseMatrix(S.transpose());
    for (int l = h.num_levels() - 1; l >= k; --l) {  // the products that make A^l
        const Level& L = h.level(l);
        Y = detail::congruence(L.C_adapted.sparse(), Y, dof_groups(h, L));  // its lower triangle
        if (l > k) Y = symmetric_from_lower(Y);
    }
    if (k == h.num_levels()) Y = Y.triangularView<Eigen::Lower>();
    Y.makeCompressed();
    return Y;
}

Vector coarse_grain(const Hierarchy& h, const Vector& g_fine, int k) {
    CG_VERIFY(g_fine.size() == h.fine_grid_dofs(),
              "mra: the fine vector has {} entries, expected {}", g_fine.size(),
              h.fine_grid_dofs());
    CG_VERIFY(k >= 1 && k <= h.num_levels(), "mra: level {} out of range 1..{}", k, h.num_levels());
    Vector g(h.fine_dofs.size());
    for (Index i = 0; i < h.fine_dofs.size(); ++i) g[i] = g_fine[h.fine_dofs[i]];
    for (int l = h.num_levels() - 1; l >= k; --l) g = h.level(l).C_adapted * g;
    return g;
}

}  // namespace coarsegrain::mra
