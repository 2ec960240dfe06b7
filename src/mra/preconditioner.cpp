#include "coarsegrain/mra/preconditioner.hpp"

#include <fmt/format.h>

#include <cmath>
#include <random>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/fem/stiff_clusters.hpp"
#include "coarsegrain/mra/automatic_levels.hpp"
#include "coarsegrain/solve/deflation.hpp"

namespace coarsegrain::mra {

namespace {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

constexpr int kPowerIterations = 20;
constexpr double kUpperSafety = 1.1;  ///< smoothing interval [λ / 10, 1.1 λ]
constexpr double kLowerFraction = 0.1;

/// Largest eigenvalue of D^{-1} A (similar to the symmetric D^{-1/2} A D^{-1/2}): the Rayleigh
/// quotient x^T A x / x^T D x of the kPowerIterations-th power iterate of a fixed random start.
double largest_eigenvalue(const SparseMatrix& A, const Vector& inverse_diagonal) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Vector x(A.rows()), y;
    for (Index i = 0; i < x.size(); ++i) x[i] = u(rng);
    const Vector diagonal = A.diagonal();
    double lambda = 0;
    for (int it = 0; it < kPowerIterations; ++it) {
        solve::symmetric_multiply(A, x, y);
        lambda = x.dot(y) / x.dot(diagonal.cwiseProduct(x));
        x = inverse_diagonal.cwiseProduct(y);
        x /= x.norm();
    }
    return lambda;
}

}  // namespace

struct MultigridPreconditioner::Level {
    /// A^k with both triangles (the fine level: a pointer to the caller's A).
    SparseMatrix owned;
    const SparseMatrix* A = nullptr;
    Vector inverse_diagonal;
    double lambda = 0;
    RowMatrix restriction;   ///< C̃^{k-1}: level k-1 by level k (k > 1)
    RowMatrix prolongation;  ///< C̃^{k-1,T}
};

void validate(const PreconditionerOptions& o) {
    CG_VERIFY(o.levels == 0 || (o.levels >= 2 && o.levels <= kMaxLevels),
              "solver.levels = {}: expected 0 (automatic) or 2..{}", o.levels, kMaxLevels);
    CG_VERIFY(o.coarsest_dofs >= 1, "solver.coarsest_dofs = {}: expected >= 1", o.coarsest_dofs);
    CG_VERIFY(std::isfinite(o.radius) && o.radius >= 1, "solver.radius = {}: expected >= 1",
              o.radius);
    CG_VERIFY(o.smoother_degree >= 1 && o.smoother_degree <= 10,
              "solver.smoother_degree = {}: expected 1..10", o.smoother_degree);
    CG_VERIFY(o.deflation_rings >= 0 && o.deflation_rings <= kMaxDeflationRings,
              "solver.deflation_rings = {}: expected 0..{}", o.deflation_rings, kMaxDeflationRings);
}

int preconditioner_levels(const Eigen::Vector3i& cells, int dim,
                          const PreconditionerOptions& options) {
    validate(options);
    const auto halves = [&](const Eigen::Vector3i& c) {
        for (int d = 0; d < dim; ++d)
            if (c[d] % 2 != 0) return false;
        return true;
    };
    CG_VERIFY(halves(cells),
              "solver (mra-pcg): the grid's cells per axis must be even to coarsen it once; "
              "they are {}",
              fmt::join(cells.head(dim), " x "));
    if (options.levels > 0) {
        Options o;
        o.levels = options.levels;
        validate_grid(o, cells, dim);
        return options.levels;
    }
    int q = 2;
    Eigen::Vector3i coarse = cells;
    coarse.head(dim) /= 2;
    while (dim * grid_nodes(coarse, dim) > options.coarsest_dofs && halves(coarse) &&
           q < kMaxLevels) {
        coarse.head(dim) /= 2;
        ++q;
    }
    return q;
}

