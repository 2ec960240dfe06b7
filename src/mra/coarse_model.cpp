#include "coarsegrain/mra/coarse_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <memory>
#include <numeric>

#include "coarsegrain/common/allocator.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mra/cell_tensors.hpp"
#include "detail.hpp"

namespace coarsegrain::mra {

using detail::cell_count;

namespace {

using Triplet = Eigen::Triplet<double, Index>;

/// Nodes of level k: of its grid, or of its mesh.
Index level_nodes(const Hierarchy& h, int k) {
    return h.on_grid() ? grid_nodes(h.cells(k), h.dim)
                       : static_cast<Index>(h.mesh_positions(k).rows());
}

/// Elements of level k < q: cells of its grid, or elements of its mesh.
Index level_elements(const Hierarchy& h, int k) {
    return h.on_grid() ? cell_count(h.cells(k), h.dim)
                       : h.level_meshes[static_cast<std::size_t>(k - 1)].num_elements();
}

/// Volume-weighted mean of the fine element stress of u over each coarsest cell (Mandel rows).
Matrix cell_mean_stress(const scene::FineModel& fine, const Vector& u,
                        const Eigen::Vector3i& coarse_cells) {
    const int dim = fine.mesh.dim();
    const mesh::GridInfo& g = *fine.mesh.grid;
    const Matrix stress = fem::element_stress(fine.mesh, fine.materials, u).stress;
    const Index per_cell = fine.mesh.num_elements() / cell_count(g.cells, dim);
    Matrix sum = Matrix::Zero(cell_count(coarse_cells, dim), stress.cols());
    Vector volume = Vector::Zero(sum.rows());
    for (Index e = 0; e < fine.mesh.num_elements(); ++e) {
        const Index fc = e / per_cell;
        Index c = 0, stride = 1;
        Index rest = fc;
        for (int d = 0; d < dim; ++d) {
            const Index i = rest % g.cells[d];
            rest /= g.cells[d];
            c += stride * (i / (g.cells[d] / coarse_cells[d]));
            stride *= coarse_cells[d];
        }
        const double v = mesh::element_measure(fine.mesh, e);
        sum.row(c) += v * stress.row(e);
        volume[c] += v;
    }
    return volume.cwiseInverse().asDiagonal() * sum;
}

/// Sec. 5.6 outputs of compare_levels: coarsest_cells.vtu, its table and `report`.
void add_coarsest_cells(const Hierarchy& h, const scene::FineModel& fine, const Vector& u1,
                        const Vector& u, bool enabled, CoarsestCellsReport& report,
                        coarsen::FineComparison& c) {
    const int dim = h.dim;
    const Eigen::Vector3i cells = h.level(1).cells;
    const Index nc = level_elements(h, 1);
    report.cells = nc;
    if (!enabled || nc > kCellTensorsMaxCells || !h.on_grid()) {
        report.skipped = !enabled ? std::string("coarse.cell_tensors is false")
                         : h.on_grid()
                             ? fmt::format("{} coarsest cells > {}", nc, kCellTensorsMaxCells)
                             : std::string(
                                   "the coarsest level is a mesh (cell tensors are "
                                   "computed on coarsest grid cells)");
        return;
    }
    const std::vector<CellTensor> tensors =
        coarsest_cell_tensors(fine.mesh, fine.materials, cells, h.options);
    const Matrix D = youngs_directions(dim);
    const int n = mandel_size(dim);
    Matrix C_voigt(nc, n * n), E_dir(nc, D.rows()), E_axes(nc, dim);
    for (Index i = 0; i < nc; ++i) {
        const Matrix& C = tensors[static_cast<std::size_t>(i)].C;
        const Matrix Cv = material::mandel_to_voigt(C);
        C_voigt.row(i) = Eigen::Map<const Vector>(Cv.data(), n * n).transpose();
        for (Index j = 0; j < D.rows(); ++j)
            E_dir(i, j) = material::directional_young(C, D.row(j).transpose());
        CellYoungs& y = report.per_cell.emplace_back();
        for (int a = 0; a < dim; ++a) {
            E_axes(i, a) = material::directional_young(C, Eigen::VectorXd::Unit(dim, a));
            y.E_axes.push_back(E_axes(i, a));
        }
        y.E_min = E_dir.row(i).minCoeff();
        y.E_max = E_dir.row(i).maxCoeff();
    }
    coarsen::VtuOutput out;
    out.file = "coarsest_cells.vtu";
    Eigen::VectorXi grid_cells(dim);
    for (int d = 0; d < dim; ++d) grid_cells[d] = cells[d];
    out.mesh =
        mesh::make_grid(dim == 2 ? mesh::ElementType::Quad4 : mesh::ElementType::Hex8,
                        fine.mesh.grid->min.head(dim), fine.mesh.grid->max.head(dim), grid_cells);
    out.fields.add_cell("C_eff", C_voigt);
    const char* axis_names[] = {"E_x", "E_y", "E_z"};
    for (int a = 0; a < dim; ++a) out.fields.add_cell_scalar(axis_names[a], E_axes.col(a));
    out.fields.add_cell_scalar("E_min", E_dir.rowwise().minCoeff());
    out.fields.add_cell_scalar("E_max", E_dir.rowwise().maxCoeff());
    out.fields.add_cell("E_directions", E_dir);
    out.fields.add_cell("stress_coarse",
                        fem::mandel_to_physical(cell_mean_stress(fine, u1, cells)));
    out.fields.add_cell("stress_fine", fem::mandel_to_physical(cell_mean_stress(fine, u, cells)));
    c.outputs.push_back(std::move(out));
    io::Table youngs{"coarsest_youngs",
                     dim == 2 ? std::vector<std::string>{"cell", "dx", "dy", "E"}
                              : std::vector<std::string>{"cell", "dx", "dy", "dz", "E"},
                     Matrix(nc * D.rows(), dim + 2)};
    for (Index i = 0; i < nc; ++i)
        for (Index j = 0; j < D.rows(); ++j) {
            const Index row = i * D.rows() + j;
            youngs.values(row, 0) = static_cast<double>(i);
            youngs.values.row(row).segment(1, dim) = D.row(j).head(dim);
            youngs.values(row, dim + 1) = E_dir(i, j);
        }
    c.tables.push_back(std::move(youngs));
    report.vtu = "coarsest_cells.vtu";
    report.E_min = E_dir.minCoeff();
    report.E_max = E_dir.maxCoeff();
}

/// Fig. 16 (2D): the table "coarsest_stress", one row per fine element with its centroid, its
/// area, its Young's modulus E and the physical stress (xx, yy, xy) and von Mises stress of the
/// fine solve u and of the coarsest level's reconstruction u1 on the fine grid.
void add_stress_map(const scene::FineModel& fine, const Vector& u1, const Vector& u,
                    coarsen::FineComparison& c) {
    const fem::ElementStress s = fem::element_stress(fine.mesh, fine.materials, u);
    const fem::ElementStress s1 = fem::element_stress(fine.mesh, fine.materials, u1);
    const Matrix p = fem::mandel_to_physical(s.stress);
    const Matrix p1 = fem::mandel_to_physical(s1.stress);
    const Matrix x = mesh::element_centroids(fine.mesh);
    io::Table t{"coarsest_stress",
                {"x", "y", "area", "E", "fine_xx", "fine_yy", "fine_xy", "fine_von_mises",
                 "coarse_xx", "coarse_yy", "coarse_xy", "coarse_von_mises"},
                Matrix(fine.mesh.num_elements(), 12)};
    for (Index e = 0; e < fine.mesh.num_elements(); ++e)
        t.values.row(e) << x(e, 0), x(e, 1), mesh::element_measure(fine.mesh, e),
            fine.materials.of(e).E, p(e, 0), p(e, 1), p(e, 2), s.von_mises[e], p1(e, 0), p1(e, 1),
            p1(e, 2), s1.von_mises[e];
    c.tables.push_back(std::move(t));
}

template <class M>
double density(const M& m, std::int64_t nonzeros) {
    const double size = static_cast<double>(m.rows()) * static_cast<double>(m.cols());
    return size > 0 ? static_cast<double>(nonzeros) / size : 0.0;
}

/// P A P^T of the symmetric A whose lower triangle is `lower`, for P(dofs[i], i) = s[i] (n rows,
/// dofs increasing), with both triangles stored, formed in one pass: A^1 can be dense (10,125
/// rows for the touching cubes at 56^3), and the sparse products P A P^T held three copies of it.
/// The coarse model's K and Galerkin mass.
SparseMatrix embedded_symmetric(const SparseMatrix& lower, const IndexVector& dofs, const Vector& s,
                                Index n) {
    const Index m = lower.cols();
    CG_VERIFY(lower.rows() == m && dofs.size() == m && s.size() == m &&
                  (m == 0 || (dofs[0] >= 0 && dofs[m - 1] < n)) &&
                  std::is_sorted(dofs.begin(), dofs.end()),
              "mra: a {}x{} operator embedded by {} increasing DOFs of {}", lower.rows(), m,
              dofs.size(), n);
    std::vector<Index> count(static_cast<std::size_t>(m), 0);  // entries of the whole column
    for (Index j = 0; j < m; ++j)
        for (SparseMatrix::InnerIterator it(lower, j); it; ++it) {
            ++count[static_cast<std::size_t>(j)];
            if (it.row() != j) ++count[static_cast<std::size_t>(it.row())];
        }
    SparseMatrix K(n, n);
    Index* outer = K.outerIndexPtr();
    std::fill(outer, outer + n + 1, 0);
    for (Index j = 0; j < m; ++j) outer[dofs[j] + 1] = count[static_cast<std::size_t>(j)];
    std::partial_sum(outer, outer + n + 1, outer);
    K.resizeNonZeros(outer[n]);
    // Column j receives its entries above the diagonal from the columns before it, in their
    // order, then its own lower part: rows in increasing order, as dofs keeps it.
    std::vector<Index> next(static_cast<std::size_t>(m));
    for (Index j = 0; j < m; ++j) next[static_cast<std::size_t>(j)] = outer[dofs[j]];
    const auto put = [&](Index row, Index col, double v) {
        const Index at = next[static_cast<std::size_t>(col)]++;
        K.innerIndexPtr()[at] = dofs[row];
        K.valuePtr()[at] = v * (s[row] * s[col]);  // the same product for both triangles
    };
    for (Index j = 0; j < m; ++j)
        for (SparseMatrix::InnerIterator it(lower, j); it; ++it) {
            put(it.row(), j, it.value());
            if (it.row() != j) put(j, it.row(), it.value());
        }
    return K;
}

}  // namespace

coarsen::CoarseModel coarse_model(const std::shared_ptr<const Hierarchy>& hierarchy,
                                  const Vector& f_fine, const SparseMatrix* K_fine) {
    const Hierarchy& h = *hierarchy;
    const Level& L1 = h.level(1);
    const int dim = h.dim;
    const Index nodes = level_nodes(h, 1);
    const Index n = dim * nodes;
    coarsen::CoarseModel m;
    m.method = "mra";
    m.nodes = nodes;
    m.elements = level_elements(h, 1);

    // Coefficients of level 1 are the measurements C^1 ... C^{q-1} u of a fine displacement u;
    // a translation t measures s t with s the row sums of that chain (1 for Dirac, 4^(q-1) in
    // the interior of a 2D grid for the linear refinement). Coarse DOFs u_c = v / s make the
    // model's DOFs displacements of the coarse nodes (exactly for translations): with v = S u_c,
    // K = S A^1 S, f = S g^1 and to_fine = Φ^{1,T} S.
    Vector s = Vector::Ones(h.fine_dofs.size());
    for (int k = h.num_levels() - 1; k >= 1; --k) s = h.level(k).C * s;
    // P: present coarsest DOFs -> all grid DOFs, scaled by s.
    SparseMatrix P(n, L1.dofs.size());
    {
        std::vector<Triplet> t;
        for (Index i = 0; i < L1.dofs.size(); ++i) t.emplace_back(L1.dofs[i], i, s[i]);
        P.setFromTriplets(t.begin(), t.end());
    }
    m.K = K_fine ? embedded_symmetric(galerkin_operator_lower(h, *K_fine, 1), L1.dofs, s, n)
                 : embedded_symmetric(L1.A, L1.dofs, s, n);
    m.f = P * coarse_grain(h, f_fine, 1);
    m.to_fine = coarsen::FineMap(h.fine_grid_dofs(), n,
                                 [hierarchy, Pt = SparseMatrix(P.transpose())](const Vector& u) {
                                     return reconstruct(*hierarchy, Pt * u, 1);
                                 });
    m.mass = [hierarchy, s, n](const SparseMatrix& M) {
        return embedded_symmetric(galerkin_operator_lower(*hierarchy, M, 1),
                                  hierarchy->level(1).dofs, s, n);
    };
    // Held at zero: the DOFs without a basis function, and the boundary-blind level's fixed ones.
    std::vector<Index> held(L1.dropped_dofs.data(),
                            L1.dropped_dofs.data() + L1.dropped_dofs.size());
    for (const Index r : L1.fixed) held.push_back(L1.dofs[r]);
    std::sort(held.begin(), held.end());
    if (!held.empty()) {
        m.bc.dofs = held;
        m.bc.values = Vector::Zero(static_cast<Index>(held.size()));
    }
    m.hierarchy = hierarchy;
    m.timings = h.timings;

    HierarchyReport report;
    report.options = h.options;
    for (const Level& L : h.levels) {
        LevelReport& r = report.levels.emplace_back();
        r.level = L.k;
        if (h.on_grid()) r.cells.assign(L.cells.data(), L.cells.data() + dim);
        r.nodes = level_nodes(h, L.k);
        r.elements = level_elements(h, L.k);
        r.dofs = L.dofs.size();
        r.wavelets = L.W.rows();
        r.radius = L.radius;
        r.build_seconds = L.build_seconds;
        r.C_nnz = L.C_adapted.nonZeros();
        r.C_density = density(L.C_adapted, L.C_adapted.nonZeros());
        r.A_nnz = symmetric_nonzeros(L.A);
        r.A_density = density(L.A, r.A_nnz);
        r.B_nnz = symmetric_nonzeros(L.B);
        r.B_density = density(L.B, r.B_nnz);
        double rings_sum = 0;
        int rings_count = 0, rings_max = 0;
        for (const int rings : L.region_rings)
            if (rings > 0) {
                rings_sum += rings;
                ++rings_count;
                rings_max = std::max(rings_max, rings);
            }
        if (rings_count > 0) {
            r.region_rings_mean = rings_sum / rings_count;
            r.region_rings_max = rings_max;
        }
    }
    report.fine_level = {h.num_levels(),
                         h.on_grid()
                             ? std::vector<int>(h.fine_cells.data(), h.fine_cells.data() + dim)
                             : std::vector<int>(),
                         level_nodes(h, h.num_levels()), h.A_fine.nonZeros()};
    report.fine_dofs = h.fine_dofs.size();
    m.report = std::move(report);
    return m;
}

coarsen::FineComparison compare_levels(const Hierarchy& h, const scene::FineModel& fine,
                                       const scene::StaticSolution& u,
                                       const CompareOptions& options) {
    const int q = h.num_levels();
    DiagnoseOptions diagnose_options{options.max_spectrum_dofs, true};
    const bool penalized = h.options.dirichlet == DirichletTreatment::Penalty ||
                           h.options.dirichlet == DirichletTreatment::DiagonalPenalty;
    if (!penalized) {  // the run's own fine solve and its factorization of K_ff
        diagnose_options.fine_solution = &u.u;
        diagnose_options.fine_factorization = u.factorization.get();
    }
    Diagnostics d = diagnose(h, fine.f, diagnose_options);
    coarsen::FineComparison c;
    ComparisonReport report;
    for (int k = 1; k <= q; ++k)
        if (const Vector& u_k = d.solutions[static_cast<std::size_t>(k - 1)]; u_k.size() > 0)
            c.reconstructions.push_back(
                {fmt::format("level_{}", k), u_k, static_cast<std::size_t>(k - 1)});
    c.tables.push_back(levels_table(d));
    add_coarsest_cells(h, fine, d.solutions.front(), d.solutions.back(), options.cell_tensors,
                       report.coarsest_cells, c);
    if (h.dim == 2) add_stress_map(fine, d.solutions.front(), d.solutions.back(), c);
    report.levels = std::move(d.levels);
    report.spectrum_max_dofs = options.max_spectrum_dofs;
    c.report = std::move(report);
    return c;
}

coarsen::CoarseModel build_coarse_model(const Options& options, const CompareOptions& compare,
                                        const scene::FineModel& fine,
                                        const std::vector<mesh::Mesh>& coarser_levels,
                                        const sim::DynamicsOptions* dynamics) {
    const auto build = [&](const SparseMatrix& A) {
        auto h = std::make_shared<const Hierarchy>(
            coarser_levels.empty()
                ? build_hierarchy(fine.mesh, A, fine.bc.dofs, options, &fine.materials)
                : build_hierarchy(coarser_levels, fine.mesh, A, fine.bc.dofs, options));
        return_free_memory();  // the build's temporaries, before the coarse model and its solves
        return h;
    };
    for (std::size_t k = 0; k < fine.bc.dofs.size(); ++k)
        CG_VERIFY(fine.bc.values[static_cast<Index>(k)] == 0.0,
                  "mra: only zero prescribed displacements are supported, but DOF {} is "
                  "prescribed {}",
                  fine.bc.dofs[k], fine.bc.values[static_cast<Index>(k)]);
    if (options.fine_operator == Operator::Stiffness) {
        const auto h = build(fine.K);
        coarsen::CoarseModel m = coarse_model(h, fine.f);
        m.compare_with_fine = [h, compare](const scene::Scene&, const scene::FineModel& f,
                                           const scene::StaticSolution& u) {
            return compare_levels(*h, f, u, compare);
        };
        return m;
    }
    CG_VERIFY(dynamics != nullptr,
              "mra: operator \"step\" needs the dynamics options that define the step");
    Timings timings;
    SparseMatrix S;
    {
        const Phase phase("step operator", &timings);
        S = sim::step_operator(fine.K, fem::mass_matrix(fine.mesh, fine.materials, dynamics->mass),
                               *dynamics);
    }
    const auto h = build(S);
    coarsen::CoarseModel m = coarse_model(h, fine.f, &fine.K);
    for (const auto& [phase, seconds] : timings.entries()) m.timings.add(phase, seconds);
    return m;
}

}  // namespace coarsegrain::mra
