#pragma once
/// @file Corotated linear elasticity of one element (Kharevych et al. 2009, Sec. 4,
/// "Corotational Method for Potential Evaluation"): the linear potential evaluated in a frame
/// that follows the element's rotation, so that rigid rotations of any angle store no energy.
/// Any element stiffness K^e works (isotropic or anisotropic, fine or coarse, P1 or Q1): the
/// frame rotates the element's own K^e.
#include <memory>
#include <string>
#include <vector>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/element.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

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

/// Corotated linear elasticity of a whole mesh (Kharevych et al. 2009, Sec. 4): the potential
/// W(u) = Σ_e ½ û^eᵀ K^e û^e with û^e = R^eᵀ(x^e - b^e) - (X^e - b_0^e) (corotate()), the
/// internal force f(u) = Σ_e R^e K^e û^e (the paper's ∇W, R held fixed) and the tangent
/// K_R(u) = Σ_e R^e K^e R^eᵀ (node blocks rotated, the frames held fixed), and the Jacobian of
/// the force, which also differentiates the frames (jacobian()). It equals the linear model at
/// u = 0 and whenever every R^e = I.
///
/// The elements and their work run in parallel (OpenMP); the tangent is gathered into the
/// pattern of stiffness_matrix, so a solver's symbolic analysis of it is reused every iteration.
class CorotatedModel {
  public:
    /// The state of the model at one displacement.
    struct State {
        /// The frames R^e, dim x dim each, column-major, one after the other (#E * dim^2).
        std::vector<double> frames;
        double energy = 0;    ///< W(u)
        Vector force;         ///< f(u), num_dofs() entries
        Vector displacement;  ///< the mesh displacement u (T w with a DOF map)
        /// The force's round-off, absolute: û = Rᵀ(x - b) - (X - b_0) is a small difference of
        /// quantities of the elements' size, so the force carries an error of about ε |K^e|
        /// |x^e - b^e| per element whatever the load: ε (Σ_e |K^e|_F² |x^e - b^e|_F²)^½ (ε the
        /// machine epsilon). Newton iterations with the exact Jacobian stall at 0.4 to 2.1 times
        /// it (the layered bar of the tests at gravity 1e-2 to 1e-6, the cantilever of
        /// bench/bench_corotation.cpp at 3 refinements and 2 loads).
        double round_off = 0;
    };

    /// The model of `mesh` with the element stiffnesses K^e of `mats` (any anisotropic tensor:
    /// the fine materials or a coarse mesh's effective tensors rotate with their element), the
    /// K^e of stiffness_matrix(mesh, mats, formulation). On a regular Quad4/Hex8 grid one K^e
    /// per material is stored, otherwise one per element.
    /// `dof_map` (optional; empty: the identity): a mesh DOFs x model DOFs matrix T whose
    /// columns are the model's DOFs w, u = T w (a coarse model whose Dirichlet conditions combine
    /// DOFs); force and tangent are then Tᵀ f(T w) and Tᵀ K_R T.
    /// @throws Error as stiffness_matrix, or if dof_map has other than mesh.num_dofs() rows
    CorotatedModel(const mesh::Mesh& mesh, const material::ElementMaterials& mats,
                   Formulation formulation, CorotationFrame frame, SparseMatrix dof_map = {});
    ~CorotatedModel();
    CorotatedModel(CorotatedModel&&) noexcept;
    CorotatedModel& operator=(CorotatedModel&&) noexcept;

    /// Number of model DOFs (the mesh's, or the columns of dof_map).
    Index num_dofs() const;
    CorotationFrame frame() const;
    /// The frames, energy and internal force at displacement u (num_dofs()).
    /// @throws Error if u has the wrong size or a non-finite entry
    State evaluate(const Vector& u) const;
    /// The tangent K_R at a state that evaluate() returned: num_dofs() square, symmetric
    /// positive semi-definite, both triangles stored, one pattern for every state.
    SparseMatrix tangent(const State& state) const;
    /// The Jacobian ∂f/∂u of the force at a state that evaluate() returned, the derivative of
    /// the frames included: per element R (K^e + V G) Rᵀ with G (dim(dim-1)/2 x npe*dim) the
    /// derivative of the frame's rotation vector, from the polar decomposition M = R S of the
    /// frame's moment (de Veubeke: M = Σ_a (x_a - b)(X_a - b_0)ᵀ; polar: F), dω = (tr S I -
    /// S)^{-1} Σ_a c_a × Rᵀ dx_a (2D: dθ = Σ_a c_a × Rᵀ dx_a / tr S) with c_a = X_a - b_0
    /// (polar: J^{-1}(X_a - b_0)), and V's column k = E_k (K^e û) - K^e (E_k û), E_k the
    /// infinitesimal rotation about axis k applied to each node. Not symmetric (the force is
    /// the energy's gradient only up to O(|û|²)); its non-symmetric part vanishes at û = 0.
    /// An element whose frame is not differentiable (tr S I - S singular: inverted or
    /// collapsed) keeps R K^e Rᵀ. num_dofs() square, the pattern of tangent().
    SparseMatrix jacobian(const State& state) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

}  // namespace coarsegrain::fem
