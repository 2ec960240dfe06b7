// The material-adapted hierarchy of the mra methods (Chen et al. 2019, Algorithm 1): its levels
// as scipy.sparse matrices and its multilevel solves (mra/hierarchy.hpp,
// mra/multilevel_solver.hpp).
//
// Copies: C̃^k (kept by runs, mra::RunMatrix), A^k and B^k (kept as lower triangles) and Φ^k
// (computed) are new matrices; W^k, C^k, C^{k,†} and A^q are views of the hierarchy's storage.
#include "coarsegrain/mra/hierarchy.hpp"

#include <pybind11/stl.h>

#include "bindings.hpp"

namespace coarsegrain::python {

namespace {

/// Level k (1 <= k < q) of a hierarchy; keeps the hierarchy alive.
struct PyLevel {
    std::shared_ptr<PyHierarchy> hierarchy;
    int k = 1;
    const mra::Level& level() const { return hierarchy->h->level(k); }
};

// A view of a compressed matrix owned by `owner`, or a compressed copy.
py::object sparse_out(const SparseMatrix& M, py::handle owner) {
    return M.isCompressed() ? scipy_view(M, owner) : owned_sparse(SparseMatrix(M));
}

// Index vector (int32) view.
py::array index_view(const IndexVector& v, py::handle owner) {
    return vector_view(v.data(), v.size(), owner);
}

// The hierarchy's multilevel solver, made on first use; locked without the GIL (the thread that
// holds the lock needs the GIL to finish its call).
template <class F>
Vector with_solver(PyHierarchy& h, F f) {
    std::unique_lock<std::mutex> lock(h.mutex, std::defer_lock);
    {
        const py::gil_scoped_release release;
        lock.lock();
    }
    return run_interruptible([&] {
        if (!h.solver) h.solver = std::make_unique<mra::MultilevelSolver>(*h.h);
        return f(*h.solver);
    });
}

}  // namespace

void bind_hierarchy(py::module_& m) {
    py::class_<PyHierarchy, std::shared_ptr<PyHierarchy>>(
        m, "Hierarchy",
        R"(The material-adapted hierarchy of an mra coarse model (Chen et al. 2019, Algorithm 1).

Levels are numbered as in the paper: 1 is the coarsest, q = num_levels the finest (the fine
grid). Level k < q is built from level k+1; its DOFs are the present DOFs of its grid
(Level.dofs, indices dim*node + d into the grid's DOFs). "fine grid DOFs" are all DOFs of the
fine mesh, interleaved per node (the FineModel's DOFs); fine_dofs are those the hierarchy keeps
(all but the eliminated Dirichlet DOFs).)")
        .def_property_readonly(
            "dim", [](const PyHierarchy& h) { return h.h->dim; }, "2 or 3.")
        .def_property_readonly(
            "num_levels", [](const PyHierarchy& h) { return h.h->num_levels(); },
            "q: the number of levels, the fine grid included.")
        .def_property_readonly(
            "num_fine_dofs", [](const PyHierarchy& h) { return h.h->fine_grid_dofs(); },
            "Fine grid DOFs (dim x nodes of the fine grid).")
        .def_property_readonly(
            "fine_dofs",
            [](py::object self) {
                return index_view(self.cast<PyHierarchy&>().h->fine_dofs, self);
            },
            "The fine grid DOFs the hierarchy keeps (level q's DOFs; int32, read-only view).")
        .def_property_readonly(
            "A_fine",
            [](py::object self) { return sparse_out(self.cast<PyHierarchy&>().h->A_fine, self); },
            "A^q: the fine stiffness on fine_dofs (len(fine_dofs) square, both triangles; "
            "scipy.sparse.csc_matrix, read-only view).")
        .def_property_readonly(
            "levels",
            [](const std::shared_ptr<PyHierarchy>& h) {
                std::vector<PyLevel> levels;
                for (int k = 1; k < h->h->num_levels(); ++k) levels.push_back({h, k});
                return levels;
            },
            "The levels k = 1 .. q-1 (a list of Level; levels[k-1] is level k).")
        .def(
            "level",
            [](const std::shared_ptr<PyHierarchy>& h, int k) {
                h->h->level(k);  // checks k
                return PyLevel{h, k};
            },
            py::arg("k"), "Level k, 1 <= k < q. Raises Error otherwise.")
        .def(
            "solve",
            [](PyHierarchy& h, const DoubleArray& f, std::optional<int> levels) {
                const Vector g = from_numpy(f, h.h->fine_grid_dofs(), "Hierarchy.solve: f");
                const int used = levels.value_or(h.h->num_levels());
                return to_numpy(with_solver(
                    h, [&](mra::MultilevelSolver& s) { return s.solve_levels(g, used); }));
            },
            py::arg("f"), py::arg("levels") = py::none(),
            R"(Multilevel solve (Sec. 3.6) of A^q u = f with the wavelets of levels 1 .. levels-1.

f: num_fine_dofs load over the fine grid DOFs (entries at eliminated Dirichlet DOFs are
ignored). levels = m in 1..q (default q, every level): g^k = C̃^k g^{k+1}, B^k w^k = W^k g^{k+1},
A^1 v^1 = g^1, u = Φ^{1,T} v^1 + sum_{k<m} Ψ^{k,T} w^k. With m = q and an exact construction
(global solves, truncation=0, invariance=False) this is the fine solution; with m = 1 the
coarsest solve. Returns u over the fine grid DOFs (zero at eliminated DOFs; a new array). The
factorizations of A^k and B^k are made on first use and kept for further solves.
Raises Error if levels is not in 1..q, f has the wrong size, or levels > 1 on a boundary-blind
hierarchy.)")
        .def(
            "solve_level",
            [](PyHierarchy& h, const DoubleArray& f, int k) {
                const Vector g = from_numpy(f, h.h->fine_grid_dofs(), "Hierarchy.solve_level: f");
                return to_numpy(
                    with_solver(h, [&](mra::MultilevelSolver& s) { return s.solve_level(g, k); }));
            },
            py::arg("f"), py::arg("k"),
            R"(Single-level solve on level k in 1..q (Sec. 4.1): A^k u^k = g^k, u = Φ^{k,T} u^k.

f and the result are over the fine grid DOFs (num_fine_dofs; a new array). k = q is the fine
solve. Raises Error if k is not in 1..q or f has the wrong size.)")
        .def(
            "basis",
            [](const PyHierarchy& h, int k) {
                SparseMatrix Phi;
                run_interruptible([&] { Phi = mra::basis(*h.h, k); });
                return owned_sparse(std::move(Phi));
            },
            py::arg("k"),
            R"(Φ^k = C̃^k ... C̃^{q-1} Φ^q: len(level(k).dofs) x num_fine_dofs (k = q: the selection of fine_dofs).

A new scipy.sparse.csc_matrix; for coarse levels of a large grid it is nearly dense (prefer
reconstruct). Raises Error if k is not in 1..q.)")
        .def(
            "reconstruct",
            [](const PyHierarchy& h, const DoubleArray& u, int k) {
                const Index n =
                    k == h.h->num_levels() ? h.h->fine_dofs.size() : h.h->level(k).dofs.size();
                const Vector uk = from_numpy(u, n, "Hierarchy.reconstruct: u");
                return to_numpy(run_interruptible([&] { return mra::reconstruct(*h.h, uk, k); }));
            },
            py::arg("u"), py::arg("k"),
            "Φ^{k,T} u over the fine grid DOFs for u over level k's DOFs (len(level(k).dofs); "
            "k = q: fine_dofs), level by level without forming Φ^k (a new array). Raises Error "
            "if k is not in 1..q or u has the wrong size.")
        .def(
            "coarse_grain",
            [](const PyHierarchy& h, const DoubleArray& g, int k) {
                const Vector gf = from_numpy(g, h.h->fine_grid_dofs(), "Hierarchy.coarse_grain: g");
                return to_numpy(run_interruptible([&] { return mra::coarse_grain(*h.h, gf, k); }));
            },
            py::arg("g"), py::arg("k"),
            "g^k = C̃^k ... C̃^{q-1} g^q of a load g over the fine grid DOFs (restricted to "
            "fine_dofs), over level k's DOFs (a new array). Raises Error if k is not in 1..q.");

    py::class_<PyLevel>(
        m, "Level",
        R"(Level k < q of a Hierarchy, built from level k+1 (Algorithm 1, lines 2-7).

n_k = len(dofs) DOFs; n_{k+1} those of level k+1 (len(fine_dofs) for k = q-1); w_k wavelets.)")
        .def_property_readonly(
            "k", [](const PyLevel& l) { return l.k; }, "The paper's index, 1 = coarsest.")
        .def_property_readonly(
            "cells",
            [](const PyLevel& l) {
                const mra::Level& L = l.level();
                if (!l.hierarchy->h->on_grid()) return std::vector<int>();
                return std::vector<int>(L.cells.data(), L.cells.data() + l.hierarchy->h->dim);
            },
            "Grid cells per axis of level k (empty on level meshes).")
        .def_property_readonly(
            "dofs",
            [](py::object self) { return index_view(self.cast<PyLevel&>().level().dofs, self); },
            "The level's present DOFs: indices dim*node + d into its grid's DOFs, sorted; rows "
            "of C_adapted and A follow this order (int32, read-only view).")
        .def_property_readonly(
            "num_wavelets", [](const PyLevel& l) { return l.level().W.rows(); }, "w_k.")
        .def_property_readonly(
            "C_adapted",
            [](const PyLevel& l) {
                SparseMatrix C;
                run_interruptible([&] { C = l.level().C_adapted.sparse(); });
                return owned_sparse(std::move(C));
            },
            "C̃^k = C^{k,†} + Z W^k (Eq. 11), the material-adapted refinement: n_k x n_{k+1} "
            "(a new scipy.sparse.csc_matrix: the hierarchy keeps it by runs).")
        .def_property_readonly(
            "A",
            [](const PyLevel& l) {
                return owned_sparse(
                    run_interruptible([&] { return mra::symmetric_from_lower(l.level().A); }));
            },
            "A^k = C̃^k A^{k+1} C̃^{k,T} (Alg. 1 line 7): n_k square, both triangles (a new "
            "scipy.sparse.csc_matrix: the hierarchy keeps its lower triangle).")
        .def_property_readonly(
            "B",
            [](const PyLevel& l) {
                return owned_sparse(
                    run_interruptible([&] { return mra::symmetric_from_lower(l.level().B); }));
            },
            "B^k = W^k A^{k+1} W^{k,T} (Alg. 1 line 2), the wavelet stiffness: w_k square, both "
            "triangles (a new scipy.sparse.csc_matrix).")
        .def_property_readonly(
            "W", [](py::object self) { return sparse_out(self.cast<PyLevel&>().level().W, self); },
            "W^k, the kernel (wavelet) matrix: w_k x n_{k+1}, W^k C^{k,T} = 0 "
            "(scipy.sparse.csc_matrix, read-only view).")
        .def_property_readonly(
            "C", [](py::object self) { return sparse_out(self.cast<PyLevel&>().level().C, self); },
            "C^k, the canonical refinement (Eq. 6): n_k x n_{k+1} (read-only view).")
        .def_property_readonly(
            "C_dagger",
            [](py::object self) {
                return sparse_out(self.cast<PyLevel&>().level().C_dagger, self);
            },
            "C^{k,†}, the left inverse of Eq. 10: n_k x n_{k+1} (read-only view).");
}

}  // namespace coarsegrain::python
