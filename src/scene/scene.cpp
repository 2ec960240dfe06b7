#include "coarsegrain/scene/scene.hpp"

#include <fmt/ranges.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <set>

#include "coarsegrain/fem/assembly.hpp"
#include "coarsegrain/fem/loads.hpp"
#include "coarsegrain/fem/locking.hpp"
#include "coarsegrain/fem/stress.hpp"
#include "coarsegrain/io/material_fields.hpp"
#include "coarsegrain/io/mesh_io.hpp"
#include "coarsegrain/io/vtu.hpp"
#include "coarsegrain/material/material_field.hpp"
#include "coarsegrain/mesh/grid.hpp"
#include "coarsegrain/mesh/point_locator.hpp"
#include "coarsegrain/mra/hierarchy.hpp"
#include "coarsegrain/mra/preconditioner.hpp"
#include "json_reader.hpp"

namespace coarsegrain::scene {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string resolve(const std::string& base_dir, const std::string& file) {
    const fs::path p(file);
    return p.is_absolute() || base_dir.empty() ? file : (fs::path(base_dir) / p).string();
}

/// Cells per axis of a grid (mesh.grid.cells, coarse.mesh.grid.cells).
constexpr std::int64_t kMaxGridCells = 100000;

/// Stiffness nonzeros per DOF of a grid's element type (node neighbours times dim): 27 nodes
/// share an element with an interior hex node, 9 with a quad node; an interior node of the
/// 6-tet split of a cube touches 15 nodes, of the 2-triangle split of a square 7.
int grid_nonzeros_per_dof(mesh::ElementType type) {
    switch (type) {
        case mesh::ElementType::Hex8:
            return 27 * 3;
        case mesh::ElementType::Tet4:
            return 15 * 3;
        case mesh::ElementType::Quad4:
            return 9 * 2;
        default:
            return 7 * 2;
    }
}

/// Physical memory of this machine in bytes (0 if unknown).
double physical_memory() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
}

/// Fails (naming `r`'s key) unless a model of `nodes` nodes has a DOF count that fits the
/// 32-bit indices of the sparse matrices and CHOLMOD, and its stiffness matrix (12 bytes per
/// nonzero: value and row index) fits in this machine's memory. Computed in 64-bit before any
/// array is allocated.
void check_model_size(const JsonReader& r, std::int64_t nodes, int dim, int nonzeros_per_dof) {
    const std::int64_t dofs = nodes * dim;
    r.fail_unless(dofs <= std::numeric_limits<Index>::max(),
                  "{} nodes make {} DOFs, more than the {} that 32-bit indices hold", nodes, dofs,
                  std::numeric_limits<Index>::max());
    const double bytes = 12.0 * static_cast<double>(dofs) * nonzeros_per_dof;
    const double memory = physical_memory();
    r.fail_unless(memory == 0 || bytes <= memory,
                  "{} nodes ({} DOFs): the stiffness matrix alone needs about {:.1f} GB, more than "
                  "this machine's {:.1f} GB",
                  nodes, dofs, bytes / 1e9, memory / 1e9);
}

/// The path of an existing regular file (not a folder, device or FIFO), resolved against
/// base_dir; fails naming `r`'s key.
std::string regular_file(const JsonReader& r, const std::string& base_dir) {
    const std::string path = resolve(base_dir, r.string());
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    r.fail_unless(fs::exists(status), "file {} does not exist", path);
    r.fail_unless(fs::is_regular_file(status), "{} is not a regular file", path);
    return path;
}

mesh::ElementType parse_element(const JsonReader& r) {
    const std::string s = r.string();
    if (s == "hex") return mesh::ElementType::Hex8;
    if (s == "tet") return mesh::ElementType::Tet4;
    if (s == "quad") return mesh::ElementType::Quad4;
    if (s == "tri") return mesh::ElementType::Tri3;
    r.fail("unknown element \"{}\"; expected \"hex\", \"tet\", \"quad\" or \"tri\"", s);
}

// `carried` (if given) receives the per-element materials a .vtu mesh file may carry
// (io/material_fields.hpp: a coarse model written by `coarsegrain coarsen`).
mesh::Mesh parse_mesh(const JsonReader& r, const std::optional<int>& dimension,
                      const std::string& base_dir,
                      std::map<int, material::Material>* carried = nullptr) {
    r.allow_only({"file", "grid"});
    r.fail_unless(r.has("file") != r.has("grid"), "expected exactly one of \"file\" or \"grid\"");
    if (auto file = r.find("file")) {
        const std::string path = regular_file(*file, base_dir);
        if (!carried || fs::path(path).extension() != ".vtu") return io::read_mesh(path);
        auto [m, fields] = io::read_vtu(path);
        if (io::has_element_material_fields(fields, m.dim())) {
            try {
                *carried = io::element_materials_from_fields(fields, m, path);
            } catch (const InvalidScene&) {
                throw;
            } catch (const Error& e) {
                file->fail("{}", e.what());
            }
        }
        return m;
    }
    const JsonReader g = r.at("grid");
    g.allow_only({"min", "max", "cells", "element"});
    const int dim = dimension ? *dimension : static_cast<int>(g.at("min").array_size());
    g.fail_unless(dim == 2 || dim == 3, "grid min must have 2 or 3 numbers");
    const mesh::ElementType type =
        g.has("element") ? parse_element(g.at("element"))
                         : (dim == 3 ? mesh::ElementType::Hex8 : mesh::ElementType::Quad4);
    g.fail_unless(mesh::element_dim(type) == dim, "element \"{}\" is not a {}D element",
                  mesh::element_name(type), dim);
    const Eigen::VectorXd lo = g.at("min").vector(dim), hi = g.at("max").vector(dim);
    const JsonReader c = g.at("cells");
    c.fail_unless(c.array_size() == static_cast<std::size_t>(dim), "expected {} integers", dim);
    Eigen::VectorXi cells(dim);
    std::int64_t nodes = 1;
    for (int d = 0; d < dim; ++d) {
        cells[d] = static_cast<int>(c.at(static_cast<std::size_t>(d)).integer(1, kMaxGridCells));
        nodes *= cells[d] + 1;  // at most (1e5 + 1)^3 < 2^63
    }
    check_model_size(c, nodes, dim, grid_nonzeros_per_dof(type));
    for (int d = 0; d < dim; ++d)
        g.fail_unless(hi[d] > lo[d], "max[{}] = {} must exceed min[{}] = {}", d, hi[d], d, lo[d]);
    return mesh::make_grid(type, lo, hi, cells);
}

