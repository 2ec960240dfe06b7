// coarsegrain._core: the C++ side of the Python module (python/coarsegrain/__init__.py wraps it).
// This file binds scenes, fine and coarse models and coarsen(); hierarchy.cpp the mra methods'
// hierarchy, dynamics.cpp simulate() and modes(); bindings.hpp holds what they share.
//
// Arrays: matrices and vectors the C++ objects own are handed out as read-only NumPy views (and
// scipy.sparse matrices over such views) that keep their Python owner alive, without copying.
// Copies are made where the layouts differ: the arrays that build a scene's mesh (NumPy's
// row-major nodes into Eigen's column-major matrix), a coarse mass (computed on request), the
// per-element tensors (gathered from the material table) and vectors a function returns;
// to_fine @ U of the hierarchy's operator copies U into column-major order, and its result is
// taken over without a copy.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.hpp"
#include "coarsegrain/coarsen/fine_run.hpp"
#include "coarsegrain/coarsen/runtime.hpp"
#include "coarsegrain/common/error.hpp"
#include "coarsegrain/material/material.hpp"
#include "coarsegrain/mesh/mesh.hpp"
#include "coarsegrain/scene/scene.hpp"
#include "coarsegrain/sim/corotational.hpp"
#include "coarsegrain/solve/lu_solver.hpp"
#include "coarsegrain/solve/spd_solver.hpp"
#include "interrupt.hpp"

namespace py = pybind11;
namespace cg = coarsegrain;

namespace {

using cg::Index;
using cg::python::build_fine;
using cg::python::compressed;
using cg::python::DoubleArray;
using cg::python::from_numpy;
using cg::python::index_matrix_view;
using cg::python::IntArray;
using cg::python::json_to_python;
using cg::python::matrix_view;
using cg::python::PyCoarse;
using cg::python::PyFine;
using cg::python::PyScene;
using cg::python::scipy_view;
using cg::python::timings_dict;
using cg::python::to_numpy;
using cg::python::vector_view;
using cg::python::view;

// #E by n by n per-element tensors of `materials` (Mandel, or Voigt with `voigt`).
py::array_t<double> element_tensors(const cg::material::ElementMaterials& materials, int dim,
                                    bool voigt) {
    const int n = cg::mandel_size(dim);
    py::array_t<double> out(
        {static_cast<py::ssize_t>(materials.size()), py::ssize_t(n), py::ssize_t(n)});
    auto o = out.mutable_unchecked<3>();
    std::vector<cg::Matrix> table;
    for (const cg::material::Material& m : materials.table) {
        const cg::Matrix C = cg::material::tensor(m, dim);
        table.push_back(voigt ? cg::material::mandel_to_voigt(C) : C);
    }
    for (Index e = 0; e < materials.size(); ++e) {
        const cg::Matrix& C = table[static_cast<std::size_t>(materials.index[e])];
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) o(e, i, j) = C(i, j);
    }
    return out;
}

py::array_t<double> element_densities(const cg::material::ElementMaterials& materials) {
    py::array_t<double> out(materials.size());
    for (Index e = 0; e < materials.size(); ++e) out.mutable_at(e) = materials.of(e).density;
    return out;
}

bool parse_notation(const std::string& notation) {
    CG_VERIFY(notation == "mandel" || notation == "voigt",
              "notation \"{}\": expected \"mandel\" or \"voigt\"", notation);
    return notation == "voigt";
}

cg::mesh::ElementType element_type(const std::string& name) {
    for (auto t : {cg::mesh::ElementType::Tri3, cg::mesh::ElementType::Quad4,
                   cg::mesh::ElementType::Tet4, cg::mesh::ElementType::Hex8})
        if (cg::mesh::element_name(t) == name) return t;
    throw cg::InvalidScene(
        fmt::format("element \"{}\": expected \"tri\", \"quad\", \"tet\" or \"hex\"", name));
}

