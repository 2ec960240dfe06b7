#pragma once
/// @file Preconditioned conjugate gradients for sparse symmetric positive-definite systems, with
/// a preconditioner supplied by a higher layer (the material-adapted hierarchy's multigrid cycle,
/// mra/preconditioner.hpp).
#include <functional>
#include <memory>
#include <string>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"

namespace coarsegrain::solve {

/// An iteration did not converge (conjugate gradients: the matrix may be singular or too
/// ill-conditioned, or the iteration or time limit was reached).
class NotConverged : public ErrorOf<NotConverged> {
  public:
    using ErrorOf::ErrorOf;
};

/// A symmetric positive-definite preconditioner M^{-1} ≈ A^{-1}.
class Preconditioner {
  public:
    virtual ~Preconditioner() = default;
    /// z = M^{-1} r (size n).
    virtual Vector apply(const Vector& r) const = 0;
};

/// Builds a preconditioner for the matrix given (both triangles stored, compressed). The matrix
/// outlives the preconditioner.
using PreconditionerFactory = std::function<std::unique_ptr<Preconditioner>(const SparseMatrix& A)>;

/// y = A x for a symmetric A with both triangles stored (compressed, column-major): each entry of
/// y is the dot product of a column with x, so the product runs in parallel over the columns
/// (OpenMP), with no write conflicts.
/// @throws Error on a size mismatch
void symmetric_multiply(const SparseMatrix& A, const Vector& x, Vector& y);

/// Options of pcg.
struct PcgOptions {
    double tolerance = 1e-8;  ///< stop when ||b - A x|| <= tolerance ||b||
    int max_iterations = 1000;
    double time_limit = 0;  ///< seconds (0: none)
    /// Name in progress lines and errors ("mra-pcg").
    std::string name = "pcg";
};

/// How a pcg solve went.
struct PcgReport {
    int iterations = 0;
    double relative_residual = 0;  ///< ||b - A x|| / ||b|| of the recurrence
    double seconds = 0;
};

/// Solves A x = b by conjugate gradients preconditioned with M (Hestenes-Stiefel recurrence,
/// x0 = 0). A is symmetric positive definite, both triangles stored. A progress line (see
/// progress_line) reports the relative residual every 10 s of iterating.
/// @param[out] report  iterations, final relative residual and seconds (if given)
/// @throws NotConverged naming the iterations, residual and tolerance if the tolerance is not
///         reached within max_iterations or time_limit, or if a search direction has no positive
///         curvature (A or M not positive definite); Error on a size mismatch or a non-finite b
Vector pcg(const SparseMatrix& A, const Vector& b, const Preconditioner& M,
           const PcgOptions& options, PcgReport* report = nullptr);

}  // namespace coarsegrain::solve