material::Material parse_material(const JsonReader& r, int dim, material::PlaneMode plane) {
    r.allow_only({"E", "nu", "density", "C_voigt", "C_mandel"});
    const double density = r.at("density").number();
    r.at("density").fail_unless(density > 0, "density = {} must be > 0", density);
    const bool iso = r.has("E") || r.has("nu");
    const int tensors = int(r.has("C_voigt")) + int(r.has("C_mandel"));
    r.fail_unless(iso != (tensors == 1) && tensors <= 1,
                  "give either \"E\" and \"nu\" (isotropic) or one of \"C_voigt\" / \"C_mandel\"");
    try {
        if (iso)
            return material::isotropic(dim, r.at("E").number(), r.at("nu").number(), density,
                                       plane);
        const bool voigt = r.has("C_voigt");
        const JsonReader c = r.at(voigt ? "C_voigt" : "C_mandel");
        const int n = mandel_size(dim);
        c.fail_unless(c.array_size() == static_cast<std::size_t>(n),
                      "expected a {}x{} matrix (rows of numbers)", n, n);
        Matrix C(n, n);
        for (int i = 0; i < n; ++i)
            C.row(i) = c.at(static_cast<std::size_t>(i)).vector(n).transpose();
        return material::anisotropic(dim, voigt ? material::voigt_to_mandel(C) : C, density);
    } catch (const InvalidScene&) {
        throw;
    } catch (const Error& e) {
        r.fail("{}", e.what());
    }
}

int parse_axis(const JsonReader& r, int dim) {
    int axis = -1;
    if (r.json().is_string()) {
        const std::string s = r.string();
        axis = s == "x" ? 0 : s == "y" ? 1 : s == "z" ? 2 : -1;
    } else {
        axis = r.integer();
    }
    r.fail_unless(axis >= 0 && axis < dim, "expected an axis 0..{} or \"x\", \"y\"{}", dim - 1,
                  dim == 3 ? ", \"z\"" : "");
    return axis;
}

std::vector<int> parse_ids(const JsonReader& r) {
    std::vector<int> ids;
    for (std::size_t i = 0; i < r.array_size(); ++i) ids.push_back(r.at(i).integer());
    r.fail_unless(!ids.empty(), "expected at least one material id");
    return ids;
}

// Applies a material_field block; returns materials it defines (image fields).
std::map<int, material::Material> apply_material_field(const JsonReader& r, mesh::Mesh& m,
                                                       material::PlaneMode plane,
                                                       const std::string& base_dir) {
    r.allow_only({"layers", "spheres", "checkerboard", "image", "voxels"});
    r.fail_unless(r.json().size() == 1, "expected exactly one field kind");
    const int dim = m.dim();
    const Matrix box = mesh::bounding_box(m);
    if (auto l = r.find("layers")) {
        l->allow_only({"axis", "thickness", "ids", "origin"});
        const int axis = parse_axis(l->at("axis"), dim);
        const double origin = l->has("origin") ? l->at("origin").number() : box(0, axis);
        material::layers(m, axis, origin, l->at("thickness").positive(), parse_ids(l->at("ids")));
    } else if (auto s = r.find("spheres")) {
        s->allow_only({"centres", "radius", "inside", "outside"});
        const JsonReader c = s->at("centres");
        Matrix centres(static_cast<Index>(c.array_size()), dim);
        for (std::size_t i = 0; i < c.array_size(); ++i)
            centres.row(static_cast<Index>(i)) = c.at(i).vector(dim).transpose();
        if (s->has("outside")) m.material_ids.setConstant(s->at("outside").integer());
        material::spheres(m, centres, s->at("radius").positive(), s->at("inside").integer());
    } else if (auto c = r.find("checkerboard")) {
        c->allow_only({"origin", "size", "ids"});
        const std::vector<int> ids = parse_ids(c->at("ids"));
        c->at("ids").fail_unless(ids.size() == 2, "expected two material ids");
        const Eigen::VectorXd origin = c->has("origin") ? c->at("origin").vector(dim)
                                                        : Eigen::VectorXd(box.row(0).transpose());
        material::checkerboard(m, origin, c->at("size").positive(), ids[0], ids[1]);
    } else if (auto im = r.find("image")) {
        im->allow_only({"file", "E_black", "E_white", "nu", "density"});
        im->fail_unless(dim == 2, "image material fields need a 2D mesh");
        material::ImageField opt;
        opt.file = regular_file(im->at("file"), base_dir);
        opt.E_black = im->at("E_black").positive();
        opt.E_white = im->at("E_white").positive();
        opt.nu = im->at("nu").number();
        opt.density = im->at("density").positive();
        opt.mode = plane;
        return material::image_field(m, opt);
    } else if (auto v = r.find("voxels")) {
        v->allow_only({"file", "dims"});
        v->fail_unless(dim == 3, "voxel material fields need a 3D mesh");
        const JsonReader d = v->at("dims");
        d.fail_unless(d.array_size() == 3, "expected 3 integers");
        Eigen::Vector3i dims;
        for (int k = 0; k < 3; ++k)
            dims[k] = static_cast<int>(d.at(static_cast<std::size_t>(k)).integer(1, 1 << 20));
        const JsonReader file = v->at("file");
        const std::string path = regular_file(file, base_dir);
        const std::uintmax_t bytes = fs::file_size(path);
        const std::uintmax_t expected = static_cast<std::uintmax_t>(dims[0]) *
                                        static_cast<std::uintmax_t>(dims[1]) *
                                        static_cast<std::uintmax_t>(dims[2]);
        file.fail_unless(bytes == expected,
                         "{} has {} bytes, expected {}x{}x{} = {} (one byte per voxel)", path,
                         bytes, dims[0], dims[1], dims[2], expected);
        try {
            material::voxel_field(m, path, dims);
        } catch (const Error& e) {
            file.fail("{}", e.what());
        }
    }
    return {};
}