// A mesh from arrays: nodes (#V x dim), elements (#E x nodes per element), element type name,
// material ids (#E; empty: all 0).
cg::mesh::Mesh mesh_from_arrays(const DoubleArray& nodes, const IntArray& elements,
                                const std::string& element, const IntArray& material_ids,
                                const std::string& key) {
    cg::mesh::Mesh m;
    m.type = element_type(element);
    const int dim = m.dim(), k = cg::mesh::nodes_per_element(m.type);
    CG_VERIFY_AS(cg::InvalidScene, nodes.ndim() == 2 && nodes.shape(1) == dim,
                 "{}.nodes: expected a #nodes x {} array for {} elements", key, dim, element);
    CG_VERIFY_AS(cg::InvalidScene, elements.ndim() == 2 && elements.shape(1) == k,
                 "{}.elements: expected a #elements x {} array for {} elements", key, k, element);
    const Index nv = static_cast<Index>(nodes.shape(0)), ne = static_cast<Index>(elements.shape(0));
    m.rest_positions.resize(nv, dim);
    for (Index v = 0; v < nv; ++v)
        for (int d = 0; d < dim; ++d) m.rest_positions(v, d) = nodes.at(v, d);
    m.elements.resize(ne, k);
    for (Index e = 0; e < ne; ++e)
        for (int a = 0; a < k; ++a) {
            const long long i = elements.at(e, a);
            CG_VERIFY_AS(cg::InvalidScene, i >= 0 && i < nv,
                         "{}.elements[{}][{}] = {}: expected a node index in [0, {})", key, e, a, i,
                         nv);
            m.elements(e, a) = static_cast<Index>(i);
        }
    m.material_ids = cg::IndexVector::Zero(ne);
    if (material_ids.size() > 0) {
        CG_VERIFY_AS(cg::InvalidScene, material_ids.ndim() == 1 && material_ids.shape(0) == ne,
                     "{}.material_ids: expected one id per element ({})", key, ne);
        for (Index e = 0; e < ne; ++e) m.material_ids[e] = static_cast<Index>(material_ids.at(e));
    }
    return m;
}

// One material per element from #E x n x n tensors (Mandel or Voigt) and #E densities; sets the
// mesh's material ids to 0..#E-1.
std::map<int, cg::material::Material> element_materials_from_arrays(cg::mesh::Mesh& m,
                                                                    const DoubleArray& C,
                                                                    bool voigt,
                                                                    const DoubleArray& density,
                                                                    const std::string& key) {
    const int dim = m.dim(), n = cg::mandel_size(dim);
    const Index ne = m.num_elements();
    const char* name = voigt ? "C_voigt" : "C_mandel";
    CG_VERIFY_AS(cg::InvalidScene,
                 C.ndim() == 3 && C.shape(0) == ne && C.shape(1) == n && C.shape(2) == n,
                 "{}.{}: expected a #elements x {} x {} array ({} elements)", key, name, n, n, ne);
    CG_VERIFY_AS(cg::InvalidScene, density.ndim() == 1 && density.shape(0) == ne,
                 "{}.density: expected one density per element ({})", key, ne);
    std::map<int, cg::material::Material> out;
    for (Index e = 0; e < ne; ++e) {
        cg::Matrix c(n, n);
        for (int i = 0; i < n; ++i)
            for (int j = 0; j < n; ++j) c(i, j) = C.at(e, i, j);
        try {
            out[e] = cg::material::anisotropic(dim, voigt ? cg::material::voigt_to_mandel(c) : c,
                                               density.at(e));
        } catch (const cg::Error& err) {
            throw cg::InvalidScene(fmt::format("{}.{}[{}]: {}", key, name, e, err.what()));
        }
        m.material_ids[e] = e;
    }
    return out;
}

struct PyStatic {
    std::shared_ptr<const cg::scene::Scene> scene;
    cg::scene::StaticSolution solution;
    int dim = 3;
};

struct PyResult {
    std::string method;
    std::shared_ptr<PyFine> fine;
    std::shared_ptr<PyCoarse> coarse;
    cg::coarsen::CoarseSolution solution;
    cg::coarsen::Errors errors;
    cg::Timings timings;  ///< the coarse solve's phases (build phases: coarse_model.timings)
};

// Solves the fine model as its scene asks (coarsen::solve_fine), once; keeps the factorization
// if `method` uses it.
void solve_fine(PyFine& fine, const cg::scene::Scene& scene, const std::string& method) {
    if (fine.solved) return;
    // in place: if the solve fails or is interrupted, the model stays usable
    cg::python::run_interruptible([&] { cg::coarsen::solve_fine(scene, *fine.run, {method}); });
    fine.solved = true;
}