int preconditioner_levels(const mesh::Mesh& fine, const PreconditionerOptions& options) {
    if (fine.grid) return preconditioner_levels(fine.grid->cells, fine.dim(), options);
    validate(options);
    CG_VERIFY(fine.type == mesh::ElementType::Tri3 || fine.type == mesh::ElementType::Tet4,
              "solver (mra-pcg): the fine mesh must be a regular grid or of linear triangles or "
              "tetrahedra, got {} elements",
              mesh::element_name(fine.type));
    const int most = max_automatic_levels(fine);
    CG_VERIFY(most >= 2,
              "solver (mra-pcg): a fine mesh of {} nodes is too small for a coarser level; use "
              "cholmod",
              fine.num_nodes());
    if (options.levels > 0) {
        CG_VERIFY(options.levels <= most,
                  "solver.levels = {}: the automatic level meshes of a fine mesh of {} nodes allow "
                  "at most {} levels",
                  options.levels, fine.num_nodes(), most);
        return options.levels;
    }
    const int dim = fine.dim();
    const auto coarsest_dofs = [&](int levels) {
        return dim * std::ldexp(static_cast<double>(fine.num_nodes()), -dim * (levels - 1));
    };
    int q = 2;
    while (q < most && coarsest_dofs(q) > static_cast<double>(options.coarsest_dofs)) ++q;
    return q;
}

MultigridPreconditioner::MultigridPreconditioner(Hierarchy h, const SparseMatrix& A,
                                                 int smoother_degree)
    : m_h(std::move(h)), m_degree(smoother_degree) {
    const DirichletTreatment t = m_h.options.dirichlet;
    CG_VERIFY(t == DirichletTreatment::Eliminate || t == DirichletTreatment::Constrain,
              "mra-pcg: the hierarchy must eliminate the Dirichlet DOFs (eliminate or "
              "constrain), not {}",
              dirichlet_name(t));
    CG_VERIFY(A.rows() == m_h.fine_dofs.size() && A.cols() == A.rows(),
              "mra-pcg: the fine operator is {}x{}, the hierarchy's {}", A.rows(), A.cols(),
              m_h.fine_dofs.size());
    m_h.A_fine = SparseMatrix();
    const int q = m_h.num_levels();
    m_levels.resize(static_cast<std::size_t>(q));
    for (int k = q; k >= 1; --k) {
        Level& L = m_levels[static_cast<std::size_t>(k - 1)];
        if (k == q) {
            L.A = &A;
        } else {
            mra::Level& hl = m_h.levels[static_cast<std::size_t>(k - 1)];
            L.owned = symmetric_from_lower(hl.A);
            L.A = &L.owned;
            hl.A = SparseMatrix();  // the cycle's copy replaces it
            hl.B = SparseMatrix();  // not needed by the cycle (if the build kept it)
            Level& finer = m_levels[static_cast<std::size_t>(k)];
            finer.restriction = RowMatrix(hl.C_adapted.sparse());
            finer.prolongation = RowMatrix(finer.restriction.transpose());
        }
        if (k > 1) {
            L.inverse_diagonal = L.A->diagonal().cwiseInverse();
            CG_VERIFY_AS(NotPositiveDefinite,
                         L.inverse_diagonal.allFinite() && L.inverse_diagonal.minCoeff() > 0,
                         "mra-pcg: level {} has a diagonal entry that is not positive", k);
            L.lambda = largest_eigenvalue(*L.A, L.inverse_diagonal);
        }
    }
    m_coarsest.compute(*m_levels.front().A);
}

MultigridPreconditioner::~MultigridPreconditioner() = default;

std::vector<std::pair<Index, Index>> MultigridPreconditioner::level_sizes() const {
    std::vector<std::pair<Index, Index>> sizes;
    for (const Level& L : m_levels) sizes.emplace_back(L.A->rows(), L.A->nonZeros());
    return sizes;
}

