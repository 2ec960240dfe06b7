#pragma once
/// @file `--export inp` of `coarsen` and `simulate`: a coarse model written for other codes.
#include <filesystem>

#include "coarsegrain/coarsen/coarse_model.hpp"
#include "coarsegrain/scene/scene.hpp"

namespace coarsegrain::app {

/// Files `coarsen` and `simulate` write on request (command-line options).
struct Exports {
    /// --export inp: each coarse model for other codes (write_export): DIR[/<method>]/
    /// coarse_model.inp, an element model as a CalculiX / Abaqus deck; the hierarchy (mra*),
    /// which is no element model, as Matrix Market files instead.
    bool calculix = false;
};

/// Writes a coarse model for use elsewhere into `dir`:
/// - an element model (effective tensors, baselines): coarse_model.inp, a CalculiX / Abaqus deck
///   (io::write_calculix_deck) with a *STATIC step, or with `mass` (a dynamic run's coarse mass)
///   a *DYNAMIC step of the scene's "dynamics" (lumped masses as *MASS elements; a mass that is
///   not diagonal cannot be stated per node, so the deck then takes CalculiX's mass of the
///   elements' densities, and a note on stderr says so);
/// - the hierarchy: Matrix Market files coarse_K.mtx, coarse_M.mtx (`mass`, or the coarse mass
///   of the fine mass of the scene's "dynamics" or consistent), coarse_f.mtx,
///   coarse_dirichlet.mtx (if it has conditions: rows of 1-based DOF and value) and to_fine.mtx
///   (the coarse-to-fine map, formed column by column unless it has more than 5e7 entries:
///   then a note on stderr).
/// @throws Error naming the method if its Dirichlet conditions hold DOFs in combination (no
///         deck of nodes and elements states them), or a file cannot be written
void write_export(const scene::Scene& sc, const scene::FineModel& fine,
                  const coarsen::CoarseModel& coarse, const std::filesystem::path& dir,
                  const SparseMatrix* mass = nullptr);

/// Checks, before any work, that `simulate --export inp` can state the scene's run in a deck:
/// linear kinematics (CalculiX's NLGEOM is another model than corotated elasticity), a start
/// from rest, no Rayleigh damping.
/// @throws InvalidScene naming the key otherwise
void check_dynamic_export(const scene::Scene& sc);

}  // namespace coarsegrain::app