std::shared_ptr<PyResult> coarsen(const std::shared_ptr<const cg::scene::Scene>& base,
                                  const std::string& method, const std::string& overrides,
                                  std::shared_ptr<PyFine> fine) {
    const std::shared_ptr<const cg::scene::Scene> scene =
        cg::python::with_overrides(base, overrides);
    cg::coarsen::validate_method(*scene, method);
    if (!fine) fine = build_fine(base);
    CG_VERIFY(fine->scene == base,
              "coarsen: the fine model was built from another scene ({}) than this one ({}); "
              "pass the Scene object it was built from",
              fine->scene->source, base->source);
    auto result = std::make_shared<PyResult>();
    result->method = method;
    result->fine = fine;
    result->coarse = std::make_shared<PyCoarse>();
    result->coarse->fine = fine;
    {
        // Locked without the GIL: the thread that holds the lock needs the GIL to finish.
        std::unique_lock<std::mutex> lock(fine->mutex, std::defer_lock);
        {
            const py::gil_scoped_release release;
            lock.lock();
        }
        solve_fine(*fine, *scene, method);
        cg::coarsen::MethodRun run;
        cg::python::run_interruptible([&] {
            run = cg::coarsen::run_method(*scene, *fine->run, method, &result->timings);
            run.model.K.makeCompressed();
        });
        result->coarse->model = std::move(run.model);
        result->solution = std::move(run.solution);
        result->errors = run.errors;
    }
    return result;
}

void register_exceptions(py::module_& m) {
    // pybind11 tries the translators last registered first: the base class goes first.
    auto& error = py::register_exception<cg::Error>(m, "Error", PyExc_RuntimeError);
    error.doc() =
        "Base of every error coarsegrain reports (bad input or a numerical failure); the "
        "message is the command-line tool's `error:` line.";
    py::register_exception<cg::InvalidScene>(m, "InvalidScene", error.ptr()).doc() =
        "A scene is invalid; the message names the JSON key (or the array).";
    py::register_exception<cg::MeshReadError>(m, "MeshReadError", error.ptr()).doc() =
        "A mesh file could not be read; the message names the file and line.";
    py::register_exception<cg::NotPositiveDefinite>(m, "NotPositiveDefinite", error.ptr()).doc() =
        "A matrix that must be symmetric positive definite is not (e.g. a part of the mesh "
        "without a Dirichlet condition).";
    py::register_exception<cg::solve::NotConverged>(m, "NotConverged", error.ptr()).doc() =
        "An iterative solve did not converge.";
    py::register_exception<cg::solve::SingularMatrix>(m, "SingularMatrix", error.ptr()).doc() =
        "A matrix to factorize is singular.";
    py::register_exception<cg::sim::NewtonFailed>(m, "NewtonFailed", error.ptr()).doc() =
        "Newton's method of a corotated solve failed at its smallest load increment.";
    py::register_exception<cg::Interrupted>(m, "Interrupted", PyExc_KeyboardInterrupt).doc() =
        "A computation stopped at a phase boundary after an interrupt (Ctrl-C) was requested.";
}

}  // namespace

