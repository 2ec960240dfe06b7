#pragma once
// Shared by the binding files of coarsegrain._core: NumPy / SciPy views of the C++ objects'
// storage, and the Python-side objects (each holds what its arrays view; a view keeps its
// Python owner alive).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "coarsegrain/coarsen/fine_run.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/mra/multilevel_solver.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "interrupt.hpp"

namespace coarsegrain::python {

namespace py = pybind11;
namespace cg = coarsegrain;

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<long long, py::array::c_style | py::array::forcecast>;

inline py::object json_to_python(const nlohmann::json& j) {
    return py::module_::import("json").attr("loads")(j.dump());
}

// A read-only NumPy view of the values at `data`, kept alive by `owner`.
template <class T>
py::array view(const T* data, std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides,
               py::handle owner) {
    py::array a(py::dtype::of<T>(), std::move(shape), std::move(strides), data, owner);
    a.attr("setflags")(py::arg("write") = false);
    return a;
}

template <class T>
py::array vector_view(const T* data, py::ssize_t n, py::handle owner) {
    return view(data, {n}, {static_cast<py::ssize_t>(sizeof(T))}, owner);
}

inline py::array vector_view(const cg::Vector& v, py::handle owner) {
    return vector_view(v.data(), v.size(), owner);
}

// #rows by #cols view of an Eigen matrix (column-major: Fortran strides).
inline py::array matrix_view(const cg::Matrix& m, py::handle owner) {
    const auto s = static_cast<py::ssize_t>(sizeof(double));
    return view(m.data(), {m.rows(), m.cols()}, {s, s * m.rows()}, owner);
}

inline py::array index_matrix_view(const cg::IndexMatrix& m, py::handle owner) {
    const auto s = static_cast<py::ssize_t>(sizeof(Index));
    return view(m.data(), {m.rows(), m.cols()}, {s * m.cols(), s}, owner);
}

// A scipy.sparse.csc_matrix over the compressed storage of M (compressed; owned by `owner`).
inline py::object scipy_view(const cg::SparseMatrix& M, py::handle owner) {
    CG_VERIFY(M.isCompressed(), "internal: a sparse matrix handed to Python is not compressed");
    const py::ssize_t nnz = M.nonZeros();
    py::tuple storage = py::make_tuple(vector_view(M.valuePtr(), nnz, owner),
                                       vector_view(M.innerIndexPtr(), nnz, owner),
                                       vector_view(M.outerIndexPtr(), M.cols() + 1, owner));
    return py::module_::import("scipy.sparse")
        .attr("csc_matrix")(storage, py::arg("shape") = py::make_tuple(M.rows(), M.cols()),
                            py::arg("copy") = false);
}

inline cg::SparseMatrix compressed(cg::SparseMatrix M) {
    M.makeCompressed();
    return M;
}

inline py::array_t<double> to_numpy(const cg::Vector& v) {
    py::array_t<double> a(v.size());
    std::copy(v.data(), v.data() + v.size(), a.mutable_data());
    return a;
}

inline cg::Vector from_numpy(const DoubleArray& a, Index size, const char* what) {
    CG_VERIFY(
        a.ndim() == 1 && a.shape(0) == size, "{}: expected a vector of {} values, got shape {}",
        what, size,
        py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))
            .cast<std::string>());
    return Eigen::Map<const cg::Vector>(a.data(), size);
}

// A #rows x cols matrix from a 2-D array (copied: NumPy's C order into Eigen's column-major).
inline cg::Matrix columns_from_numpy(const DoubleArray& a, Index rows) {
    CG_VERIFY(a.ndim() == 2 && a.shape(0) == rows,
              "to_fine @ U: expected a {} x k array (one coarse vector per column), got {} "
              "dimensions of shape ({})",
              rows, a.ndim(), a.ndim() > 0 ? a.shape(0) : 0);
    return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        a.data(), rows, a.shape(1));
}

// A scipy.sparse.csc_matrix that takes over a sparse matrix (compressed first; no copy).
inline py::object owned_sparse(cg::SparseMatrix&& M) {
    auto* held = new cg::SparseMatrix(std::move(M));
    held->makeCompressed();
    py::capsule owner(held, [](void* p) { delete static_cast<cg::SparseMatrix*>(p); });
    return scipy_view(*held, owner);
}