std::vector<BoxCondition> parse_box_conditions(const JsonReader& r, int dim, bool value_required) {
    std::vector<BoxCondition> out;
    for (std::size_t i = 0; i < r.array_size(); ++i) {
        const JsonReader c = r.at(i);
        c.allow_only({"box", "value"});
        const JsonReader b = c.at("box");
        b.allow_only({"min", "max"});
        BoxCondition bc;
        bc.key = c.path();
        bc.box.min = b.at("min").vector(dim);
        bc.box.max = b.at("max").vector(dim);
        for (int d = 0; d < dim; ++d)
            b.fail_unless(bc.box.max[d] >= bc.box.min[d], "max[{}] = {} is below min[{}] = {}", d,
                          bc.box.max[d], d, bc.box.min[d]);
        bc.value = value_required || c.has("value") ? c.at("value").vector(dim)
                                                    : Eigen::VectorXd::Zero(dim);
        out.push_back(bc);
    }
    return out;
}

// A given mesh (GivenMeshes), checked; its errors are InvalidScene.
mesh::Mesh given_mesh(const mesh::Mesh& m, const std::string& source, const std::string& key) {
    try {
        mesh::validate(m, source + ": " + key);
    } catch (const Error& e) {
        throw InvalidScene(e.what());
    }
    return m;
}

// The hierarchy adapted to one time step (coarse.operator "step") needs the scene's dynamics.
void check_coarse_operator(const Scene& s, const JsonReader& coarse) {
    if (s.coarse.mra.fine_operator != mra::Operator::Step) return;
    coarse.at("operator")
        .fail_unless(
            s.dynamics.has_value(),
            "\"step\" adapts the hierarchy to one time step, which the scene's \"dynamics\" "
            "block defines (dt, integrator, damping, mass); add one or use \"stiffness\"");
}

// The coarse mesh of coarse.mesh (`m`) on a scene of dimension dim.
mesh::Mesh coarse_mesh(const JsonReader& m, int dim, const std::string& base_dir) {
    mesh::Mesh coarse = parse_mesh(m, dim, base_dir);
    m.fail_unless(coarse.dim() == dim, "the coarse mesh is {}D, the scene {}D", coarse.dim(), dim);
    return coarse;
}

/// coarse.level_meshes: each entry a mesh file name or an object read like "mesh", checked as
/// mra::build_hierarchy will (simplicial, of the scene's dimension, no more nodes than the next
/// finer level) before any work.
std::vector<mesh::Mesh> level_meshes(const JsonReader& list, const mesh::Mesh& fine,
                                     const mra::Options& options, const std::string& base_dir) {
    std::vector<mesh::Mesh> levels;
    for (std::size_t i = 0; i < list.array_size(); ++i) {
        const JsonReader entry = list.at(i);
        if (entry.json().is_string()) {
            levels.push_back(io::read_mesh(regular_file(entry, base_dir)));
            entry.fail_unless(levels.back().dim() == fine.dim(), "the mesh is {}D, the scene {}D",
                              levels.back().dim(), fine.dim());
        } else {
            levels.push_back(coarse_mesh(entry, fine.dim(), base_dir));
        }
        entry.fail_unless(mesh::is_simplex(levels.back().type),
                          "the levels of the hierarchy must be simplicial meshes "
                          "(triangles or tetrahedra), got {} elements",
                          mesh::element_name(levels.back().type));
    }
    try {
        mra::validate_level_meshes(levels, fine, options);
    } catch (const Error& e) {
        list.fail("{}", e.what());
    }
    return levels;
}

}  // namespace

