#pragma once
/// @file Dirichlet conditions, eliminated from the system (not a penalty).
#include <vector>

#include "coarsegrain/common/progress.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/solve/spd_solver.hpp"

namespace coarsegrain::fem {

/// Prescribed DOF values. dofs is sorted and unique; values has the same length.
struct Dirichlet {
    std::vector<Index> dofs;
    Vector values;

    /// Prescribes all dim components of each node (dim = value.size(), DOF dim*node + d).
    /// Later calls override earlier values of the same DOF.
    void fix_nodes(const std::vector<Index>& nodes, const Eigen::VectorXd& value);
    /// Prescribes one component (0..dim-1) of each node, e.g. a roller or symmetry condition.
    /// Later calls override earlier values of the same DOF.
    void fix_component(const std::vector<Index>& nodes, int dim, int component, double value);
    bool empty() const { return dofs.empty(); }
};

/// The system restricted to the free DOFs: K_ff u_f = f_f - K_fd u_d.
struct ReducedSystem {
    SparseMatrix K;         ///< free by free block
    Vector rhs;             ///< f_f - K_fd u_d
    IndexVector free_dofs;  ///< reduced index -> full DOF
};

/// The DOFs of an n-DOF model that bc does not prescribe, ascending.
/// @throws Error if bc.dofs is not sorted, unique and in 0..n-1
IndexVector free_dofs(Index n, const Dirichlet& bc);
/// The same for a sorted list of fixed DOFs.
/// @throws Error if fixed is not sorted, unique and in 0..n-1
IndexVector free_dofs(Index n, const std::vector<Index>& fixed);

/// Eliminates the Dirichlet DOFs from K u = f in O(nnz(K)): K_ff is copied column by column
/// (K must be compressed, both triangles stored) and only the prescribed columns are read for
/// K_fd u_d.
/// @throws Error if sizes disagree or bc.dofs is not sorted, unique and in range
ReducedSystem reduce(const SparseMatrix& K, const Vector& f, const Dirichlet& bc);

/// Full solution from the free-DOF solution and the prescribed values.
Vector expand(const ReducedSystem& sys, const Vector& u_free, const Dirichlet& bc, Index num_dofs);

/// Solves K u = f with the conditions bc eliminated: reduce, one SpdSolver factorization of
/// K_ff, expand (the one static solve of fine and coarse models). Phases "factorize" and
/// "solve" go to `timings`.
/// @return the full solution, num_dofs = K.rows() entries, prescribed values included
/// @throws Error as reduce; NotPositiveDefinite if the conditions do not hold the structure
Vector solve_static(const SparseMatrix& K, const Vector& f, const Dirichlet& bc,
                    const solve::SolverOptions& options, Timings* timings = nullptr);
/// The same with `solver` (and its options), which keeps the factorization of K_ff for further
/// solves with the same conditions.
Vector solve_static(const SparseMatrix& K, const Vector& f, const Dirichlet& bc,
                    solve::SpdSolver& solver, Timings* timings = nullptr);

}  // namespace coarsegrain::fem
