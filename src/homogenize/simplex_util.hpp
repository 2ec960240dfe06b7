#pragma once
// P1 simplex helpers shared by the homogenize sources (private).
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::homogenize::detail {

/// Small dense matrices up to 4x4 without heap allocation.
using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 4, 4>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 6, 1>;

/// Gradients of the barycentric coordinates of simplex e: (dim+1) by dim, row a = grad λ_a.
/// measure (if non-null) gets the signed measure det[x1-x0, ..] / dim!.
inline Small p1_gradients(const mesh::Mesh& m, Index e, double* measure = nullptr) {
    const int dim = m.dim();
    Small D(dim, dim);
    const auto x0 = m.rest_positions.row(m.elements(e, 0));
    for (int i = 0; i < dim; ++i)
        D.col(i) = (m.rest_positions.row(m.elements(e, i + 1)) - x0).transpose();
    const double det = D.determinant();
    if (measure) *measure = det / (dim == 2 ? 2.0 : 6.0);
    const Small Dinv = D.inverse();
    Small g(dim + 1, dim);
    g.bottomRows(dim) = Dinv;
    g.row(0) = -Dinv.colwise().sum();
    return g;
}

/// Mandel vector of the symmetric part of a dim by dim displacement gradient F (F_ik = du_i/dx_k):
/// (e11 e22 [e33 √2e23 √2e13] √2e12).
inline SmallVec mandel_strain(const Small& F) {
    const int dim = static_cast<int>(F.rows());
    SmallVec e(mandel_size(dim));
    for (int i = 0; i < dim; ++i) e[i] = F(i, i);
    if (dim == 2) {
        e[2] = kInvSqrt2 * (F(0, 1) + F(1, 0));
    } else {
        e[3] = kInvSqrt2 * (F(1, 2) + F(2, 1));
        e[4] = kInvSqrt2 * (F(0, 2) + F(2, 0));
        e[5] = kInvSqrt2 * (F(0, 1) + F(1, 0));
    }
    return e;
}

/// Longest edge of element e.
inline double longest_edge(const mesh::Mesh& m, Index e) {
    double h = 0;
    const Index npe = static_cast<Index>(m.elements.cols());
    for (Index a = 0; a < npe; ++a)
        for (Index b = a + 1; b < npe; ++b)
            h = std::max(
                h, (m.rest_positions.row(m.elements(e, a)) - m.rest_positions.row(m.elements(e, b)))
                       .norm());
    return h;
}

inline void verify_simplicial(const mesh::Mesh& m, const char* what) {
    CG_VERIFY(mesh::is_simplex(m.type), "{}: needs a simplicial (tri/tet) mesh, got {} elements",
              what, mesh::element_name(m.type));
}

}  // namespace coarsegrain::homogenize::detail