namespace {

/// solver.tolerance of mra-pcg unless given: the relative residual at which the fine solve
/// agrees with CHOLMOD's to about 1e-8 (tests/solve/test_mra_pcg.cpp).
constexpr double kIterativeTolerance = 1e-8;

/// The "solver" block: backend, tolerance, and the iterative backends' limits and mra-pcg's
/// hierarchy (Scene::preconditioner).
void parse_solver(const JsonReader& sv, Scene& s) {
    sv.allow_only({"backend", "tolerance", "max_iterations", "time_limit", "levels", "radius",
                   "smoother_degree", "deflation", "deflation_rings"});
    if (auto b = sv.find("backend")) {
        try {
            s.solver.backend = solve::parse_backend(b->string());
        } catch (const Error& e) {
            b->fail("{}", e.what());
        }
    }
    const bool iterative = solve::is_iterative(s.solver.backend);
    const bool pcg = s.solver.backend == solve::Backend::MraPcg;
    if (pcg) s.solver.cg_tolerance = kIterativeTolerance;
    if (auto t = sv.find("tolerance")) {
        s.solver.cg_tolerance = t->positive();
        t->fail_unless(s.solver.cg_tolerance < 1, "expected a relative residual in (0, 1), got {}",
                       s.solver.cg_tolerance);
    }
    const auto only_iterative = [&](const char* key) {
        auto v = sv.find(key);
        if (v) v->fail_unless(iterative, "applies to the iterative backends (cg, mra-pcg) only");
        return v;
    };
    const auto only_pcg = [&](const char* key) {
        auto v = sv.find(key);
        if (v) v->fail_unless(pcg, "applies to the mra-pcg backend only");
        return v;
    };
    if (auto v = only_iterative("max_iterations"))
        s.solver.cg_max_iterations = static_cast<int>(v->integer(1, 1000000000));
    if (auto v = only_iterative("time_limit")) s.solver.time_limit = v->positive();
    if (auto v = only_pcg("levels"))
        s.preconditioner.levels = static_cast<int>(v->integer(2, mra::kMaxLevels));
    if (auto v = only_pcg("radius")) {
        s.preconditioner.radius = v->number();
        v->fail_unless(s.preconditioner.radius >= 1,
                       "expected a radius >= 1 (rings of the finer grid), got {}",
                       s.preconditioner.radius);
    }
    if (auto v = only_pcg("smoother_degree"))
        s.preconditioner.smoother_degree = static_cast<int>(v->integer(1, 10));
    if (auto v = only_pcg("deflation")) s.preconditioner.deflation = v->boolean();
    if (auto v = only_pcg("deflation_rings"))
        s.preconditioner.deflation_rings = static_cast<int>(v->integer(0, mra::kMaxDeflationRings));
}

/// mra-pcg solves the linear fine model of a grid whose cells halve, or of linear triangles or
/// tetrahedra with enough nodes for a coarser automatic level: checked before any work.
void check_mra_pcg(const Scene& s, const JsonReader& sv) {
    const JsonReader backend = sv.at("backend");
    backend.fail_unless(s.kinematics == sim::Kinematics::Linear,
                        "mra-pcg solves linear fine models; corotated kinematics factorize their "
                        "tangents (use cholmod)");
    try {
        mra::preconditioner_levels(s.mesh, s.preconditioner);
    } catch (const Error& e) {
        (sv.has("levels") ? sv.at("levels") : backend).fail("{}", e.what());
    }
}

}  // namespace

