#include "coarsegrain/homogenize/coarse_maps.hpp"

#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "simplex_util.hpp"

namespace coarsegrain::homogenize {

namespace {

/// Skew generator r of infinitesimal rotations: 2D [[0,-1],[1,0]]; 3D [e_r]×.
Matrix skew_generator(int dim, int r) {
    Matrix W = Matrix::Zero(dim, dim);
    if (dim == 2) {
        W(0, 1) = -1;
        W(1, 0) = 1;
        return W;
    }
    const int i = (r + 1) % 3, j = (r + 2) % 3;
    W(i, j) = -1;
    W(j, i) = 1;
    return W;
}

/// Rotation exp(sum_r phi_r W_r) (Rodrigues in 3D).
Matrix rotation(int dim, const Eigen::VectorXd& phi) {
    if (dim == 2) {
        Matrix R(2, 2);
        R << std::cos(phi[0]), -std::sin(phi[0]), std::sin(phi[0]), std::cos(phi[0]);
        return R;
    }
    const double t = phi.norm();
    if (t == 0) return Matrix::Identity(3, 3);
    Matrix K = Matrix::Zero(3, 3);
    for (int r = 0; r < 3; ++r) K += phi[r] / t * skew_generator(3, r);
    return Matrix::Identity(3, 3) + std::sin(t) * K + (1 - std::cos(t)) * K * K;
}

}  // namespace

std::vector<mesh::Location> locate_points(const mesh::PointLocator& coarse_locator,
                                          const Matrix& points) {
    std::vector<mesh::Location> out(static_cast<std::size_t>(points.rows()));
#pragma omp parallel for schedule(dynamic, 256)
    for (Index i = 0; i < points.rows(); ++i)
        out[i] = coarse_locator.locate_nearest(points.row(i).transpose());
    return out;
}

SparseMatrix barycentric_embedding(const mesh::Mesh& coarse,
                                   const std::vector<mesh::Location>& locations) {
    const int dim = coarse.dim();
    std::vector<Eigen::Triplet<double, Index>> t;
    t.reserve(locations.size() * static_cast<std::size_t>(coarse.elements.cols() * dim));
    for (std::size_t i = 0; i < locations.size(); ++i) {
        const mesh::Location& loc = locations[i];
        for (Eigen::Index a = 0; a < coarse.elements.cols(); ++a)
            for (int d = 0; d < dim; ++d)
                t.emplace_back(dim * static_cast<Index>(i) + d,
                               dim * coarse.elements(loc.element, a) + d, loc.weights[a]);
    }
    SparseMatrix E(dim * static_cast<Index>(locations.size()), coarse.num_dofs());
    E.setFromTriplets(t.begin(), t.end());
    E.makeCompressed();
    return E;
}

CarriedConditions carry_dirichlet(const fem::Dirichlet& fine, const SparseMatrix& E) {
    constexpr double kTouch = 1e-10;
    const Index nc = E.cols();
    std::vector<Index> row(static_cast<std::size_t>(E.rows()), -1);  // fine DOF -> condition
    for (std::size_t k = 0; k < fine.dofs.size(); ++k) {
        const Index d = fine.dofs[k];
        CG_VERIFY(d >= 0 && d < E.rows(), "carry_dirichlet: fine Dirichlet DOF {} out of 0..{}", d,
                  E.rows() - 1);
        row[d] = static_cast<Index>(k);
    }
    // D: the coarse DOFs that touch a fixed fine DOF; B = E_FD.
    std::vector<Index> D, index_in_D(static_cast<std::size_t>(nc), -1);
    std::vector<Eigen::Triplet<double, Index>> t;
    for (Index j = 0; j < nc; ++j) {
        bool touches = false;
        for (SparseMatrix::InnerIterator it(E, j); it; ++it)
            touches = touches || (row[it.row()] >= 0 && std::abs(it.value()) > kTouch);
        if (!touches) continue;
        index_in_D[j] = static_cast<Index>(D.size());
        for (SparseMatrix::InnerIterator it(E, j); it; ++it)
            if (row[it.row()] >= 0) t.emplace_back(row[it.row()], index_in_D[j], it.value());
        D.push_back(j);
    }
    const Index nd = static_cast<Index>(D.size());
    SparseMatrix B(static_cast<Index>(fine.dofs.size()), nd);
    B.setFromTriplets(t.begin(), t.end());
    const SparseMatrix BtB = SparseMatrix(B.transpose()) * B;
    const Vector Btg = B.transpose() * fine.values;
    // Blocks of D coupled by a common fixed fine DOF (union-find over BtB's pattern).
    std::vector<Index> root(static_cast<std::size_t>(nd));
    for (Index i = 0; i < nd; ++i) root[i] = i;
    const auto find = [&root](Index i) {
        while (root[i] != i) i = root[i] = root[root[i]];
        return i;
    };
    for (Index j = 0; j < nd; ++j)
        for (SparseMatrix::InnerIterator it(BtB, j); it; ++it) root[find(it.row())] = find(j);
    std::vector<std::vector<Index>> blocks;
    std::vector<Index> block_of(static_cast<std::size_t>(nd), -1);
    for (Index i = 0; i < nd; ++i) {
        Index& b = block_of[find(i)];
        if (b < 0) {
            b = static_cast<Index>(blocks.size());
            blocks.emplace_back();
        }
        blocks[b].push_back(i);
    }
    // Per block: the least-squares values (pseudo-inverse of B^T B) and the null space of B, the
    // combinations of its DOFs that E carries to zero on every fixed fine DOF.
    Vector value = Vector::Zero(nd);
    std::vector<Matrix> null(blocks.size());
    for (std::size_t b = 0; b < blocks.size(); ++b) {
        const std::vector<Index>& L = blocks[b];
        const Index n = static_cast<Index>(L.size());
        Matrix N(n, n);
        for (Index i = 0; i < n; ++i)
            for (Index j = 0; j < n; ++j) N(i, j) = BtB.coeff(L[i], L[j]);
        const Eigen::SelfAdjointEigenSolver<Matrix> eig(N);
        const double tol = 1e-10 * eig.eigenvalues()[n - 1];
        const Index k = (eig.eigenvalues().array() <= tol).count();  // ascending order
        null[b] = eig.eigenvectors().leftCols(k);
        Vector rhs(n);
        for (Index i = 0; i < n; ++i) rhs[i] = Btg[L[i]];
        const Matrix V = eig.eigenvectors().rightCols(n - k);
        const Vector u = V * (V.transpose() * rhs).cwiseQuotient(eig.eigenvalues().tail(n - k));
        for (Index i = 0; i < n; ++i) value[L[i]] = u[i];
    }
    // Reduced DOFs: every coarse DOF outside the null-space blocks (the fixed ones held at their
    // values), then the null-space coordinates, then one DOF held at 1 that carries the values
    // of the null-space blocks' DOFs if any is nonzero.
    CarriedConditions out;
    std::vector<Eigen::Triplet<double, Index>> tt;
    std::vector<std::pair<Index, double>> fixed;
    Index w = 0;
    for (Index j = 0; j < nc; ++j) {
        const Index i = index_in_D[j];
        if (i >= 0 && null[block_of[find(i)]].cols() > 0) continue;
        tt.emplace_back(j, w, 1.0);
        if (i >= 0) fixed.emplace_back(w, value[i]);
        ++w;
    }
    bool offset = false;
    for (std::size_t b = 0; b < blocks.size(); ++b) {
        const std::vector<Index>& L = blocks[b];
        for (Index c = 0; c < null[b].cols(); ++c, ++w) {
            ++out.combinations;
            for (std::size_t i = 0; i < L.size(); ++i)
                if (null[b](static_cast<Index>(i), c) != 0)
                    tt.emplace_back(D[L[i]], w, null[b](static_cast<Index>(i), c));
        }
        if (null[b].cols() > 0) {
            out.constrained += static_cast<Index>(L.size());
            for (const Index i : L) offset = offset || value[i] != 0;
        }
    }
    if (offset) {
        for (std::size_t b = 0; b < blocks.size(); ++b)
            if (null[b].cols() > 0)
                for (const Index i : blocks[b]) tt.emplace_back(D[i], w, value[i]);
        fixed.emplace_back(w++, 1.0);
    }
    out.fixed = static_cast<Index>(fixed.size()) - (offset ? 1 : 0);
    out.bc.dofs.resize(fixed.size());
    out.bc.values.resize(static_cast<Index>(fixed.size()));
    for (std::size_t k = 0; k < fixed.size(); ++k) {
        out.bc.dofs[k] = fixed[k].first;
        out.bc.values[static_cast<Index>(k)] = fixed[k].second;
    }
    out.T.resize(nc, w);
    out.T.setFromTriplets(tt.begin(), tt.end());
    out.T.makeCompressed();
    return out;
}

HarmonicMap::HarmonicMap(const mesh::Mesh& coarse, const Matrix& H_coarse, const Matrix& points,
                         const Matrix& H_points, std::vector<Index> carrier)
    : m_dim(coarse.dim()),
      m_coarse(coarse),
      m_H_coarse(H_coarse),
      m_points(points),
      m_H_points(H_points),
      m_carrier(std::move(carrier)) {
    detail::verify_simplicial(coarse, "harmonic map");
    const int d = m_dim, n = mandel_size(d), dd = d * d;
    const Index np = static_cast<Index>(points.rows());
    CG_VERIFY(H_coarse.rows() == coarse.num_dofs() && H_coarse.cols() == n && points.cols() == d &&
                  H_points.rows() == d * np && H_points.cols() == n &&
                  static_cast<Index>(m_carrier.size()) == np,
              "harmonic map: inconsistent sizes (coarse fields {}x{}, {} points of dim {}, point "
              "fields {}x{}, {} carriers)",
              H_coarse.rows(), H_coarse.cols(), np, points.cols(), H_points.rows(), H_points.cols(),
              m_carrier.size());
    const Index nc = coarse.num_elements();
    m_edge_maps.resize(static_cast<std::size_t>(nc));
    std::vector<Matrix> inverse(static_cast<std::size_t>(nc));
    for (Index q = 0; q < nc; ++q) {
        Matrix M(dd, dd);
        const Index v0 = coarse.elements(q, 0);
        for (int i = 1; i <= d; ++i) {
            const Index vi = coarse.elements(q, i);
            M.block((i - 1) * d, 0, d, n) =
                H_coarse.middleRows(d * vi, d) - H_coarse.middleRows(d * v0, d);
            const Eigen::VectorXd dX =
                (coarse.rest_positions.row(vi) - coarse.rest_positions.row(v0)).transpose();
            for (int r = 0; r < dd - n; ++r)
                M.block((i - 1) * d, n + r, d, 1) = skew_generator(d, r) * dX;
        }
        const Eigen::FullPivLU<Matrix> lu(M);
        CG_VERIFY(lu.isInvertible(),
                  "harmonic map: the harmonic fields sampled on coarse element {} do not span "
                  "its strains (singular coarse mollifier)",
                  q);
        m_edge_maps[q] = M;
        inverse[q] = lu.inverse();
    }
    // Linearization: u(x) = U^0 + Q_x M^{-1} (U^i - U^0)_i, Q_x = [H(x) - H^0 | W_r (x - X^0)].
    std::vector<Eigen::Triplet<double, Index>> t;
    const int npe = d + 1;
    t.reserve(static_cast<std::size_t>(np) * d * npe * d);
    for (Index p = 0; p < np; ++p) {
        const Index q = m_carrier[p];
        CG_VERIFY(q >= 0 && q < nc, "harmonic map: point {} carried by coarse element {} of {}", p,
                  q, nc);
        const Index v0 = coarse.elements(q, 0);
        Matrix Q(d, dd);
        Q.leftCols(n) = H_points.middleRows(d * p, d) - H_coarse.middleRows(d * v0, d);
        const Eigen::VectorXd dx = (points.row(p) - coarse.rest_positions.row(v0)).transpose();
        for (int r = 0; r < dd - n; ++r) Q.col(n + r) = skew_generator(d, r) * dx;
        const Matrix QM = Q * inverse[q];  // d by dd, acting on edge differences (i, k)
        Matrix T = Matrix::Zero(d, npe * d);
        T.leftCols(d).setIdentity();
        for (int i = 1; i <= d; ++i) {
            T.middleCols(i * d, d) += QM.middleCols((i - 1) * d, d);
            T.leftCols(d) -= QM.middleCols((i - 1) * d, d);
        }
        for (int a = 0; a < npe; ++a)
            for (int k = 0; k < d; ++k)
                for (int l = 0; l < d; ++l)
                    t.emplace_back(d * p + k, d * coarse.elements(q, a) + l, T(k, a * d + l));
    }
    m_linear.resize(d * np, coarse.num_dofs());
    m_linear.setFromTriplets(t.begin(), t.end());
    m_linear.makeCompressed();
}

Matrix HarmonicMap::deformed_positions(const Matrix& coarse_deformed) const {
    const int d = m_dim, n = mandel_size(d), dd = d * d, nr = dd - n;
    CG_VERIFY(coarse_deformed.rows() == m_coarse.num_nodes() && coarse_deformed.cols() == d,
              "harmonic map: deformed coarse positions are {}x{}, expected {}x{}",
              coarse_deformed.rows(), coarse_deformed.cols(), m_coarse.num_nodes(), d);
    const Index nc = m_coarse.num_elements();
    std::vector<Matrix> R(static_cast<std::size_t>(nc));
    std::vector<Eigen::VectorXd> S(static_cast<std::size_t>(nc));
    std::vector<char> converged(static_cast<std::size_t>(nc), 0);
#pragma omp parallel for schedule(dynamic, 8)
    for (Index q = 0; q < nc; ++q) {
        const Index v0 = m_coarse.elements(q, 0);
        Matrix D(d, d), D0(d, d);
        for (int i = 1; i <= d; ++i) {
            const Index vi = m_coarse.elements(q, i);
            D.col(i - 1) = (coarse_deformed.row(vi) - coarse_deformed.row(v0)).transpose();
            D0.col(i - 1) =
                (m_coarse.rest_positions.row(vi) - m_coarse.rest_positions.row(v0)).transpose();
        }
        // Start from the polar rotation: R F symmetric for F = D D0^{-1}.
        const Eigen::JacobiSVD<Matrix> svd(D * D0.inverse(),
                                           Eigen::ComputeFullU | Eigen::ComputeFullV);
        Matrix Rf = svd.matrixU() * svd.matrixV().transpose();
        if (Rf.determinant() < 0) {
            Matrix U = svd.matrixU();
            U.col(d - 1) *= -1;
            Rf = U * svd.matrixV().transpose();
        }
        Matrix Rq = Rf.transpose();
        Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
        const Matrix& M = m_edge_maps[q];
        const double scale = D0.norm();
        for (int it = 0; it < 50; ++it) {
            // residual, rows (i, k): (R D - D0)_{k,i} - sum_J c_J ΔH_J
            const Matrix RD = Rq * D;
            Eigen::VectorXd r(dd);
            for (int i = 0; i < d; ++i) r.segment(i * d, d) = RD.col(i) - D0.col(i);
            r -= M.leftCols(n) * c;
            if (r.norm() <= 1e-14 * scale) {
                converged[q] = 1;
                break;
            }
            Matrix J(dd, dd);
            J.leftCols(nr).setZero();
            for (int k = 0; k < nr; ++k) {
                const Matrix WRD = skew_generator(d, k) * RD;
                for (int i = 0; i < d; ++i) J.block(i * d, k, d, 1) = WRD.col(i);
            }
            J.rightCols(n) = -M.leftCols(n);
            const Eigen::VectorXd step = J.fullPivLu().solve(-r);
            Rq = rotation(d, step.head(nr)) * Rq;
            c += step.tail(n);
        }
        R[q] = Rq;
        S[q] = c;
    }
    for (Index q = 0; q < nc; ++q)
        CG_VERIFY(converged[q],
                  "harmonic map: no rotation and harmonic combination match the "
                  "deformed coarse element {} (Eq. 9; Newton did not converge)",
                  q);
    Matrix x(m_points.rows(), d);
#pragma omp parallel for schedule(static)
    for (Index p = 0; p < m_points.rows(); ++p) {
        const Index q = m_carrier[p];
        const Index v0 = m_coarse.elements(q, 0);
        const Eigen::VectorXd local =
            (m_points.row(p) - m_coarse.rest_positions.row(v0)).transpose() +
            (m_H_points.middleRows(d * p, d) - m_H_coarse.middleRows(d * v0, d)) * S[q];
        x.row(p) = coarse_deformed.row(v0) + (R[q].transpose() * local).transpose();
    }
    return x;
}

}  // namespace coarsegrain::homogenize
