#include "export.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <optional>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/io/inp_export.hpp"
#include "coarsegrain/io/matrix_market.hpp"
#include "coarsegrain/sim/dynamics.hpp"

namespace coarsegrain::app {

namespace {

namespace fs = std::filesystem;

/// Coarse-to-fine maps larger than this (rows x columns) are not formed for export: the
/// hierarchy's is nearly dense (64x16x16 hexes, 3 levels: 1275 x 55488).
constexpr double kMaxExportedMapEntries = 5e7;

/// Writes a model that is no element model (the hierarchy) as Matrix Market files in `dir`:
/// coarse_K.mtx, coarse_M.mtx (`mass`, a run's coarse mass, or the coarse mass of the fine mass
/// of the scene's "dynamics", or consistent), coarse_f.mtx, coarse_dirichlet.mtx (if it has
/// conditions: rows of DOF, 1-based, and value) and to_fine.mtx (the coarse-to-fine map, formed
/// column by column, unless it has more than kMaxExportedMapEntries entries: then a note on
/// stderr).
void write_matrices(const scene::Scene& sc, const scene::FineModel& fine,
                    const coarsen::CoarseModel& coarse, const fs::path& dir,
                    const SparseMatrix* mass) {
    const std::string about = fmt::format("coarsegrain {} model of {}", coarse.method, sc.source);
    io::write_matrix_market((dir / "coarse_K.mtx").string(), coarse.K,
                            about + "\ncoarse stiffness K, coarse DOFs square");
    io::write_matrix_market((dir / "coarse_f.mtx").string(), Matrix(coarse.f),
                            about + "\ncoarse load f: K u = f");
    if (mass || coarse.mass) {
        const SparseMatrix M = mass ? *mass : coarse.mass(scene::mass_matrix(sc, fine));
        io::write_matrix_market((dir / "coarse_M.mtx").string(), M,
                                about + "\ncoarse mass M, coarse DOFs square");
    }
    if (!coarse.bc.dofs.empty()) {
        Matrix d(static_cast<Index>(coarse.bc.dofs.size()), 2);
        for (Index i = 0; i < d.rows(); ++i) {
            d(i, 0) = static_cast<double>(coarse.bc.dofs[static_cast<std::size_t>(i)] + 1);
            d(i, 1) = coarse.bc.values[i];
        }
        io::write_matrix_market((dir / "coarse_dirichlet.mtx").string(), d,
                                about + "\nprescribed coarse DOFs (1-based) and their values");
    }
    const coarsen::FineMap& map = coarse.to_fine;
    if (static_cast<double>(map.rows()) * static_cast<double>(map.cols()) >
        kMaxExportedMapEntries) {
        std::fprintf(stderr,
                     "coarsegrain: --export inp: %s/to_fine.mtx not written: the %ld x %ld "
                     "coarse-to-fine map is nearly dense, more than %.0g entries\n",
                     dir.c_str(), static_cast<long>(map.rows()), static_cast<long>(map.cols()),
                     kMaxExportedMapEntries);
        return;
    }
    std::vector<Eigen::Triplet<double, Index>> entries;
    for (Index j = 0; j < map.cols(); ++j) {
        const Vector column = map * Vector(Vector::Unit(map.cols(), j));
        for (Index i = 0; i < column.size(); ++i)
            if (column[i] != 0) entries.emplace_back(i, j, column[i]);
    }
    SparseMatrix T(map.rows(), map.cols());
    T.setFromTriplets(entries.begin(), entries.end());
    io::write_matrix_market((dir / "to_fine.mtx").string(), T,
                            about + "\ncoarse-to-fine map: u_fine = T u (fine DOFs x coarse DOFs)");
}

}  // namespace

void write_export(const scene::Scene& sc, const scene::FineModel& fine,
                  const coarsen::CoarseModel& coarse, const fs::path& dir,
                  const SparseMatrix* mass) {
    if (!coarse.element_model) {
        write_matrices(sc, fine, coarse, dir, mass);
        return;
    }
    const coarsen::ElementModel& e = *coarse.element_model;
    CG_VERIFY(e.dof_map.size() == 0,
              "--export inp: the {} model holds its Dirichlet conditions on combinations of its "
              "nodes' DOFs (no coarse node lies where the fine ones are prescribed), which a deck "
              "of nodes and elements cannot state; put coarse nodes on the prescribed faces",
              coarse.method);
    std::optional<io::CalculixDynamics> dynamics;
    if (mass) {
        const sim::DynamicsOptions& o = *sc.dynamics;
        dynamics.emplace();
        dynamics->dt = o.dt;
        dynamics->steps = o.steps;
        dynamics->output_every = o.output_every;
        if (mass->nonZeros() == mass->rows())
            dynamics->lumped_mass = mass->diagonal();
        else
            std::fprintf(stderr,
                         "coarsegrain: --export inp: the %s model's coarse mass is not lumped, "
                         "which *MASS elements cannot state; its deck takes CalculiX's mass of "
                         "the elements' densities instead (on C3D4 integrated at one point)\n",
                         coarse.method.c_str());
        if (!o.initial_velocity.isZero())
            dynamics->initial_velocity = sim::uniform_field(coarse.K.rows(), o.initial_velocity);
    }
    io::write_calculix_deck(
        (dir / "coarse_model.inp").string(), e.mesh, e.materials, coarse.f, coarse.bc, sc.plane,
        fmt::format("coarsegrain {} model of {}", coarse.method, sc.source), dynamics);
}

void check_dynamic_export(const scene::Scene& sc) {
    const sim::DynamicsOptions& o = *sc.dynamics;
    CG_VERIFY_AS(InvalidScene, sc.kinematics == sim::Kinematics::Linear,
                 "{}: kinematics: --export inp writes linear models; CalculiX's geometrically "
                 "nonlinear analysis (NLGEOM) is another model than corotated elasticity",
                 sc.source);
    CG_VERIFY_AS(InvalidScene, o.start == sim::Start::Rest,
                 "{}: dynamics.start: --export inp writes runs that start from rest", sc.source);
    CG_VERIFY_AS(InvalidScene, o.rayleigh_mass == 0 && o.rayleigh_stiffness == 0,
                 "{}: dynamics.damping: --export inp does not write Rayleigh damping", sc.source);
}

}  // namespace coarsegrain::app
