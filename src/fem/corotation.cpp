#include "coarsegrain/fem/corotation.hpp"

#include <Eigen/SVD>

#include "coarsegrain/common/error.hpp"

namespace coarsegrain::fem {

namespace {

/// Node positions relative to their barycentre (npe x dim).
Matrix centred(const Matrix& X) { return X.rowwise() - X.colwise().mean(); }

/// The rotation factor of A (square): U diag(1, .., det(U Vᵀ)) Vᵀ from A = U Σ Vᵀ, the rotation
/// closest to A (maximizing tr(Rᵀ A)).
Matrix rotation_factor(const Matrix& A) {
    const Eigen::JacobiSVD<Matrix> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Matrix U = svd.matrixU();
    const Matrix V = svd.matrixV();
    if ((U * V.transpose()).determinant() < 0) U.col(U.cols() - 1) *= -1;  // smallest σ
    return U * V.transpose();
}

/// v with each dim-block of an interleaved vector multiplied by R.
Vector rotate_blocks(const Matrix& R, const Vector& v) {
    const Index dim = R.rows();
    Vector out(v.size());
    for (Index a = 0; a < v.size() / dim; ++a)
        out.segment(a * dim, dim) = R * v.segment(a * dim, dim);
    return out;
}

}  // namespace

std::string corotation_frame_name(CorotationFrame frame) {
    return frame == CorotationFrame::DeVeubeke ? "de_veubeke" : "polar";
}

Matrix corotation_frame(const Matrix& X, const Matrix& x, CorotationFrame frame) {
    CG_VERIFY(X.rows() == x.rows() && X.cols() == x.cols() && (X.cols() == 2 || X.cols() == 3) &&
                  X.rows() > X.cols(),
              "corotation: rest corners {}x{} and current corners {}x{} must be one npe x dim "
              "shape with dim 2 or 3 and npe > dim",
              X.rows(), X.cols(), x.rows(), x.cols());
    const Matrix X0 = centred(X);
    const Matrix A = centred(x).transpose() * X0;  // Σ_a (x_a - b)(X_a - b_0)ᵀ
    if (frame == CorotationFrame::DeVeubeke) return rotation_factor(A);
    const Matrix J = X0.transpose() * X0;
    return rotation_factor(A * J.inverse());  // F = A J^{-1}
}

CorotatedElement corotate(const Matrix& X, const Matrix& x, const Matrix& Ke,
                          CorotationFrame frame) {
    const Index n = X.rows() * X.cols();
    CG_VERIFY(Ke.rows() == n && Ke.cols() == n,
              "corotation: element stiffness {}x{} for {} nodes of dimension {}", Ke.rows(),
              Ke.cols(), X.rows(), X.cols());
    CorotatedElement e;
    e.R = corotation_frame(X, x, frame);
    const Index dim = X.cols();
    const Matrix u_hat = centred(x) * e.R - centred(X);  // rows: Rᵀ(x_a - b) - (X_a - b_0)
    e.u_hat.resize(n);
    for (Index a = 0; a < X.rows(); ++a) e.u_hat.segment(a * dim, dim) = u_hat.row(a).transpose();
    const Vector Ku = Ke * e.u_hat;
    e.energy = 0.5 * e.u_hat.dot(Ku);
    e.force = rotate_blocks(e.R, Ku);
    Matrix Rb = Matrix::Zero(n, n);  // block diagonal R
    for (Index a = 0; a < X.rows(); ++a) Rb.block(a * dim, a * dim, dim, dim) = e.R;
    e.tangent = Rb * Ke * Rb.transpose();
    return e;
}

}  // namespace coarsegrain::fem
