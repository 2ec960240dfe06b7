#pragma once
/// @file Element kernels for P1 (Tri3, Tet4) and Q1 (Quad4, Hex8) elements, any anisotropic
/// tensor. Strain vectors are Mandel (common/types.hpp), DOFs interleaved per node.
#include <string>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::fem {

/// The fine element's formulation (scene key "fem": {"formulation": ...}).
enum class Formulation {
    /// Displacement-based P1 / Q1 elements (Q1 with full 2^dim Gauss integration).
    Standard,
    /// Q1 with incompatible modes (Wilson, Taylor, Beresford and Wilson 1976, the QM6 / "C3D8I"
    /// family): dim bubble modes per displacement component inside each element, condensed out.
    /// Quad4 / Hex8 only. Bends without shear locking and does not lock near incompressibility
    /// on regular meshes (docs/guide.md, "Near-incompressible materials"). On parallelepipeds it
    /// is CalculiX's C3D8I; on distorted hexes it keeps Taylor's j0/j factor, which CalculiX
    /// omits (src/fem/element_kernels.hpp, ModeMapping).
    Incompatible,
};

/// "standard", "incompatible".
std::string formulation_name(Formulation f);
/// Parses a formulation name.
/// @throws Error naming the allowed values if the name is unknown
Formulation parse_formulation(const std::string& name);
/// Whether formulation f is defined for elements of the given type (Incompatible: Quad4, Hex8).
bool formulation_applies(Formulation f, mesh::ElementType type);
/// @throws Error naming `fem.formulation`, the element type and the element types it allows,
///         unless formulation_applies(f, type)
void verify_formulation(Formulation f, mesh::ElementType type);

/// Strain-displacement matrix B at reference point xi: mandel_size(dim) by npe*dim, mapping
/// interleaved nodal displacements to the Mandel strain (e11 e22 [e33 √2e23 √2e13] √2e12).
/// @param[in] X   npe by dim corner positions
/// @param[in] xi  reference coordinates (in [0,1]^dim for Q1; ignored for P1, strain constant)
/// @param[out] detJ  Jacobian determinant of the reference map at xi (for P1: the measure
///                   times dim!, i.e. the determinant of the edge matrix)
/// @throws Error if the element is inverted or degenerate at xi
Matrix strain_displacement(mesh::ElementType type, const Matrix& X, const Eigen::VectorXd& xi,
                           double* detJ = nullptr);

/// Element stiffness K_e = ∫ B^T C B: closed form for P1 (constant strain), 2x2 / 2x2x2 Gauss
/// for Q1 (exact for parallelogram/parallelepiped elements). Formulation::Incompatible: the Q1
/// stiffness enriched by the incompatible modes, condensed to the nodes (same Gauss points).
/// @param[in] X  npe by dim corner positions (orderings as in mesh::ElementType)
/// @param[in] C  mandel_size(dim) square elasticity tensor
/// @return npe*dim square symmetric PSD matrix whose kernel holds the rigid motions
/// @throws Error if the element is inverted or degenerate, or the formulation does not apply
Matrix element_stiffness(mesh::ElementType type, const Matrix& X, const Matrix& C,
                         Formulation formulation = Formulation::Standard);

/// Element mass: consistent (∫ rho N_a N_b, times the dim x dim identity per node pair) or
/// lumped (row sums on the diagonal). npe*dim square.
Matrix element_mass(mesh::ElementType type, const Matrix& X, double density, bool lumped);

/// ∫ N_a over the element for each node a (npe values): the nodal weights of a constant body force.
Eigen::VectorXd element_load_weights(mesh::ElementType type, const Matrix& X);

/// Reference coordinates of the element centre (barycentre for P1, 1/2,..,1/2 for Q1).
Eigen::VectorXd element_centre(mesh::ElementType type);

}  // namespace coarsegrain::fem