Scene parse_scene(const json& j, const std::string& source, const std::string& base_dir,
                  const GivenMeshes& given) {
    Scene s;
    s.source = source;
    s.base_dir = base_dir;
    const JsonReader root(j, "", s.source);
    root.require_object();
    root.allow_only({"description", "dimension", "mesh", "materials", "material_field", "plane",
                     "dirichlet", "loads", "probes", "fem", "solver", "coarse", "dynamics",
                     "kinematics", "corotation", "warp"});
    // Everything that needs no mesh first, so that a bad option fails before a mesh is read.
    std::optional<int> dimension;
    if (auto d = root.find("dimension")) dimension = static_cast<int>(d->integer(2, 3));
    if (auto p = root.find("plane")) {
        const std::string mode = p->string();
        p->fail_unless(mode == "strain" || mode == "stress", "expected \"strain\" or \"stress\"");
        s.plane = mode == "strain" ? material::PlaneMode::Strain : material::PlaneMode::Stress;
    }
    if (auto sv = root.find("solver")) parse_solver(*sv, s);
    if (auto f = root.find("fem")) {
        f->allow_only({"formulation"});
        if (auto v = f->find("formulation")) {
            try {
                s.formulation = fem::parse_formulation(v->string());
            } catch (const InvalidScene&) {
                throw;
            } catch (const Error& e) {
                v->fail("{}", e.what());
            }
        }
    }
    if (auto c = root.find("coarse")) s.coarse = parse_coarse_options(c->json(), s.source);
    if (auto d = root.find("dynamics")) s.dynamics = parse_dynamics_options(d->json(), s.source);
    if (auto k = root.find("kinematics"))
        s.kinematics = k->choice({"linear", "corotational"}) == 0 ? sim::Kinematics::Linear
                                                                  : sim::Kinematics::Corotational;
    if (auto w = root.find("warp")) s.rs_warp = w->choice({"none", "rs"}) == 1;
    if (auto c = root.find("corotation")) {
        c->fail_unless(s.kinematics == sim::Kinematics::Corotational,
                       "applies to \"kinematics\": \"corotational\" only; add that key or "
                       "remove this block");
        s.corotation = parse_corotation_options(c->json(), s.source);
    }
    if (auto c = root.find("coarse")) {
        s.coarse_block = c->json();
        check_coarse_operator(s, *c);
    }

    std::map<int, material::Material> carried;
    if (given.mesh) {
        root.fail_unless(!root.has("mesh"), "the mesh is also given directly; remove \"mesh\"");
        s.mesh = given_mesh(*given.mesh, s.source, "mesh");
        carried = given.element_materials;
        root.fail_unless(
            carried.empty() || carried.size() == static_cast<std::size_t>(s.mesh.num_elements()),
            "mesh: {} element materials for {} elements", carried.size(), s.mesh.num_elements());
    } else {
        s.mesh = parse_mesh(root.at("mesh"), dimension, base_dir, &carried);
    }
    s.dimension = s.mesh.dim();
    root.fail_unless(!dimension || *dimension == s.dimension, "dimension is {} but the mesh is {}D",
                     dimension.value_or(0), s.dimension);
    if (s.solver.backend == solve::Backend::MraPcg) check_mra_pcg(s, root.at("solver"));
    const int dim = s.dimension;
    if (auto v = root.find("fem"); v && v->has("formulation"))
        v->at("formulation")
            .fail_unless(fem::formulation_applies(s.formulation, s.mesh.type),
                         "\"{}\" does not apply to {} elements; expected \"standard\" (any "
                         "element) or \"incompatible\" (hex and quad elements only)",
                         fem::formulation_name(s.formulation), mesh::element_name(s.mesh.type));

    if (!carried.empty()) {
        root.fail_unless(!root.has("materials") && !root.has("material_field"),
                         "{} one elasticity tensor per element ({} and density); remove "
                         "\"materials\" and \"material_field\"",
                         given.mesh ? "the mesh given directly has" : "mesh.file carries",
                         given.mesh ? "C_mandel or C_voigt" : "cell fields C_voigt_IJ");
        s.materials = std::move(carried);
    }
    if (auto f = root.find("material_field"))
        s.materials = apply_material_field(*f, s.mesh, s.plane, base_dir);
    if (auto m = root.find("materials")) {
        m->require_object();
        for (const auto& [key, value] : m->json().items()) {
            const JsonReader entry = m->at(key);
            int id = 0;
            const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), id);
            entry.fail_unless(
                ec == std::errc() && end == key.data() + key.size() && std::to_string(id) == key,
                "material keys must be integer ids written without sign or "
                "leading zeros (\"1\", not \"01\" or \"+1\")");
            s.materials[id] = parse_material(entry, dim, s.plane);
        }
    }
    root.fail_unless(!s.materials.empty(), "no materials: give \"materials\" or an image field");
    if (auto p = root.find("plane")) {
        p->fail_unless(dim == 2, "applies to 2D scenes only; this one is 3D");
        for (const auto& [id, mat] : s.materials)
            p->fail_unless(!std::isnan(mat.nu),
                           "applies to isotropic materials (E, nu) only, but material {} is "
                           "anisotropic: a 2D C_voigt / C_mandel is already the in-plane tensor; "
                           "remove \"plane\"",
                           id);
    }

    if (auto d = root.find("dirichlet")) s.dirichlet = parse_box_conditions(*d, dim, false);
    s.gravity = Eigen::VectorXd::Zero(dim);
    if (auto l = root.find("loads")) {
        l->allow_only({"gravity", "traction"});
        if (auto g = l->find("gravity")) s.gravity = g->vector(dim);
        if (auto t = l->find("traction")) s.traction = parse_box_conditions(*t, dim, true);
    }
    if (s.dynamics && s.dynamics->initial_velocity.size() == 0)
        s.dynamics->initial_velocity = Eigen::VectorXd::Zero(dim);
    else if (s.dynamics)
        root.at("dynamics")
            .at("initial_velocity")
            .fail_unless(s.dynamics->initial_velocity.size() == dim,
                         "expected {} numbers for a {}D scene, got {}", dim, dim,
                         s.dynamics->initial_velocity.size());
    if (auto p = root.find("probes"))
        for (std::size_t i = 0; i < p->array_size(); ++i) s.probes.push_back(p->at(i).vector(dim));
    if (auto c = root.find("coarse"); c && c->has("level_meshes"))
        s.coarse.level_meshes = level_meshes(c->at("level_meshes"), s.mesh, s.coarse.mra, base_dir);
    if (auto c = root.find("coarse"); c && c->has("mesh")) {
        c->fail_unless(!given.coarse_mesh,
                       "the coarse mesh is also given directly; remove "
                       "\"mesh\"");
        s.coarse.mesh = coarse_mesh(c->at("mesh"), dim, base_dir);
    } else if (given.coarse_mesh) {
        s.coarse.mesh = given_mesh(*given.coarse_mesh, s.source, "coarse.mesh");
        CG_VERIFY_AS(InvalidScene, s.coarse.mesh->dim() == dim,
                     "{}: coarse.mesh: the coarse mesh is {}D, the scene {}D", s.source,
                     s.coarse.mesh->dim(), dim);
    }
    return s;
}

Scene with_coarse_overrides(Scene s, const json& overrides) {
    const JsonReader o(overrides, "coarse", s.source);
    o.require_object();
    json block = s.coarse_block.is_object() ? s.coarse_block : json::object();
    for (const auto& [key, value] : overrides.items()) block[key] = value;
    std::optional<mesh::Mesh> mesh = std::move(s.coarse.mesh);
    std::vector<mesh::Mesh> levels = std::move(s.coarse.level_meshes);
    s.coarse = parse_coarse_options(block, s.source);
    const JsonReader c(block, "coarse", s.source);
    check_coarse_operator(s, c);
    s.coarse.mesh =
        overrides.contains("mesh")
            ? std::optional<mesh::Mesh>(coarse_mesh(c.at("mesh"), s.dimension, s.base_dir))
            : std::move(mesh);
    if (c.has("level_meshes"))
        s.coarse.level_meshes =
            overrides.contains("level_meshes")
                ? level_meshes(c.at("level_meshes"), s.mesh, s.coarse.mra, s.base_dir)
                : std::move(levels);
    s.coarse_block = std::move(block);
    return s;
}

SparseMatrix mass_matrix(const Scene& scene, const FineModel& model) {
    return fem::mass_matrix(model.mesh, model.materials,
                            scene.dynamics ? scene.dynamics->mass : fem::MassType::Consistent);
}

