#include "coarsegrain/solve/pcg.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "coarsegrain/common/progress.hpp"

namespace coarsegrain::solve {

namespace {
/// Products with fewer stored entries run on one thread: a parallel region costs a barrier, which
/// waits a scheduler time slice when another process holds a core (V-cycles on a 16^2 grid took
/// 68x longer on two threads than on one beside a concurrent build), and the product of a
/// smaller matrix takes well under a millisecond.
constexpr Index kParallelNonzeros = 200000;
}  // namespace

void symmetric_multiply(const SparseMatrix& A, const Vector& x, Vector& y) {
    CG_VERIFY(A.rows() == A.cols() && A.cols() == x.size() && A.isCompressed(),
              "symmetric_multiply: a {}x{} matrix (compressed: {}) times a vector of {}", A.rows(),
              A.cols(), A.isCompressed(), x.size());
    y.resize(A.rows());
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    const double* values = A.valuePtr();
    const Index n = A.cols();
#pragma omp parallel for schedule(static) if (A.nonZeros() >= kParallelNonzeros)
    for (Index j = 0; j < n; ++j) {
        double sum = 0;
        for (int p = outer[j]; p < outer[j + 1]; ++p) sum += values[p] * x[inner[p]];
        y[j] = sum;
    }
}

Vector pcg(const SparseMatrix& A, const Vector& b, const Preconditioner& M,
           const PcgOptions& options, PcgReport* report) {
    CG_VERIFY(A.rows() == A.cols() && b.size() == A.rows(),
              "{}: a {}x{} matrix and a right-hand side of {}", options.name, A.rows(), A.cols(),
              b.size());
    CG_VERIFY(b.allFinite(), "{}: the right-hand side has a non-finite value", options.name);
    using clock = std::chrono::steady_clock;
    const auto start = clock::now();
    const auto seconds = [&] {
        return std::chrono::duration<double>(clock::now() - start).count();
    };
    const double b_norm = b.norm();
    Vector x = Vector::Zero(b.size());
    PcgReport r_out;
    const auto finish = [&](int iterations, double residual) {
        r_out.iterations = iterations;
        r_out.relative_residual = residual;
        r_out.seconds = seconds();
        if (report) *report = r_out;
    };
    if (b_norm == 0) {
        finish(0, 0);
        return x;
    }
    Vector r = b;
    Vector z = M.apply(r);
    Vector p = z;
    Vector Ap(b.size());
    double rz = r.dot(z);
    double residual = 1;
    double next_report = 10;
    for (int it = 1;; ++it) {
        symmetric_multiply(A, p, Ap);
        const double curvature = p.dot(Ap);
        CG_VERIFY_AS(
            NotConverged, curvature > 0 && rz > 0,
            "{}: conjugate gradients broke down at iteration {} (n = {}): p^T A p = {:.3g}, "
            "r^T M^-1 r = {:.3g}; the matrix or the preconditioner is not positive "
            "definite",
            options.name, it, b.size(), curvature, rz);
        const double alpha = rz / curvature;
        x += alpha * p;
        r -= alpha * Ap;
        residual = r.norm() / b_norm;
        if (residual <= options.tolerance) {
            finish(it, residual);
            return x;
        }
        const double elapsed = seconds();
        CG_VERIFY_AS(NotConverged, it < options.max_iterations,
                     "{}: no convergence in {} iterations (n = {}): relative residual {:.3g}, "
                     "tolerance {:.3g}; raise solver.max_iterations or use cholmod",
                     options.name, it, b.size(), residual, options.tolerance);
        CG_VERIFY_AS(NotConverged, options.time_limit <= 0 || elapsed < options.time_limit,
                     "{}: the time limit of {:.3g} s was reached after {} iterations (n = {}): "
                     "relative residual {:.3g}, tolerance {:.3g}",
                     options.name, options.time_limit, it, b.size(), residual, options.tolerance);
        if (elapsed >= next_report) {
            progress_line(fmt::format("{}: iteration {}, relative residual {:.3g}", options.name,
                                      it, residual));
            next_report += 10;
        }
        z = M.apply(r);
        const double rz_next = r.dot(z);
        p = z + (rz_next / rz) * p;
        rz = rz_next;
    }
}

}  // namespace coarsegrain::solve