// A NumPy array that takes over a matrix (no copy): #rows x #cols with Fortran strides, or with
// `transposed` #cols x #rows with C strides (row i is column i of m). Writable.
inline py::array owned_matrix(cg::Matrix&& m, bool transposed = false) {
    auto* held = new cg::Matrix(std::move(m));
    py::capsule owner(held, [](void* p) { delete static_cast<cg::Matrix*>(p); });
    const auto s = static_cast<py::ssize_t>(sizeof(double));
    if (transposed)
        return py::array(py::dtype::of<double>(), {held->cols(), held->rows()},
                         {s * held->rows(), s}, held->data(), owner);
    return py::array(py::dtype::of<double>(), {held->rows(), held->cols()}, {s, s * held->rows()},
                     held->data(), owner);
}

struct PyScene {
    std::shared_ptr<const cg::scene::Scene> scene;
};

/// A fine model, and once solved (solve_fine) its solution. The model lives in `run`.
struct PyFine {
    std::shared_ptr<const cg::scene::Scene> scene;
    std::shared_ptr<cg::coarsen::FineRun> run;
    bool solved = false;
    std::once_flag mass_once;
    cg::SparseMatrix M;  ///< fine mass, on request
    std::mutex mutex;    ///< held while the run changes (solve, warp)

    const cg::SparseMatrix& mass() {
        std::call_once(mass_once,
                       [this] { M = compressed(cg::scene::mass_matrix(*scene, run->model)); });
        return M;
    }
};

/// A hierarchy (the mra methods' coarse model holds one) and its multilevel solver, made on the
/// first solve and kept with its factorizations.
struct PyHierarchy {
    std::shared_ptr<const cg::mra::Hierarchy> h;
    std::unique_ptr<cg::mra::MultilevelSolver> solver;
    std::mutex mutex;  ///< held while the solver is used (it is not thread-safe)
};

struct PyCoarse {
    std::shared_ptr<PyFine> fine;
    cg::coarsen::CoarseModel model;
    std::once_flag mass_once;
    std::optional<cg::SparseMatrix> M;
    std::once_flag hierarchy_once;
    std::shared_ptr<PyHierarchy> hierarchy;  ///< of model.hierarchy, made on first use

    /// The model's hierarchy (one object for every call), or null for a method without one.
    std::shared_ptr<PyHierarchy> python_hierarchy() {
        std::call_once(hierarchy_once, [this] {
            if (!model.hierarchy) return;
            hierarchy = std::make_shared<PyHierarchy>();
            hierarchy->h = model.hierarchy;
        });
        return hierarchy;
    }
};

inline py::dict timings_dict(const cg::Timings& t) {
    py::dict d;
    for (const auto& [phase, seconds] : t.entries())
        d[py::str(phase)] = (d.contains(phase) ? d[py::str(phase)].cast<double>() : 0.0) + seconds;
    return d;
}

inline std::shared_ptr<PyFine> build_fine(const std::shared_ptr<const cg::scene::Scene>& scene) {
    auto fine = std::make_shared<PyFine>();
    fine->scene = scene;
    fine->run = std::make_shared<cg::coarsen::FineRun>();
    run_interruptible([&] {
        fine->run->model = cg::scene::build_fine_model(*scene, &fine->run->timings);
        fine->run->model.K.makeCompressed();
    });
    return fine;
}

// The scene with its "coarse" block keys replaced by those of a JSON object (none if empty).
inline std::shared_ptr<const cg::scene::Scene> with_overrides(
    const std::shared_ptr<const cg::scene::Scene>& base, const std::string& overrides) {
    if (overrides.empty()) return base;
    const nlohmann::json o = cg::scene::parse_json(overrides, base->source + " (options)");
    return std::make_shared<const cg::scene::Scene>(cg::scene::with_coarse_overrides(*base, o));
}

/// simulate() and modes() (dynamics.cpp).
void bind_dynamics(py::module_& m);
/// The hierarchy's levels and multilevel solves (hierarchy.cpp).
void bind_hierarchy(py::module_& m);

}  // namespace coarsegrain::python