json parse_json(std::string_view text, const std::string& source) {
    // The parser reports each key as it reads it; a stack of the open objects' keys and the open
    // arrays' indices finds repeated keys and names their path.
    struct Open {
        bool object = true;
        std::set<std::string> keys;
        std::string key;
        std::size_t index = 0;
    };
    std::vector<Open> open;
    const auto path = [&open](const std::string& last) {
        std::string p;
        for (std::size_t i = 0; i + 1 < open.size(); ++i)
            p += open[i].object ? (p.empty() ? "" : ".") + open[i].key
                                : fmt::format("[{}]", open[i].index);
        return p.empty() ? last : p + "." + last;
    };
    const auto element_done = [&open] {
        if (!open.empty() && !open.back().object) ++open.back().index;
    };
    const json::parser_callback_t callback = [&](int, json::parse_event_t event, json& parsed) {
        using E = json::parse_event_t;
        if (event == E::object_start) open.push_back({});
        if (event == E::array_start) open.push_back({false, {}, {}, 0});
        if (event == E::key) {
            const std::string key = parsed.get<std::string>();
            CG_VERIFY_AS(InvalidScene, open.back().keys.insert(key).second,
                         "{}: {}: the key is given twice (the later one would silently win)",
                         source, path(key));
            open.back().key = key;
        }
        if (event == E::object_end || event == E::array_end) {
            open.pop_back();
            element_done();
        }
        if (event == E::value) element_done();
        return true;
    };
    try {
        return json::parse(text.begin(), text.end(), callback);
    } catch (const json::exception& e) {
        // parse_error for syntax, out_of_range for numbers beyond double range (1e400)
        CG_VERIFY_AS(InvalidScene, false, "{}: not valid JSON: {}", source, e.what());
    }
}

Scene load_scene(const std::string& file) {
    std::error_code ec;
    CG_VERIFY_AS(InvalidScene, fs::is_regular_file(file, ec), "cannot open scene file {}: {}", file,
                 fs::exists(file, ec) ? "not a regular file" : "no such file");
    std::ifstream in(file, std::ios::binary);
    CG_VERIFY_AS(InvalidScene, in.good(), "cannot open scene file {}", file);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return parse_scene(parse_json(text, file), file, fs::path(file).parent_path().string());
}

fem::Dirichlet dirichlet_conditions(const Scene& scene, const mesh::Mesh& mesh,
                                    const std::string& what) {
    fem::Dirichlet bc;
    for (const BoxCondition& c : scene.dirichlet) {
        const std::vector<Index> nodes = mesh::nodes_in_box(mesh, c.box.min, c.box.max);
        CG_VERIFY_AS(InvalidScene, !nodes.empty(), "{}: {}.box selects no node of the {}",
                     scene.source, c.key, what);
        bc.fix_nodes(nodes, c.value);
    }
    return bc;
}

Vector load_vector(const Scene& scene, const mesh::Mesh& mesh,
                   const material::ElementMaterials& materials, const mesh::Boundary& boundary,
                   const std::string& what) {
    Vector f = Vector::Zero(mesh.num_dofs());
    if (scene.gravity.squaredNorm() > 0) f += fem::gravity_load(mesh, materials, scene.gravity);
    for (const BoxCondition& c : scene.traction) {
        const std::vector<Index> facets = mesh::facets_in_box(mesh, boundary, c.box.min, c.box.max);
        CG_VERIFY_AS(InvalidScene, !facets.empty(), "{}: {}.box selects no boundary {} of the {}",
                     scene.source, c.key, mesh.dim() == 3 ? "face" : "edge", what);
        f += fem::traction_load(mesh, boundary, facets, c.value);
    }
    return f;
}

solve::SolverOptions fine_solver(const Scene& scene, const FineModel& model) {
    solve::SolverOptions o = scene.solver;
    if (o.backend == solve::Backend::MraPcg)
        o.preconditioner = mra::hierarchy_preconditioner(model.mesh, model.materials, model.bc.dofs,
                                                         scene.preconditioner);
    return o;
}

solve::SolverOptions direct_solver(const Scene& scene) {
    return scene.solver.backend == solve::Backend::MraPcg ? solve::SolverOptions{} : scene.solver;
}

FineModel build_fine_model(const Scene& scene, Timings* timings) {
    FineModel m;
    m.source = scene.source;
    m.mesh = scene.mesh;
    {
        const Phase phase("assemble", timings);
        try {
            m.materials = material::assign(m.mesh, scene.materials);
        } catch (const Error& e) {
            CG_VERIFY_AS(InvalidScene, false, "{}: materials: {}", scene.source, e.what());
        }
        m.boundary = mesh::boundary(m.mesh);
        m.bc = dirichlet_conditions(scene, m.mesh, "mesh");
        m.K = fem::stiffness_matrix(m.mesh, m.materials, scene.formulation);
        m.warnings = fem::locking_warnings(m.mesh, m.materials, scene.formulation);
        m.f = load_vector(scene, m.mesh, m.materials, m.boundary, "mesh");
    }
    return m;
}

