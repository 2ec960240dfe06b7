#pragma once
/// @file The effective-tensor coarsening of Kharevych et al. 2009 and its averaging baselines
/// behind one entry point (DESIGN.md "data flow"): fine model + coarse mesh -> CoarseModel.
///
/// Steps (effective-tensor): the fine mesh is split into simplices (hex -> 6 tets, quad -> 2
/// triangles, same nodes); the exact overlaps |T_p ∩ 𝕋_q| are computed (mesh::intersect); the
/// global harmonic displacements are solved on the fine mesh (Eq. 6, one factorization); the
/// fine mollifiers G_p (Sec. 3.5), the coarse-sampled fields ℍ (Sec. 3.2) and the coarse
/// mollifiers 𝔾_q follow, and Eq. 8 gives one anisotropic tensor per coarse element. The
/// baselines replace the last three steps by averages over the same overlaps.
#include <string>
#include <vector>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/homogenize/effective_tensor.hpp"
#include "coarsegrain/homogenize/options.hpp"
#include "coarsegrain/homogenize/report.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::homogenize {

/// Everything a coarsening computes (tests and diagnostics read the intermediate results).
struct Coarsening {
    std::string method;
    Options options;
    mesh::Mesh fine;                            ///< simplicial fine mesh (the scene's, split)
    material::ElementMaterials fine_materials;  ///< materials of `fine`
    mesh::Mesh coarse;                          ///< simplicial coarse mesh (coarse.mesh, split)
    std::vector<mesh::Overlap> overlaps;        ///< mesh::intersect(fine, coarse)
    Vector coarse_measures;                     ///< #Ec |𝕋_q|
    Vector element_mass;                        ///< #Ec fine mass inside each coarse element
    std::vector<Mandel6> C;                     ///< #Ec coarse tensors (Eq. 8 or an average)
    // Effective-tensor method only:
    Matrix h;                       ///< fine harmonic fields, fine num_dofs by n
    Matrix H;                       ///< the fields sampled at the coarse nodes
    std::vector<Mandel6> G_fine;    ///< #E fine mollifiers G_p
    std::vector<Mandel6> G_coarse;  ///< #Ec coarse mollifiers 𝔾_q used in Eq. 8
    std::vector<Mandel6> A;         ///< #Ec energy averages <G^T C G>_q used in Eq. 8
    /// Mixed boundary: coarse elements that fell back to the pure-Neumann mollifier, and the
    /// pure-Neumann fields behind them (empty if none fell back).
    std::vector<Index> fallback;
    Matrix h_neumann, H_neumann;
    std::vector<Mandel6> G_fine_neumann;
    Timings timings;  ///< phases "intersect", "harmonic", "tensors"
    Report report;
};

/// Runs a coarsening method on the scene's coarse mesh.
/// @param[in] method  "effective-tensor", "naive", "voigt" or "reuss"
/// @param[in] fine_factorization  optional: a factorization of the fine stiffness without the
///                    Dirichlet DOFs (fine.K without fine.bc.dofs, as scene::solve_static
///                    factorizes it). The harmonic solve of the mixed boundary (coarse.boundary
///                    "mixed") on a simplicial fine mesh, whose operator that is, then uses it
///                    instead of factorizing it again; other coarsenings ignore it.
/// @throws InvalidScene for an unknown method, a missing coarse.mesh or a bad coarse.* value
/// @throws Error if the coarse mesh is degenerate, does not overlap the fine mesh (e.g. other
///         units), misses part of it, holds an element without fine material or a node far
///         outside it, or if a coarse mollifier is singular (naming the coarse element)
Coarsening coarsening(const scene::Scene& scene, const scene::FineModel& fine,
                      const std::string& method,
                      const solve::SpdSolver* fine_factorization = nullptr);

/// The coarse model of a method (the CLI's `coarsen` calls this): coarse stiffness from one
/// anisotropic material per coarse element (fem::stiffness_matrix), lumped mass from the fine
/// density over the overlaps, to_fine = P, the barycentric embedding of the fine nodes (or the
/// linearized harmonic map, coarse.map), the fine load carried by it, f = P^T f_fine, and the
/// fine Dirichlet conditions carried by the barycentric embedding (carry_dirichlet; where they
/// hold coarse DOFs only in combination, the model's DOFs are the reduced ones w, u = T w, with
/// K = T^T K T, f = T^T f, to_fine = P T and mass = diag(T^T M T); report "conditions"), and
/// the outputs coarse_model.vtu (coarse mesh; cell fields C_voigt_IJ, density, E_x/E_y/E_z
/// directional Young's moduli, and for the effective-tensor method G_condition, plus fallback
/// for a mixed boundary) and, for the effective-tensor method, harmonic.vtu (fine mesh; point
/// fields h_xx, h_yy, ...). Timings: "intersect", "harmonic", "tensors", "assemble", "maps".
/// `fine_factorization` as for coarsening.
/// @throws everything coarsening throws
coarsen::CoarseModel build_coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                                        const std::string& method,
                                        const solve::SpdSolver* fine_factorization = nullptr);

/// The coarse model of a finished coarsening (build_coarse_model = this after coarsening).
coarsen::CoarseModel coarse_model(const scene::Scene& scene, const scene::FineModel& fine,
                                  Coarsening c);

}  // namespace coarsegrain::homogenize
