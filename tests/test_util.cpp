#include "test_util.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/QR>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

namespace coarsegrain::test {

double fitted_slope(const std::vector<double>& x, const std::vector<double>& y) {
    const Index n = static_cast<Index>(x.size());
    Eigen::MatrixXd A(n, 2);
    Eigen::VectorXd b(n);
    for (Index i = 0; i < n; ++i) {
        A(i, 0) = std::log(x[static_cast<std::size_t>(i)]);
        A(i, 1) = 1.0;
        b[i] = std::log(y[static_cast<std::size_t>(i)]);
    }
    return A.colPivHouseholderQr().solve(b)[0];
}

Matrix rigid_modes(const Matrix& X) {
    const Index n = static_cast<Index>(X.rows());
    const int dim = static_cast<int>(X.cols());
    const int nrot = dim == 3 ? 3 : 1;
    Matrix R = Matrix::Zero(dim * n, dim + nrot);
    for (Index i = 0; i < n; ++i) {
        for (int d = 0; d < dim; ++d) R(dim * i + d, d) = 1.0;
        if (dim == 2) {
            R(2 * i + 0, 2) = -X(i, 1);
            R(2 * i + 1, 2) = X(i, 0);
        } else {
            const Eigen::Vector3d x = X.row(i).transpose();
            for (int k = 0; k < 3; ++k) {
                const Eigen::Vector3d w = Eigen::Vector3d::Unit(k).cross(x);
                R.block(3 * i, 3 + k, 3, 1) = w;
            }
        }
    }
    return R;
}

Vector linear_field(const Matrix& X, const Matrix& A, const Eigen::VectorXd& b) {
    const Index n = static_cast<Index>(X.rows());
    const int dim = static_cast<int>(X.cols());
    Vector u(dim * n);
    for (Index i = 0; i < n; ++i) u.segment(dim * i, dim) = A * X.row(i).transpose() + b;
    return u;
}

void distort_interior(mesh::Mesh& mesh, double amount, unsigned seed) {
    const Matrix box = mesh::bounding_box(mesh);
    const int dim = mesh.dim();
    Eigen::VectorXd h(dim);
    for (int d = 0; d < dim; ++d)
        h[d] = mesh.grid ? mesh.grid->spacing()[d] : (box(1, d) - box(0, d)) / 10.0;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (Index v = 0; v < mesh.num_nodes(); ++v) {
        bool on_boundary = false;
        for (int d = 0; d < dim; ++d)
            on_boundary = on_boundary || std::abs(mesh.rest_positions(v, d) - box(0, d)) < 1e-12 ||
                          std::abs(mesh.rest_positions(v, d) - box(1, d)) < 1e-12;
        if (on_boundary) continue;
        for (int d = 0; d < dim; ++d) mesh.rest_positions(v, d) += amount * h[d] * U(rng);
    }
    mesh.grid.reset();  // no longer a regular grid
}

std::string temp_dir(const std::string& name) {
    namespace fs = std::filesystem;
    // ctest runs tests in parallel processes; the process id keeps their folders apart.
    const fs::path dir =
        fs::temp_directory_path() / "coarsegrain_tests" / std::to_string(::getpid()) / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir.string();
}

int run(const std::string& command, std::string* output) {
    FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return -1;
    std::array<char, 4096> buf{};
    std::string out;
    while (std::fgets(buf.data(), static_cast<int>(buf.size()), pipe)) out += buf.data();
    const int status = ::pclose(pipe);
    if (output) *output = out;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace coarsegrain::test
