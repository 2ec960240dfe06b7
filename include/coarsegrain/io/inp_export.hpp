#pragma once
/// @file CalculiX / Abaqus input decks (.inp) of element models: a coarse mesh with one
/// anisotropic tensor per element (the effective tensors of Kharevych et al. 2009, Eq. 8, or an
/// averaging baseline) is an ordinary FE model, which an off-the-shelf simulator runs.
///
/// Conventions (CalculiX 2.20 manual, "*ELASTIC", TYPE=ANISO): the 21 constants are the tensor
/// components D_ijkl of σ_ij = D_ijkl ε_kl, in the order
///   D1111 D1122 D2222 D1133 D2233 D3333 D1112 D2212 D3312 D1212 D1113 D2213 D3313 D1213 D1313
///   D1123 D2223 D3323 D1223 D1323 D2323,
/// eight per line. With engineering shear strains γ_ij = 2 ε_ij, Voigt's stiffness (order 11 22
/// 33 23 13 12) has exactly these components as entries: σ_12 = D_1212 ε_12 + D_1221 ε_21 =
/// D_1212 γ_12. The Mandel form coarsegrain stores (shear rows and columns scaled by √2) maps to
/// it by material::mandel_to_voigt.
///
/// 2D models: CalculiX expands plane elements to 3D and reads a 3D tensor. The in-plane block
/// (11 22 12) is the model's 2D tensor, uncoupled from the out-of-plane components, which get the
/// mean in-plane normal stiffness (D3333, D1313, D2323). Plane strain (ε33 = ε13 = ε23 = 0) and
/// plane stress (σ33 = 0, hence ε33 = 0 without coupling) then both give the 2D tensor's
/// in-plane response exactly; the out-of-plane stresses ccx reports are not the model's.
#include <array>
#include <optional>
#include <string>

#include "coarsegrain/common/types.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::io {

/// The 21 CalculiX ANISO constants of a 3D Mandel tensor, in the order of the file comment.
std::array<double, 21> calculix_aniso(const Matrix& C_mandel);

/// The 3D Mandel tensor whose in-plane block is the 2D Mandel tensor C2 (3x3: 11 22 √2·12) and
/// whose out-of-plane components are uncoupled, with the mean of C2's normal diagonal (the file
/// comment).
Matrix embed_plane_tensor(const Matrix& C2);

/// The *DYNAMIC step of a deck: M ü + K u = f from rest (or with an initial velocity), the load
/// switched on at t = 0 and held, by CalculiX's α-method with α = 0, i.e. Newmark's average
/// acceleration: for a linear model the implicit midpoint rule of sim::TimeStepper.
struct CalculixDynamics {
    double dt = 0;        ///< time step (fixed: DIRECT)
    int steps = 0;        ///< the step lasts steps * dt
    int output_every = 1;  ///< *NODE PRINT every output_every increments
    /// Lumped masses, one per DOF (equal over a node's components): written as one *MASS
    /// element per node, the elements' densities then 1e-30 of theirs. Empty: the mass is
    /// CalculiX's consistent mass of the elements' densities.
    Vector lumped_mass;
    Vector initial_velocity;  ///< one per DOF (*INITIAL CONDITIONS, TYPE=VELOCITY); empty: rest
};

/// Writes the static problem K u = f of an element model as a CalculiX deck:
///   *NODE, *ELEMENT (C3D4, C3D8; 2D: CPE3 / CPE4 for plane strain, CPS3 / CPS4 for plane
///   stress, thickness 1), one *MATERIAL (*ELASTIC, TYPE=ANISO and *DENSITY) and *SOLID SECTION
///   per group of elements with equal tensor and density, *BOUNDARY for the prescribed DOFs,
///   and a *STATIC step with the load f as *CLOAD (nonzero entries) and *NODE PRINT of the
///   displacements (ccx writes them to <name>.dat).
/// Nodes and elements are numbered from 1 in the mesh's order. Numbers are written with 13
/// significant digits, as CalculiX reads at most 20 characters of a number: the deck holds the
/// model to 5e-14 relative. Written atomically.
/// @param f   mesh.num_dofs() load (interleaved node DOFs)
/// @param bc  prescribed DOFs of the mesh
/// With `dynamics`, the step is a *DYNAMIC, DIRECT one instead (CalculixDynamics), with the
/// same load.
/// @throws Error naming the file if it cannot be written, or if f, bc or the dynamics' vectors
///         do not fit the mesh, or a node's lumped masses differ between its components
void write_calculix_deck(const std::string& file, const mesh::Mesh& mesh,
                         const material::ElementMaterials& materials, const Vector& f,
                         const fem::Dirichlet& bc, material::PlaneMode plane,
                         const std::string& heading,
                         const std::optional<CalculixDynamics>& dynamics = {});

}  // namespace coarsegrain::io
