#include "coarsegrain/mra/cell_tensors.hpp"

#include <fmt/ranges.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/mesh/boundary.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "detail.hpp"

namespace coarsegrain::mra {

using detail::cell_count;

namespace {

/// Symmetric dim x dim tensor of Mandel vector s.
Eigen::MatrixXd mandel_tensor(const Vector& s, int dim) {
    Eigen::MatrixXd t(dim, dim);
    if (dim == 2) {
        t << s[0], kInvSqrt2 * s[2], kInvSqrt2 * s[2], s[1];
    } else {
        t << s[0], kInvSqrt2 * s[5], kInvSqrt2 * s[4], kInvSqrt2 * s[5], s[1], kInvSqrt2 * s[3],
            kInvSqrt2 * s[4], kInvSqrt2 * s[3], s[2];
    }
    return t;
}

/// Grid coordinates (i, j, l) of cell c of a grid with `cells` per axis (make_grid order).
Eigen::Vector3i cell_coordinates(Index c, const Eigen::Vector3i& cells) {
    return {static_cast<int>(c % cells[0]), static_cast<int>((c / cells[0]) % cells[1]),
            static_cast<int>(c / (static_cast<Index>(cells[0]) * cells[1]))};
}

int log2_exact(int n) {
    int m = 0;
    while ((1 << m) < n) ++m;
    return (1 << m) == n ? m : -1;
}

/// X^T A^+ X for a symmetric A whose `kernel` smallest eigenvalues belong to the rigid motions:
/// they are dropped. With global solves and no truncation they vanish to round-off; localized
/// solves and truncation perturb them (measured up to 6e-4 of the next eigenvalue, even slightly
/// negative), so what is required is a clear gap: the dropped eigenvalues are below 1e-2 of the
/// smallest kept one in absolute value. @throws Error otherwise
Matrix pseudo_inverse_form(const Matrix& A, const Matrix& X, Index kernel) {
    const Eigen::SelfAdjointEigenSolver<Matrix> eig(A);
    const Vector& lambda = eig.eigenvalues();
    const Index kept = lambda.size() - kernel;
    const double gap = lambda.head(kernel).cwiseAbs().maxCoeff() / lambda[kernel];
    CG_VERIFY(kept > 0 && lambda[kernel] > 0 && gap < 1e-2,
              "mra cell tensor: the {} smallest eigenvalues of the coarsest operator should be "
              "the rigid motions, well below the others (smallest: {})",
              kernel, fmt::join(lambda.head(std::min<Index>(lambda.size(), kernel + 2)), ", "));
    const Matrix V = eig.eigenvectors().rightCols(kept);
    const Vector inv = lambda.tail(kept).cwiseInverse();
    const Matrix VX = V.transpose() * X;
    return VX.transpose() * inv.asDiagonal() * VX;
}

}  // namespace

Matrix uniform_stress_loads(const mesh::Mesh& mesh) {
    CG_ASSERT(mesh.grid.has_value(), "uniform_stress_loads: not a grid");
    const int dim = mesh.dim();
    const int n = mandel_size(dim);
    const mesh::Boundary b = mesh::boundary(mesh);
    const Eigen::VectorXd lo = mesh.grid->min.head(dim), hi = mesh.grid->max.head(dim);
    Matrix F = Matrix::Zero(mesh.num_dofs(), n);
    for (int a = 0; a < n; ++a) {
        const Eigen::MatrixXd sigma = mandel_tensor(Vector::Unit(n, a), dim);
        for (int axis = 0; axis < dim; ++axis)
            for (const int side : {-1, 1}) {
                Eigen::VectorXd box_lo = lo, box_hi = hi;
                (side < 0 ? box_hi : box_lo)[axis] = side < 0 ? lo[axis] : hi[axis];
                const Eigen::VectorXd normal = side * Eigen::VectorXd::Unit(dim, axis);
                F.col(a) += fem::traction_load(
                    mesh, b, mesh::facets_in_box(mesh, b, box_lo, box_hi), sigma * normal);
            }
    }
    return F;
}

CellTensor coarsest_cell_tensor(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                                Options options) {
    CG_VERIFY(mesh.grid.has_value(), "mra cell tensor: the mesh is not a grid");
    const int dim = mesh.dim();
    const int m = log2_exact(mesh.grid->cells[0]);
    for (int d = 0; d < dim; ++d)
        CG_VERIFY(m >= 1 && mesh.grid->cells[d] == (1 << m),
                  "mra cell tensor: the grid must have the same 2^m >= 2 cells along every axis, "
                  "got {} along axis {}",
                  mesh.grid->cells[d], d);
    options.levels = m + 1;
    options.invariance = true;
    const Hierarchy h =
        build_hierarchy(mesh, fem::stiffness_matrix(mesh, mats, options.formulation), {}, options,
                        &mats);
    const Matrix F = uniform_stress_loads(mesh);
    Matrix G(h.level(1).A.rows(), F.cols());
    for (Index a = 0; a < F.cols(); ++a) G.col(a) = coarse_grain(h, F.col(a), 1);
    const double volume = (mesh.grid->max - mesh.grid->min).head(dim).prod();
    CellTensor t;
    t.S = pseudo_inverse_form(Matrix(symmetric_from_lower(h.level(1).A)), G, dim * (dim + 1) / 2) /
          volume;
    t.S = 0.5 * (t.S + t.S.transpose()).eval();
    t.C = t.S.inverse();
    return t;
}

std::vector<CellTensor> coarsest_cell_tensors(const mesh::Mesh& fine,
                                              const material::ElementMaterials& mats,
                                              const Eigen::Vector3i& coarsest_cells,
                                              const Options& options) {
    CG_VERIFY(fine.grid.has_value(), "mra cell tensors: the fine mesh is not a grid");
    const int dim = fine.dim();
    const mesh::GridInfo& g = *fine.grid;
    Eigen::Vector3i sub = Eigen::Vector3i::Ones();
    for (int d = 0; d < dim; ++d) {
        CG_VERIFY(coarsest_cells[d] >= 1 && g.cells[d] % coarsest_cells[d] == 0,
                  "mra cell tensors: {} fine cells along axis {} do not split into {}", g.cells[d],
                  d, coarsest_cells[d]);
        sub[d] = g.cells[d] / coarsest_cells[d];
    }
    const Index per_cell = fine.num_elements() / cell_count(g.cells, dim);  // 6 tets, 2 tris
    const Eigen::Vector3d h = g.spacing();
    Eigen::VectorXi sub_cells(dim);
    for (int d = 0; d < dim; ++d) sub_cells[d] = sub[d];
    std::vector<CellTensor> out;
    const Index nc = cell_count(coarsest_cells, dim);
    for (Index c = 0; c < nc; ++c) {
        const Eigen::Vector3i ci = cell_coordinates(c, coarsest_cells);
        Eigen::VectorXd lo(dim), hi(dim);
        for (int d = 0; d < dim; ++d) {
            lo[d] = g.min[d] + ci[d] * sub[d] * h[d];
            hi[d] = lo[d] + sub[d] * h[d];
        }
        const mesh::Mesh cell = mesh::make_grid(fine.type, lo, hi, sub_cells);
        material::ElementMaterials cm;
        cm.dim = mats.dim;
        cm.table = mats.table;
        cm.index.resize(cell.num_elements());
        for (Index sc = 0; sc < cell.num_elements() / per_cell; ++sc) {
            const Eigen::Vector3i s = cell_coordinates(sc, sub);
            Index fc = 0;
            for (int d = dim - 1; d >= 0; --d) fc = fc * g.cells[d] + ci[d] * sub[d] + s[d];
            for (Index e = 0; e < per_cell; ++e)
                cm.index[sc * per_cell + e] = mats.index[fc * per_cell + e];
        }
        out.push_back(coarsest_cell_tensor(cell, cm, options));
    }
    return out;
}

Matrix youngs_directions(int dim) {
    if (dim == 2) {
        Matrix D(36, 2);
        for (int i = 0; i < 36; ++i) {
            const double a = i * std::numbers::pi / 36;
            D.row(i) << std::cos(a), std::sin(a);
        }
        return D;
    }
    Matrix D(13, 3);
    D << 1, 0, 0, 0, 1, 0, 0, 0, 1,                               //
        1, 1, 0, 1, -1, 0, 1, 0, 1, 1, 0, -1, 0, 1, 1, 0, 1, -1,  //
        1, 1, 1, 1, 1, -1, 1, -1, 1, -1, 1, 1;
    D.rowwise().normalize();
    return D;
}

}  // namespace coarsegrain::mra
