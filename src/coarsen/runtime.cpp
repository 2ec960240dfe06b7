#include "coarsegrain/coarsen/runtime.hpp"

#include <cmath>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/fem/dirichlet.hpp"
#include "coarsegrain/fem/stress.hpp"

namespace coarsegrain::coarsen {

FineMap::FineMap(SparseMatrix M)
    : rows_(M.rows()),
      cols_(M.cols()),
      matrix_(std::make_shared<const SparseMatrix>(std::move(M))),
      apply_([M = matrix_](const Vector& u) -> Vector { return *M * u; }) {}

FineMap::FineMap(Index rows, Index cols, Apply apply)
    : rows_(rows), cols_(cols), apply_(std::move(apply)) {}

Vector FineMap::apply(const Vector& u) const {
    CG_VERIFY(u.size() == cols_, "fine map: {} coarse values for {} coarse DOFs", u.size(), cols_);
    if (!apply_) return Vector::Zero(rows_);
    Vector out = apply_(u);
    CG_VERIFY(out.size() == rows_, "fine map: {} fine values for {} fine DOFs", out.size(), rows_);
    return out;
}

nlohmann::json errors_json(const Errors& e) {
    return {{"energy_rel", e.energy_rel},
            {"energy_over_load", e.energy_over_load},
            {"l2_rel", e.l2_rel},
            {"max_displacement_rel", e.max_displacement_rel},
            {"compliance_ratio", e.compliance_ratio},
            {"stress_rel", e.stress_rel}};
}

namespace {

double max_nodal_norm(const Vector& u, int dim) {
    return Eigen::Map<const Matrix>(u.data(), dim, u.size() / dim).colwise().norm().maxCoeff();
}

double energy_norm(const SparseMatrix& K, const Vector& v) {
    return std::sqrt(std::max(0.0, v.dot(K * v)));
}

/// sqrt(sum_e |e| |sigma_c,e - sigma_e|^2 / sum_e |e| |sigma_e|^2), Frobenius norms of the
/// element stresses (Mandel vectors carry them: |s|_2 = |sigma|_F).
double stress_error(const scene::FineModel& fine, const Vector& u, const Vector& u_c) {
    const Matrix s = fem::element_stress(fine.mesh, fine.materials, u).stress;
    const Matrix s_c = fem::element_stress(fine.mesh, fine.materials, u_c).stress;
    double num = 0, den = 0;
    for (Index e = 0; e < fine.mesh.num_elements(); ++e) {
        const double v = mesh::element_measure(fine.mesh, e);
        num += v * (s_c.row(e) - s.row(e)).squaredNorm();
        den += v * s.row(e).squaredNorm();
    }
    return den > 0 ? std::sqrt(num / den) : 0.0;
}

}  // namespace

CoarseSolution solve_coarse(const CoarseModel& model, const solve::SolverOptions& options,
                            Timings* timings) {
    const Index n = model.K.rows();
    CG_VERIFY(model.K.cols() == n && model.f.size() == n && model.to_fine.cols() == n,
              "coarse model {}: K is {}x{}, f has {} entries, to_fine has {} columns", model.method,
              model.K.rows(), model.K.cols(), model.f.size(), model.to_fine.cols());
    CoarseSolution s;
    s.u = fem::solve_static(model.K, model.f, model.bc, options, timings);
    s.strain_energy = 0.5 * s.u.dot(model.K * s.u);
    s.u_fine = model.to_fine * s.u;
    return s;
}

fem::CorotatedModel corotated_model(const CoarseModel& model, fem::CorotationFrame frame) {
    CG_VERIFY(model.element_model.has_value(),
              "coarse model {}: corotated kinematics need an element model (a coarse mesh and "
              "its tensors); the hierarchy's coarse DOFs are none",
              model.method);
    const ElementModel& e = *model.element_model;
    fem::CorotatedModel corotated(e.mesh, e.materials, fem::Formulation::Standard, frame,
                                  e.dof_map);
    CG_VERIFY(corotated.num_dofs() == model.K.rows(),
              "coarse model {}: {} element model DOFs for {} DOFs", model.method,
              corotated.num_dofs(), model.K.rows());
    return corotated;
}

solve::SolverOptions node_solver_options(const CoarseModel& model,
                                         const solve::SolverOptions& options) {
    solve::SolverOptions node_options = options;
    if (const auto& e = model.element_model)
        node_options.node_dofs = e->dof_map.size() ? 1 : e->mesh.dim();
    return node_options;
}

CoarseSolution solve_coarse_corotated(const CoarseModel& model,
                                      const sim::CorotationOptions& corotation,
                                      const solve::SolverOptions& options, Timings* timings) {
    const Index n = model.K.rows();
    CG_VERIFY(model.f.size() == n && model.to_fine.cols() == n,
              "coarse model {}: K is {}x{}, f has {} entries, to_fine has {} columns", model.method,
              model.K.rows(), model.K.cols(), model.f.size(), model.to_fine.cols());
    const fem::CorotatedModel corotated = corotated_model(model, corotation.frame);
    const solve::SolverOptions node_options = node_solver_options(model, options);
    CoarseSolution s;
    try {
        sim::CorotatedSolution c = sim::solve_corotated_static(corotated, model.f, model.bc,
                                                               corotation, node_options, timings);
        s.u = std::move(c.u);
        s.strain_energy = c.energy;
        s.newton = std::move(c.report);
    } catch (const Error& error) {
        throw Error(fmt::format("coarse model {}: {}", model.method, error.what()));
    }
    s.u_fine = model.to_fine * s.u;
    return s;
}

Errors compare(const scene::FineModel& fine, const Vector& u, const Vector& u_c) {
    const Index n = fine.mesh.num_dofs();
    CG_VERIFY(u.size() == n && u_c.size() == n,
              "compare: the fine model has {} DOFs, the solutions {} and {}", n, u.size(),
              u_c.size());
    const int dim = fine.mesh.dim();
    const double u_norm = u.norm(), u_energy = energy_norm(fine.K, u);
    const double u_max = max_nodal_norm(u, dim), compliance = fine.f.dot(u);
    CG_VERIFY(u_norm > 0 && u_energy > 0 && compliance != 0,
              "compare: the fine solution is zero (no load?)");
    const Vector e = u_c - u;
    Errors r;
    r.energy_rel = energy_norm(fine.K, e) / u_energy;
    // The load on the free DOFs: loads at Dirichlet DOFs do no work and never reach u.
    Vector f_free = fine.f;
    for (const Index dof : fine.bc.dofs) f_free[dof] = 0;
    r.energy_over_load = energy_norm(fine.K, e) / f_free.norm();
    r.l2_rel = e.norm() / u_norm;
    r.max_displacement_rel = std::abs(max_nodal_norm(u_c, dim) - u_max) / u_max;
    r.compliance_ratio = fine.f.dot(u_c) / compliance;
    r.stress_rel = stress_error(fine, u, u_c);
    return r;
}

}  // namespace coarsegrain::coarsen
