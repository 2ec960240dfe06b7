#pragma once
/// @file Options of the effective-tensor coarsening and its baselines, apart from the method so
/// that scene loading can validate them before any work.

namespace coarsegrain::homogenize {

/// coarse.mass: the coarse model's mass, from the fine mass M and the coarse-to-fine map P.
enum class CoarseMass {
    /// Diagonal, m_c = Pᵀ (M 1): the lumped mass ∫ρ N_a around each coarse node from the fine
    /// density (Kharevych et al. 2009, Sec. 3, "Kinetic Energy"). P is a partition of unity that
    /// reproduces affine fields, so the total mass and the first moments are the fine ones.
    Lumped,
    /// The consistent mass of the coarse elements with their mean fine density (mass inside
    /// the element over its measure): exact total mass, but each element's mass sits at its
    /// centre of volume, not of mass.
    Consistent,
    /// M_c = Pᵀ M P: the kinetic energy of every coarse velocity is that of its fine image (the
    /// paper's future work). Sparse, with the couplings of PᵀP.
    Galerkin,
};

/// The scene's "coarse" keys the effective-tensor method and its baselines read.
struct Options {
    /// coarse.normals: "coarse" (default: the traction of Eq. 6 uses the normal of the nearest
    /// coarse boundary facet, Sec. 4.2) or "fine" (the fine facet's own normal).
    bool coarse_normals = true;
    /// coarse.boundary: "neumann" (default, Eq. 6) or "mixed" (Sec. 3.8: the harmonic
    /// displacements vanish on the scene's Dirichlet nodes; coarse elements whose mollifier is
    /// then singular fall back to the pure-Neumann one).
    bool mixed_boundary = false;
    /// coarse.map: "barycentric" (default) or "harmonic": which coarse-to-fine map becomes
    /// CoarseModel::to_fine (the harmonic one linearized, HarmonicMap::linearized). Only the
    /// effective-tensor method has harmonic fields; the baselines always embed barycentrically.
    /// With a mixed boundary where elements fell back, the map uses the pure-Neumann fields
    /// (the mixed ones are singular on those elements).
    bool harmonic_map = false;
    /// coarse.mass: "lumped" (default), "consistent" or "galerkin" (CoarseMass).
    CoarseMass mass = CoarseMass::Lumped;
};

}  // namespace coarsegrain::homogenize
