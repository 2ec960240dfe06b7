#pragma once
/// @file Corotated linear elasticity of one element (Kharevych et al. 2009, Sec. 4,
/// "Corotational Method for Potential Evaluation"): the linear potential evaluated in a frame
/// that follows the element's rotation, so that rigid rotations of any angle store no energy.
/// Any element stiffness K^e works (isotropic or anisotropic, fine or coarse, P1 or Q1): the
/// frame rotates the element's own K^e.
#include <string>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::fem {

/// How the rotation R^e of an element is chosen.
enum class CorotationFrame {
    /// de Veubeke (1976), the paper's choice: R minimizes the corotated displacement |û|², i.e.
    /// Σ_a |Rᵀ(x_a - b) - (X_a - b_0)|² (b, b_0 the current and rest node barycentres). This is
    /// the orthogonal Procrustes problem: R is the rotation factor of the polar decomposition of
    /// A = Σ_a (x_a - b)(X_a - b_0)ᵀ, in closed form by an SVD (Georgii and Westermann 2008
    /// iterate towards the same optimum). Stationarity: Rᵀ A is symmetric.
    DeVeubeke,
    /// The rotation factor of the polar decomposition of the element's deformation gradient F,
    /// here the least-squares affine fit of its nodes, F = A J^{-1} with J = Σ_a (X_a - b_0)(X_a -
    /// b_0)ᵀ (the exact F of a simplex; of a Q1 element, its mean gradient when it is a
    /// parallelogram / parallelepiped). It equals DeVeubeke when J is a multiple of the identity
    /// (a square, a cube, an equilateral simplex) and differs on elongated or sheared elements.
    Polar,
};

/// "de_veubeke", "polar".
std::string corotation_frame_name(CorotationFrame frame);

/// The rotation R^e (dim x dim, det +1) of an element with rest corners X and current corners x
/// (both npe x dim, rows are nodes).
/// @throws Error if the shapes differ or dim is not 2 or 3
Matrix corotation_frame(const Matrix& X, const Matrix& x, CorotationFrame frame);

/// The corotated state of one element.
struct CorotatedElement {
    Matrix R;       ///< dim x dim rotation
    Vector u_hat;   ///< û = Rᵀ(x - b) - (X - b_0), npe*dim interleaved
    double energy;  ///< W^e = ½ ûᵀ K^e û
    /// Internal force R K^e û (npe*dim, node blocks rotated by R): the paper's ∇W with R held
    /// fixed (its formula, as K^e annihilates translations). The derivative of R is left out.
    Vector force;
    /// R K^e Rᵀ (node blocks): the tangent of `force` with R held fixed, symmetric positive
    /// semi-definite.
    Matrix tangent;
};

/// The corotated displacement, energy, force and tangent of an element of stiffness Ke
/// (npe*dim square, interleaved node DOFs, rigid motions in its kernel) with rest corners X and
/// current corners x = X + u (npe x dim).
/// @throws Error if the shapes disagree
CorotatedElement corotate(const Matrix& X, const Matrix& x, const Matrix& Ke,
                          CorotationFrame frame);

}  // namespace coarsegrain::fem