namespace {

/// Connected parts of a mesh (nodes sharing an element): the part of each node, 0..parts-1.
std::vector<Index> mesh_parts(const mesh::Mesh& m, Index& parts) {
    std::vector<Index> root(static_cast<std::size_t>(m.num_nodes()));
    for (Index v = 0; v < m.num_nodes(); ++v) root[static_cast<std::size_t>(v)] = v;
    const auto find = [&root](Index v) {
        while (root[static_cast<std::size_t>(v)] != v)
            v = root[static_cast<std::size_t>(v)] =
                root[static_cast<std::size_t>(root[static_cast<std::size_t>(v)])];
        return v;
    };
    for (Index e = 0; e < m.num_elements(); ++e)
        for (Eigen::Index a = 1; a < m.elements.cols(); ++a)
            root[static_cast<std::size_t>(find(m.elements(e, a)))] = find(m.elements(e, 0));
    std::vector<Index> part(root.size(), -1), label(root.size(), -1);
    parts = 0;
    for (Index v = 0; v < m.num_nodes(); ++v) {
        Index& l = label[static_cast<std::size_t>(find(v))];
        if (l < 0) l = parts++;
        part[static_cast<std::size_t>(v)] = l;
    }
    return part;
}

/// The stiffness contrast of the fine materials: their Young's moduli's span (for anisotropic
/// materials the mean axis modulus, Material::E).
std::pair<double, double> modulus_range(const material::ElementMaterials& materials) {
    double e_min = std::numeric_limits<double>::infinity(), e_max = 0;
    for (const material::Material& mat : materials.table) {
        e_min = std::min(e_min, mat.E);
        e_max = std::max(e_max, mat.E);
    }
    return {e_min, e_max};
}

/// Why the fine stiffness with its Dirichlet conditions is singular, for the error message: a
/// connected part of the mesh without any Dirichlet DOF moves freely, one whose fixed DOFs do not
/// stop all its rigid motions (fixed nodes on one line in 3D) turns; if every part is held against
/// every rigid motion, the conditions are not to blame and K is singular to round-off, which the
/// materials' stiffness contrast explains. `held` tells whether every part was held.
std::string singular_cause(const FineModel& model, bool& held) {
    const mesh::Mesh& m = model.mesh;
    const int dim = m.dim(), r = dim == 2 ? 3 : 6;
    Index parts = 0;
    const std::vector<Index> part = mesh_parts(m, parts);
    const auto P = [](Index i) { return static_cast<std::size_t>(i); };
    std::vector<Index> nodes(P(parts), 0);
    Matrix centre = Matrix::Zero(parts, dim);
    Vector radius = Vector::Zero(parts);
    for (Index v = 0; v < m.num_nodes(); ++v) {
        ++nodes[P(part[P(v)])];
        centre.row(part[P(v)]) += m.rest_positions.row(v);
    }
    for (Index p = 0; p < parts; ++p) centre.row(p) /= static_cast<double>(nodes[P(p)]);
    for (Index v = 0; v < m.num_nodes(); ++v)
        radius[part[P(v)]] =
            std::max(radius[part[P(v)]], (m.rest_positions.row(v) - centre.row(part[P(v)])).norm());
    // Gram matrix of the rigid motions (translations, rotations about the part's centre scaled by
    // its radius) over each part's fixed DOFs: full rank if and only if they stop them all.
    std::vector<Matrix> gram(P(parts), Matrix::Zero(r, r));
    std::vector<Index> fixed(P(parts), 0);
    for (const Index dof : model.bc.dofs) {
        const Index v = dof / dim, p = part[P(v)];
        const int c = static_cast<int>(dof % dim);
        const Eigen::VectorXd x =
            (m.rest_positions.row(v) - centre.row(p)).transpose() / std::max(radius[p], 1e-300);
        Eigen::VectorXd row = Eigen::VectorXd::Zero(r);
        row[c] = 1;  // translation along c
        if (dim == 2) {
            row[2] = c == 0 ? -x[1] : x[0];
        } else {
            for (int k = 0; k < 3; ++k)  // component c of e_k × x
                row[3 + k] = Eigen::Vector3d::Unit(k).cross(Eigen::Vector3d(x))[c];
        }
        gram[P(p)] += row * row.transpose();
        ++fixed[P(p)];
    }
    held = false;
    const auto where = [&](Index p) {
        return fmt::format(
            "part {} of the mesh's {} connected parts ({} nodes, centred at ({:.4g}))", p + 1,
            parts, nodes[P(p)], fmt::join(centre.row(p), ", "));
    };
    for (Index p = 0; p < parts; ++p)
        if (fixed[P(p)] == 0)
            return fmt::format(
                "{} has no Dirichlet node and can move freely; add a dirichlet box "
                "that touches it",
                where(p));
    for (Index p = 0; p < parts; ++p) {
        const Eigen::SelfAdjointEigenSolver<Matrix> eig(gram[P(p)]);
        if (eig.eigenvalues()[0] < 1e-10 * eig.eigenvalues()[r - 1])
            return fmt::format(
                "{} has {} fixed DOFs, which do not stop all its rigid motions "
                "(fixed nodes on one line can turn about it); fix nodes off that "
                "line",
                where(p), fixed[P(p)]);
    }
    held = true;
    const auto [e_min, e_max] = modulus_range(model.materials);
    return fmt::format(
        "every connected part of the mesh ({}) is held against all its rigid motions, so the "
        "Dirichlet conditions are not missing: K is numerically singular at the materials' "
        "stiffness contrast of {:.3g} (Young's moduli {:.3g} to {:.3g}): at such a ratio "
        "neither a factorization (cholmod, ldlt) nor conjugate gradients can tell the soft "
        "material from a free one in double precision (a 16x16 checkerboard clamped at one edge "
        "solves up to 1e12 and fails from 1e13); lower the contrast (e.g. model the soft "
        "material as a cavity, or raise its modulus)",
        parts, e_max / e_min, e_min, e_max);
}

}  // namespace

namespace {

/// Runs solve(), which solves with the model's stiffness or tangent, and explains a singular
/// model (NotPositiveDefinite, or conjugate gradients failing for that cause) by its cause.
template <class Solve>
void explaining_singular(const FineModel& model, Solve&& solve) {
    try {
        solve();
    } catch (const NotPositiveDefinite& e) {
        bool held = false;
        const std::string cause = singular_cause(model, held);
        throw NotPositiveDefinite(
            fmt::format("{}: the fine model is singular: {} ({})", model.source, cause,
                        held ? solve::without_singular_hint(e.what()) : std::string(e.what())));
    } catch (const solve::NotConverged& e) {
        // Conjugate gradients: a singular K (missing conditions) or one too ill-conditioned.
        bool held = false;
        const std::string cause = singular_cause(model, held);
        const auto [e_min, e_max] = modulus_range(model.materials);
        if (!held || e_max / e_min >= 1e10)
            throw NotPositiveDefinite(fmt::format("{}: the fine model is singular: {} ({})",
                                                  model.source, cause,
                                                  solve::without_singular_hint(e.what())));
        throw;
    }
}

}  // namespace

