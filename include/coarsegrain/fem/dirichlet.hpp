#pragma once
/// @file Dirichlet conditions, eliminated from the system (not a penalty).
#include <vector>

#include "coarsegrain/common/types.hpp"

namespace coarsegrain::fem {

/// Prescribed DOF values. dofs is sorted and unique; values has the same length.
struct Dirichlet {
    std::vector<Index> dofs;
    Vector values;

    /// Prescribes all dim components of each node. Later calls override earlier values.
    void fix_nodes(const std::vector<Index>& nodes, const Eigen::VectorXd& value);
    bool empty() const { return dofs.empty(); }
};

/// The system restricted to the free DOFs: K_ff u_f = f_f - K_fd u_d.
struct ReducedSystem {
    SparseMatrix K;        ///< free by free block
    Vector rhs;            ///< f_f - K_fd u_d
    IndexVector free_dofs; ///< reduced index -> full DOF
};

/// Eliminates the Dirichlet DOFs from K u = f.
ReducedSystem reduce(const SparseMatrix& K, const Vector& f, const Dirichlet& bc);

/// Full solution from the free-DOF solution and the prescribed values.
Vector expand(const ReducedSystem& sys, const Vector& u_free, const Dirichlet& bc, Index num_dofs);

}  // namespace coarsegrain::fem