PYBIND11_MODULE(_core, m) {
    m.doc() = "coarsegrain's C++ core; use the package `coarsegrain`, which wraps it.";
    register_exceptions(m);
    cg::python::bind_hierarchy(m);
    cg::python::bind_dynamics(m);

    // ---- scenes
    py::class_<PyScene>(m, "Scene",
                        R"(A parsed, validated scene (the JSON scene format of docs/guide.md).

Made by load_scene(path) or scene_from_dict(d). Read-only; with_coarse(**options) returns a
copy whose "coarse" block keys are replaced.)")
        .def_property_readonly(
            "source", [](const PyScene& s) { return s.scene->source; },
            "The scene's file name (or the name given to scene_from_dict), used in messages.")
        .def_property_readonly(
            "dimension", [](const PyScene& s) { return s.scene->dimension; }, "2 or 3.")
        .def_property_readonly(
            "base_dir", [](const PyScene& s) { return s.scene->base_dir; },
            "Folder that relative file names in the scene are resolved against.")
        .def_property_readonly(
            "element", [](const PyScene& s) { return cg::mesh::element_name(s.scene->mesh.type); },
            "The fine mesh's element type: \"tri\", \"quad\", \"tet\" or \"hex\".")
        .def_property_readonly(
            "num_nodes", [](const PyScene& s) { return s.scene->mesh.num_nodes(); },
            "Nodes of the fine mesh.")
        .def_property_readonly(
            "num_elements", [](const PyScene& s) { return s.scene->mesh.num_elements(); },
            "Elements of the fine mesh.")
        .def_property_readonly(
            "nodes",
            [](py::object self) {
                return matrix_view(self.cast<PyScene&>().scene->mesh.rest_positions, self);
            },
            "#nodes x dim rest positions of the fine mesh (read-only view, no copy).")
        .def_property_readonly(
            "elements",
            [](py::object self) {
                return index_matrix_view(self.cast<PyScene&>().scene->mesh.elements, self);
            },
            "#elements x nodes-per-element node indices (int32, VTK ordering; read-only view).")
        .def_property_readonly(
            "material_ids",
            [](py::object self) {
                const cg::IndexVector& ids = self.cast<PyScene&>().scene->mesh.material_ids;
                return vector_view(ids.data(), ids.size(), self);
            },
            "#elements material id of each element (int32, read-only view).")
        .def_property_readonly(
            "coarse_options",
            [](const PyScene& s) { return json_to_python(s.scene->coarse_block); },
            "The scene's \"coarse\" block as given (a dict; None if absent).")
        .def_property_readonly(
            "kinematics",
            [](const PyScene& s) { return cg::sim::kinematics_name(s.scene->kinematics); },
            "\"linear\" or \"corotational\".")
        .def_property_readonly(
            "warp", [](const PyScene& s) { return s.scene->rs_warp ? "rs" : "none"; },
            "\"rs\" (rotation-strain post-warp of linear solutions) or \"none\".")
        .def(
            "configured_methods",
            [](const PyScene& s) { return cg::coarsen::configured_methods(*s.scene); },
            R"(The methods the scene's "coarse" block configures (what the CLI's `--method all` runs).

Raises InvalidScene if it configures none.)")
        .def(
            "_with_coarse",
            [](const PyScene& s, const std::string& overrides) {
                return PyScene{
                    std::make_shared<const cg::scene::Scene>(cg::scene::with_coarse_overrides(
                        *s.scene,
                        cg::scene::parse_json(overrides, s.scene->source + " (options)")))};
            },
            py::arg("overrides_json"),
            "The scene with its \"coarse\" block keys replaced by a JSON object's (validated).");

    m.def(
        "load_scene",
        [](const std::string& path) {
            return PyScene{std::make_shared<const cg::scene::Scene>(
                cg::python::run_interruptible([&] { return cg::scene::load_scene(path); }))};
        },
        py::arg("path"),
        R"(Reads and validates a scene file (JSON; relative file names inside it are relative to its folder).

Raises InvalidScene / MeshReadError / Error naming the file and the JSON key.)");

    m.def(
        "_parse_scene",
        [](const std::string& text, const std::string& source, const std::string& base_dir,
           py::object mesh, py::object coarse_mesh) {
            cg::scene::GivenMeshes given;
            const auto read = [](py::dict d, const std::string& key,
                                 std::map<int, cg::material::Material>* materials) {
                cg::mesh::Mesh built = mesh_from_arrays(
                    d["nodes"].cast<DoubleArray>(), d["elements"].cast<IntArray>(),
                    d["element"].cast<std::string>(),
                    d.contains("material_ids") ? d["material_ids"].cast<IntArray>() : IntArray(0),
                    key);
                const bool voigt = d.contains("C_voigt");
                if (materials && (voigt || d.contains("C_mandel"))) {
                    CG_VERIFY_AS(cg::InvalidScene, d.contains("density"),
                                 "{}: per-element tensors need \"density\" (one per element or "
                                 "one for all)",
                                 key);
                    *materials = element_materials_from_arrays(
                        built, d[voigt ? "C_voigt" : "C_mandel"].cast<DoubleArray>(), voigt,
                        d["density"].cast<DoubleArray>(), key);
                }
                return built;
            };
            if (!mesh.is_none())
                given.mesh = read(mesh.cast<py::dict>(), "mesh", &given.element_materials);
            if (!coarse_mesh.is_none())
                given.coarse_mesh = read(coarse_mesh.cast<py::dict>(), "coarse.mesh", nullptr);
            const nlohmann::json j = cg::scene::parse_json(text, source);
            return PyScene{std::make_shared<const cg::scene::Scene>(
                cg::scene::parse_scene(j, source, base_dir, given))};
        },
        py::arg("json_text"), py::arg("source"), py::arg("base_dir"), py::arg("mesh"),
        py::arg("coarse_mesh"),
        "Validates a scene given as JSON text, with meshes given as arrays (dicts of nodes, "
        "elements, element, material_ids, and for the fine mesh C_mandel or C_voigt and "
        "density); scene_from_dict wraps it.");

    m.def(
        "demo_scene", [](double scale) { return json_to_python(cg::scene::demo_scene(scale)); },
        py::arg("scale") = 1.0,
        R"(The built-in demo scene as a dict (the scene of `coarsegrain demo --scale S`).

A layered beam, 16b x 4b x 4b hexes with b = round(3 scale) (at least 1), clamped at x = 0
and hanging under gravity; effective-tensor, baselines and a 3-level hierarchy configured.)");

    m.def("method_names", &cg::coarsen::method_names,
          "Names of every coarsening method, in the order reports list them.");

    m.def(
        "directional_young",
        [](const DoubleArray& C, const DoubleArray& d) {
            CG_VERIFY(C.ndim() == 2 && C.shape(0) == C.shape(1),
                      "directional_young: C must be a square Mandel tensor");
            const Index n = static_cast<Index>(C.shape(0));
            const cg::Matrix Cm = Eigen::Map<
                const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                C.data(), n, n);
            return cg::material::directional_young(
                Cm, Eigen::Map<const Eigen::VectorXd>(d.data(), d.size()));
        },
        py::arg("C_mandel"), py::arg("direction"),
        R"(Directional Young's modulus 1 / (d⊗d : C⁻¹ : d⊗d) of a Mandel tensor (3x3 in 2D, 6x6 in 3D) along a direction (normalized here).

Raises Error if the sizes do not match or the direction is zero.)");

    // ---- the fine model
    py::class_<PyFine, std::shared_ptr<PyFine>>(m, "FineModel",
                                                R"(The fine FEM model of a scene (build_fine_model).

DOFs are interleaved per node (x0 y0 z0 x1 ...); stiffness and mass are over all DOFs, without
the Dirichlet conditions applied (dirichlet_dofs / dirichlet_values hold them).)")
        .def_property_readonly(
            "scene", [](const PyFine& f) { return PyScene{f.scene}; },
            "The scene it was built from.")
        .def_property_readonly(
            "dim", [](const PyFine& f) { return f.run->model.mesh.dim(); }, "2 or 3.")
        .def_property_readonly(
            "num_dofs", [](const PyFine& f) { return f.run->model.mesh.num_dofs(); },
            "dim x #nodes.")
        .def_property_readonly(
            "stiffness",
            [](py::object self) { return scipy_view(self.cast<PyFine&>().run->model.K, self); },
            "num_dofs square stiffness K (scipy.sparse.csc_matrix over the model's own storage: "
            "read-only, no copy).")
        .def_property_readonly(
            "mass",
            [](py::object self) {
                PyFine& f = self.cast<PyFine&>();
                cg::python::run_interruptible([&] { f.mass(); });
                return scipy_view(f.M, self);
            },
            "num_dofs square mass M (consistent, or lumped if the scene's dynamics.mass says so), "
            "assembled on first use (scipy.sparse.csc_matrix, read-only).")
        .def_property_readonly(
            "load",
            [](py::object self) { return vector_view(self.cast<PyFine&>().run->model.f, self); },
            "num_dofs load f: gravity and tractions (read-only view).")
        .def_property_readonly(
            "dirichlet_dofs",
            [](py::object self) {
                const auto& dofs = self.cast<PyFine&>().run->model.bc.dofs;
                return vector_view(dofs.data(), static_cast<py::ssize_t>(dofs.size()), self);
            },
            "Indices of the DOFs the Dirichlet conditions fix (int32, read-only view).")
        .def_property_readonly(
            "dirichlet_values",
            [](py::object self) {
                return vector_view(self.cast<PyFine&>().run->model.bc.values, self);
            },
            "Their prescribed values (read-only view).")
        .def_property_readonly(
            "nodes",
            [](py::object self) {
                return matrix_view(self.cast<PyFine&>().run->model.mesh.rest_positions, self);
            },
            "#nodes x dim rest positions (read-only view).")
        .def_property_readonly(
            "elements",
            [](py::object self) {
                return index_matrix_view(self.cast<PyFine&>().run->model.mesh.elements, self);
            },
            "#elements x nodes-per-element node indices (int32, read-only view).")
        .def_property_readonly(
            "warnings", [](const PyFine& f) { return f.run->model.warnings; },
            "Problems worth a user's attention (e.g. locking), as the CLI prints them.")
        .def(
            "element_tensors",
            [](const PyFine& f, const std::string& notation) {
                return element_tensors(f.run->model.materials, f.run->model.mesh.dim(),
                                       parse_notation(notation));
            },
            py::arg("notation") = "mandel",
            "#elements x n x n elasticity tensor of each element (n = 6 in 3D, 3 in 2D), "
            "notation \"mandel\" or \"voigt\" (a new array).")
        .def(
            "element_densities",
            [](const PyFine& f) { return element_densities(f.run->model.materials); },
            "#elements density of each element (a new array).")
        .def(
            "solve_static",
            [](const PyFine& f) {
                auto s = std::make_shared<PyStatic>();
                s->scene = f.scene;
                s->dim = f.run->model.mesh.dim();
                cg::python::run_interruptible([&] {
                    s->solution = cg::scene::solve_static(
                        f.run->model, cg::scene::fine_solver(*f.scene, f.run->model));
                });
                return s;
            },
            R"(Solves K u = f with the Dirichlet conditions eliminated (the scene's solver), linear kinematics.

Returns a StaticSolution. Raises NotPositiveDefinite naming the cause if the model is singular
(e.g. a part without a Dirichlet node).)");

    py::class_<PyStatic, std::shared_ptr<PyStatic>>(m, "StaticSolution",
                                                    "A static solution on the fine model.")
        .def_property_readonly(
            "u",
            [](py::object self) { return vector_view(self.cast<PyStatic&>().solution.u, self); },
            "num_dofs displacement, interleaved (read-only view).")
        .def_property_readonly(
            "displacements",
            [](py::object self) {
                PyStatic& s = self.cast<PyStatic&>();
                const auto d = static_cast<py::ssize_t>(sizeof(double));
                return view(s.solution.u.data(), {s.solution.u.size() / s.dim, s.dim},
                            {d * s.dim, d}, self);
            },
            "#nodes x dim displacement (a read-only view of u).")
        .def_property_readonly(
            "strain_energy", [](const PyStatic& s) { return s.solution.strain_energy; },
            "½ uᵀ K u.");

    // ---- coarse models
    py::class_<PyCoarse, std::shared_ptr<PyCoarse>>(
        m, "CoarseModel",
        R"(A coarse model: an operator on coarse DOFs, its load and conditions, and the map to the fine DOFs.)")
        .def_property_readonly(
            "method", [](const PyCoarse& c) { return c.model.method; },
            "\"effective-tensor\", \"naive\", \"voigt\", \"reuss\" or \"mra\".")
        .def_property_readonly(
            "num_dofs", [](const PyCoarse& c) { return c.model.K.rows(); }, "Coarse DOFs.")
        .def_property_readonly(
            "num_nodes", [](const PyCoarse& c) { return c.model.nodes; },
            "Coarse nodes (mra: nodes of the coarsest grid).")
        .def_property_readonly(
            "num_elements", [](const PyCoarse& c) { return c.model.elements; },
            "Coarse elements (mra: cells of the coarsest grid).")
        .def_property_readonly(
            "stiffness",
            [](py::object self) { return scipy_view(self.cast<PyCoarse&>().model.K, self); },
            "Coarse DOFs square stiffness (scipy.sparse.csc_matrix, read-only, no copy).")
        .def_property_readonly(
            "load",
            [](py::object self) { return vector_view(self.cast<PyCoarse&>().model.f, self); },
            "Coarse load, one entry per coarse DOF (read-only view).")
        .def_property_readonly(
            "mass",
            [](py::object self) -> py::object {
                PyCoarse& c = self.cast<PyCoarse&>();
                if (!c.model.mass) return py::none();
                cg::python::run_interruptible([&] {
                    std::call_once(c.mass_once,
                                   [&c] { c.M = compressed(c.model.mass(c.fine->mass())); });
                });
                return scipy_view(*c.M, self);
            },
            "Coarse DOFs square mass for the fine mass (FineModel.mass), computed on first use "
            "(effective tensors and baselines: by coarse.mass; mra: the Galerkin mass); None if "
            "the method defines none.")
        .def_property_readonly(
            "dirichlet_dofs",
            [](py::object self) {
                const auto& dofs = self.cast<PyCoarse&>().model.bc.dofs;
                return vector_view(dofs.data(), static_cast<py::ssize_t>(dofs.size()), self);
            },
            "Coarse DOFs the Dirichlet conditions fix (empty when built into the stiffness).")
        .def_property_readonly(
            "dirichlet_values",
            [](py::object self) {
                return vector_view(self.cast<PyCoarse&>().model.bc.values, self);
            },
            "Their prescribed values.")
        .def_property_readonly(
            "_to_fine_matrix",
            [](py::object self) -> py::object {
                const cg::SparseMatrix* M = self.cast<PyCoarse&>().model.to_fine.matrix();
                if (!M) return py::none();
                return scipy_view(*M, self);
            },
            "The map to the fine DOFs as a matrix, or None if it is applied without forming it.")
        .def_property_readonly(
            "_to_fine_shape",
            [](const PyCoarse& c) {
                return py::make_tuple(c.model.to_fine.rows(), c.model.to_fine.cols());
            },
            "(fine DOFs, coarse DOFs).")
        .def(
            "_apply_to_fine",
            [](const PyCoarse& c, const DoubleArray& u) {
                const cg::Vector x = from_numpy(u, c.model.to_fine.cols(), "to_fine");
                cg::Vector y;
                cg::python::run_interruptible([&] { y = c.model.to_fine.apply(x); });
                return to_numpy(y);
            },
            py::arg("u"), "to_fine applied to one coarse vector (a new array).")
        .def(
            "_apply_to_fine_columns",
            [](const PyCoarse& c, const DoubleArray& U) {
                const cg::Matrix x = cg::python::columns_from_numpy(U, c.model.to_fine.cols());
                cg::Matrix y;
                cg::python::run_interruptible([&] { y = c.model.to_fine * x; });
                return cg::python::owned_matrix(std::move(y));
            },
            py::arg("U"),
            "to_fine applied to each column of a #coarse DOFs x k array: #fine DOFs x k (a new "
            "array, Fortran order).")
        .def_property_readonly(
            "hierarchy",
            [](PyCoarse& c) -> py::object {
                const auto h = c.python_hierarchy();
                if (!h) return py::none();
                return py::cast(h);
            },
            "The material-adapted hierarchy behind the model (a Hierarchy: levels C̃^k, A^k, "
            "B^k, W^k and multilevel solves) for the mra methods; None for the others.")
        .def(
            "element_tensors",
            [](const PyCoarse& c, const std::string& notation) {
                const bool voigt = parse_notation(notation);
                CG_VERIFY(c.model.element_model.has_value(),
                          "{}: the coarse model has no elements with tensors (its DOFs are a "
                          "hierarchy's)",
                          c.model.method);
                return element_tensors(c.model.element_model->materials,
                                       c.model.element_model->mesh.dim(), voigt);
            },
            py::arg("notation") = "mandel",
            R"(#elements x n x n effective elasticity tensor of each coarse element (n = 6 in 3D, 3 in 2D), notation "mandel" or "voigt" (a new array).

Raises Error for a method without coarse elements (mra).)")
        .def(
            "element_densities",
            [](const PyCoarse& c) {
                CG_VERIFY(c.model.element_model.has_value(), "{}: the coarse model has no elements",
                          c.model.method);
                return element_densities(c.model.element_model->materials);
            },
            "#elements density of each coarse element (a new array).")
        .def_property_readonly(
            "nodes",
            [](py::object self) -> py::object {
                const auto& em = self.cast<PyCoarse&>().model.element_model;
                if (!em) return py::none();
                return matrix_view(em->mesh.rest_positions, self);
            },
            "#nodes x dim rest positions of the coarse mesh (None for mra; read-only view).")
        .def_property_readonly(
            "elements",
            [](py::object self) -> py::object {
                const auto& em = self.cast<PyCoarse&>().model.element_model;
                if (!em) return py::none();
                return index_matrix_view(em->mesh.elements, self);
            },
            "#elements x nodes-per-element of the coarse mesh (None for mra; read-only view).")
        .def_property_readonly(
            "timings", [](const PyCoarse& c) { return timings_dict(c.model.timings); },
            "Seconds of each build phase.");

    py::class_<PyResult, std::shared_ptr<PyResult>>(
        m, "CoarsenResult", "A method run against the fine solution (coarsen).")
        .def_property_readonly(
            "method", [](const PyResult& r) { return r.method; }, "The method's name.")
        .def_property_readonly(
            "errors",
            [](const PyResult& r) { return json_to_python(cg::coarsen::errors_json(r.errors)); },
            "The CLI's summary.json \"errors\": energy_rel, energy_over_load, l2_rel, "
            "max_displacement_rel, compliance_ratio, stress_rel.")
        .def_property_readonly(
            "coarse_model", [](const PyResult& r) { return r.coarse; }, "The CoarseModel.")
        .def_property_readonly(
            "hierarchy",
            [](const PyResult& r) -> py::object {
                const auto h = r.coarse->python_hierarchy();
                if (!h) return py::none();
                return py::cast(h);
            },
            "coarse_model.hierarchy: the mra methods' Hierarchy, None for the others.")
        .def_property_readonly(
            "fine_model", [](const PyResult& r) { return r.fine; },
            "The FineModel the method was compared on.")
        .def_property_readonly(
            "u",
            [](py::object self) { return vector_view(self.cast<PyResult&>().solution.u, self); },
            "Coarse solution over the coarse DOFs (read-only view).")
        .def_property_readonly(
            "u_fine",
            [](py::object self) {
                return vector_view(self.cast<PyResult&>().solution.u_fine, self);
            },
            "The coarse solution on the fine DOFs (post-warped if the scene asks; read-only view).")
        .def_property_readonly(
            "fine_u",
            [](py::object self) {
                return vector_view(self.cast<PyResult&>().fine->run->solution.u, self);
            },
            "The fine solution it is compared with (read-only view).")
        .def_property_readonly(
            "strain_energy", [](const PyResult& r) { return r.solution.strain_energy; },
            "The coarse solution's strain energy.")
        .def_property_readonly(
            "fine_strain_energy",
            [](const PyResult& r) { return r.fine->run->solution.strain_energy; },
            "The fine solution's strain energy.")
        .def_property_readonly(
            "timings", [](const PyResult& r) { return timings_dict(r.timings); },
            "Seconds of the coarse solve's phases (factorize, solve, ...).")
        .def_property_readonly(
            "fine_timings", [](const PyResult& r) { return timings_dict(r.fine->run->timings); },
            "Seconds of the fine model's phases (assemble, factorize, solve, ...).");

    m.def(
        "build_fine_model", [](const PyScene& s) { return build_fine(s.scene); }, py::arg("scene"),
        R"(Assembles the scene's fine model (stiffness, load, Dirichlet conditions).

Raises InvalidScene if a box selects no node or facet, Error on bad elements.)");
    m.def(
        "_coarsen",
        [](const PyScene& s, const std::string& method, const std::string& overrides,
           std::shared_ptr<PyFine> fine) { return coarsen(s.scene, method, overrides, fine); },
        py::arg("scene"), py::arg("method"), py::arg("overrides_json"), py::arg("fine"),
        "coarsen(scene, method, **options) without the options' conversion to JSON.");
}