StaticSolution solve_static(const FineModel& model, const solve::SolverOptions& options,
                            Timings* timings, bool keep_factorization) {
    solve::SolverOptions node_options = options;
    node_options.node_dofs = model.mesh.dim();  // K is interleaved per node
    StaticSolution s;
    auto solver = std::make_shared<solve::SpdSolver>(node_options);
    explaining_singular(
        model, [&] { s.u = fem::solve_static(model.K, model.f, model.bc, *solver, timings); });
    s.strain_energy = fem::strain_energy(model.K, s.u);
    if (keep_factorization) s.factorization = std::move(solver);
    return s;
}

StaticSolution solve_corotated(const FineModel& model, const Scene& scene, Timings* timings) {
    solve::SolverOptions node_options = scene.solver;
    node_options.node_dofs = model.mesh.dim();
    const fem::CorotatedModel corotated(model.mesh, model.materials, scene.formulation,
                                        scene.corotation.frame);
    StaticSolution s;
    try {
        explaining_singular(model, [&] {
            sim::CorotatedSolution c = sim::solve_corotated_static(
                corotated, model.f, model.bc, scene.corotation, node_options, timings);
            s.u = std::move(c.u);
            s.strain_energy = c.energy;
            s.newton = std::move(c.report);
        });
    } catch (const sim::NewtonFailed& e) {
        throw sim::NewtonFailed(fmt::format("{}: {}", model.source, e.what()));
    }
    return s;
}

ProbeSampler::ProbeSampler(const Scene& scene, const mesh::Mesh& m) : m_mesh(&m) {
    if (scene.probes.empty()) return;
    const mesh::PointLocator locator(m);
    for (std::size_t i = 0; i < scene.probes.size(); ++i) {
        const auto loc = locator.locate(scene.probes[i]);
        CG_VERIFY_AS(InvalidScene, loc.has_value(), "{}: probes[{}] = [{}] lies outside the mesh",
                     scene.source, i, fmt::join(scene.probes[i], ", "));
        m_locations.push_back(*loc);
    }
}

std::vector<Eigen::VectorXd> ProbeSampler::operator()(const Vector& u) const {
    std::vector<Eigen::VectorXd> out;
    for (const mesh::Location& loc : m_locations)
        out.push_back(mesh::interpolate(*m_mesh, loc, u, m_mesh->dim()));
    return out;
}

std::vector<Eigen::VectorXd> probe_displacements(const Scene& scene, const mesh::Mesh& m,
                                                 const Vector& u) {
    return ProbeSampler(scene, m)(u);
}

json demo_scene(double scale) {
    // Cubic cells in multiples of 4, so that the 3-level hierarchy's coarsest grid is whole:
    // 16b x 4b x 4b with b = round(3 scale), at least 1 (scale 1: 48x12x12).
    const int b = std::max(1, static_cast<int>(std::lround(3 * scale)));
    const int nx = 16 * b, ny = 4 * b;
    return json{
        {"description",
         "Accordion beam: a 4x1x1 block of alternating stiff (E = 1e7) and soft (E = 1e4) "
         "layers across its axis, clamped at x = 0 and hanging under gravity. Coarse: a tet grid "
         "with 4x coarser cells per axis (6 tets each) for the effective tensors and the "
         "baselines, and 3 levels of the material-adapted hierarchy (coarsest grid 4x coarser "
         "per axis): the same 624 coarse DOFs at scale 1. Dynamics: released from rest under "
         "gravity, implicit midpoint, about two periods of the lowest bending mode."},
        {"dimension", 3},
        {"mesh",
         {{"grid",
           {{"min", {0, 0, 0}}, {"max", {4, 1, 1}}, {"cells", {nx, ny, ny}}, {"element", "hex"}}}}},
        {"material_field", {{"layers", {{"axis", "x"}, {"thickness", 0.25}, {"ids", {1, 2}}}}}},
        {"materials",
         {{"1", {{"E", 1e7}, {"nu", 0.3}, {"density", 1.0}}},
          {"2", {{"E", 1e4}, {"nu", 0.45}, {"density", 1.0}}}}},
        {"dirichlet", {{{"box", {{"min", {-1e-9, -1, -1}}, {"max", {1e-9, 2, 2}}}}}}},
        {"loads", {{"gravity", {0, 0, -9.81}}}},
        {"probes", {{4, 0.5, 0.5}, {2, 0.5, 0.5}, {1, 0.5, 0.5}}},
        {"coarse",
         {{"mesh",
           {{"grid",
             {{"min", {0, 0, 0}},
              {"max", {4, 1, 1}},
              {"cells", {nx / 4, ny / 4, ny / 4}},
              {"element", "tet"}}}}},
          {"levels", 3},
          {"cell_tensors", false},
          {"spectrum_max_dofs", 0}}},
        // Released from rest under gravity: 1.1 time units, about two periods of the lowest
        // bending mode (1.93 Hz on 48x12x12 hexes, `coarsegrain modes`; a coarser grid is
        // stiffer and vibrates faster), 52 steps per period.
        {"dynamics", {{"integrator", "midpoint"}, {"dt", 0.01}, {"steps", 110}, {"start", "rest"}}},
    };
}

}  // namespace coarsegrain::scene
