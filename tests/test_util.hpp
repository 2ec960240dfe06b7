#pragma once
/// @file Helpers shared by the tests.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "coarsegrain/common/error.hpp"
#include "coarsegrain/common/types.hpp"
#include "coarsegrain/mesh/mesh.hpp"

namespace coarsegrain::test {

/// The rigid motions of a point set (#V by dim): dim translations and dim(dim-1)/2
/// infinitesimal rotations, as columns of a (dim*#V) by (3 or 6) matrix (interleaved DOFs).
Matrix rigid_modes(const Matrix& X);

/// The interleaved field u(x) = A x + b at every node.
Vector linear_field(const Matrix& X, const Matrix& A, const Eigen::VectorXd& b);

/// Moves every interior node of a grid mesh by a random offset of up to `amount` times the grid
/// spacing (fixed seed), keeping elements valid. Boundary nodes stay put.
void distort_interior(mesh::Mesh& mesh, double amount, unsigned seed = 1);

/// Least-squares slope of log(y) against log(x) (x, y > 0, same length >= 2): the rate of a
/// convergence study.
double fitted_slope(const std::vector<double>& x, const std::vector<double>& y);

/// A fresh empty temporary folder for one test, private to this process.
std::string temp_dir(const std::string& name);

/// Runs a shell command, returns its exit code; stdout+stderr go to `output` if non-null.
int run(const std::string& command, std::string* output = nullptr);

/// Runs f and expects a coarsegrain::Error whose message contains `text`.
template <class F>
void expect_error(F&& f, const std::string& text) {
    try {
        f();
        ADD_FAILURE() << "no error, expected one containing: " << text;
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(text), std::string::npos)
            << "message: " << e.what() << "\nexpected to contain: " << text;
    }
}

}  // namespace coarsegrain::test