void MultigridPreconditioner::smooth(const Level& L, const Vector& b, Vector& x) const {
    // Chebyshev iteration for D^{-1} A on [lo, hi] (Saad, Iterative Methods, Alg. 12.1).
    const double hi = kUpperSafety * L.lambda, lo = kLowerFraction * hi;
    const double theta = (hi + lo) / 2, delta = (hi - lo) / 2, sigma = theta / delta;
    Vector r = b, Ad(b.size());
    if (x.size() == b.size()) {
        solve::symmetric_multiply(*L.A, x, Ad);
        r -= Ad;
    } else {
        x.setZero(b.size());
    }
    Vector d = L.inverse_diagonal.cwiseProduct(r) / theta;
    double rho = 1 / sigma;
    for (int j = 0; j < m_degree; ++j) {
        x += d;
        if (j + 1 == m_degree) break;
        solve::symmetric_multiply(*L.A, d, Ad);
        r -= Ad;
        const double rho_next = 1 / (2 * sigma - rho);
        d = (rho_next * rho) * d + (2 * rho_next / delta) * L.inverse_diagonal.cwiseProduct(r);
        rho = rho_next;
    }
}

Vector MultigridPreconditioner::cycle(std::size_t i, const Vector& b) const {
    if (i == 0) return m_coarsest.solve(b);
    const Level& L = m_levels[i];
    Vector x;
    smooth(L, b, x);
    Vector Ax(b.size());
    solve::symmetric_multiply(*L.A, x, Ax);
    const Vector coarse_residual = L.restriction * (b - Ax);
    x += L.prolongation * cycle(i - 1, coarse_residual);
    smooth(L, b, x);
    return x;
}

Vector MultigridPreconditioner::apply(const Vector& r) const {
    CG_VERIFY(r.size() == m_levels.back().A->rows(), "mra-pcg: a residual of {} for {} DOFs",
              r.size(), m_levels.back().A->rows());
    return cycle(m_levels.size() - 1, r);
}

solve::PreconditionerFactory hierarchy_preconditioner(const mesh::Mesh& fine,
                                                      const material::ElementMaterials& materials,
                                                      std::vector<Index> fixed_dofs,
                                                      const PreconditionerOptions& options) {
    Options o;
    o.levels = preconditioner_levels(fine, options);
    o.radius = {options.radius};
    o.dirichlet = DirichletTreatment::Eliminate;
    o.store_wavelet_stiffness = false;
    auto mesh = std::make_shared<const mesh::Mesh>(fine);
    auto fixed = std::make_shared<const std::vector<Index>>(std::move(fixed_dofs));
    auto clusters = std::make_shared<const fem::StiffClusters>(
        options.deflation ? fem::stiff_clusters(fine, materials, kDeflationContrast)
                          : fem::StiffClusters{});
    const int degree = options.smoother_degree, rings = options.deflation_rings;
    return [mesh, fixed, clusters, o, degree,
            rings](const SparseMatrix& A) -> std::unique_ptr<solve::Preconditioner> {
        Hierarchy h;
        if (mesh->grid) {
            const Phase phase("mra-pcg: hierarchy");
            h = build_hierarchy_free(*mesh, A, *fixed, o);
        } else {
            std::vector<mesh::Mesh> levels;
            {
                const Phase phase("mra-pcg: levels");
                levels = automatic_level_meshes(*mesh, o.levels);
            }
            const Phase phase("mra-pcg: hierarchy");
            h = build_hierarchy_free(levels, *mesh, A, *fixed, o);
        }
        std::unique_ptr<solve::Preconditioner> cycle;
        {
            const Phase phase("mra-pcg: cycle");
            cycle = std::make_unique<MultigridPreconditioner>(std::move(h), A, degree);
        }
        if (clusters->count == 0) return cycle;
        const Phase phase("mra-pcg: deflation");
        SparseMatrix Z = fem::cluster_rigid_modes(*mesh, *clusters, A, *fixed, rings);
        if (Z.cols() == 0) return cycle;
        return std::make_unique<solve::DeflatedPreconditioner>(A, std::move(cycle), std::move(Z));
    };
}

const MultigridPreconditioner& multigrid_cycle(const solve::Preconditioner& M) {
    if (const auto* deflated = dynamic_cast<const solve::DeflatedPreconditioner*>(&M))
        return multigrid_cycle(deflated->base());
    const auto* cycle = dynamic_cast<const MultigridPreconditioner*>(&M);
    CG_VERIFY(cycle != nullptr, "mra-pcg: the preconditioner is not the hierarchy's cycle");
    return *cycle;
}

}  // namespace coarsegrain::mra
