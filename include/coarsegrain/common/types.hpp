#pragma once
/// @file Basic types shared by every module.
///
/// Conventions (see DESIGN.md):
/// - Displacement DOFs are interleaved per node: x0 y0 [z0] x1 y1 [z1] ...
/// - Symmetric tensors are in Mandel notation: (e11 e22 e33 √2e23 √2e13 √2e12) in 3D and
///   (e11 e22 √2e12) in 2D, so double contraction is a matrix product.
#include <Eigen/Dense>
#include <Eigen/SparseCore>

namespace coarsegrain {

using Index = int;  ///< node, element and DOF indices (CHOLMOD's int interface)
using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, Index>;
using IndexVector = Eigen::Matrix<Index, Eigen::Dynamic, 1>;
/// #E by nodes-per-element connectivity, one row per element.
using IndexMatrix = Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Elasticity tensor in Mandel form. Always 6x6 storage; in 2D only the top-left 3x3 block
/// (rows/columns e11 e22 √2e12) is used and the rest is zero.
using Mandel6 = Eigen::Matrix<double, 6, 6>;

/// Number of independent components of a symmetric tensor: 3 in 2D, 6 in 3D.
constexpr int mandel_size(int dim) { return dim * (dim + 1) / 2; }

/// 1/sqrt(2), the Mandel shear scaling.
inline constexpr double kInvSqrt2 = 0.70710678118654752440;
inline constexpr double kSqrt2 = 1.41421356237309504880;

}  // namespace coarsegrain
