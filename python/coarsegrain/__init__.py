"""coarsegrain: numerical coarsening of heterogeneous linear-elastic materials.

Scenes (the JSON format of docs/guide.md) from a file or from Python objects, the fine FEM
model as SciPy / NumPy arrays, and every coarsening method of the command-line tool with its
errors against the fine solution::

    import coarsegrain
    scene = coarsegrain.load_scene("examples/layered_beam/scene.json")
    fine = coarsegrain.build_fine_model(scene)          # .stiffness, .mass, .load
    result = coarsegrain.coarsen(scene, "effective-tensor")
    result.errors                                        # summary.json's "errors"
    result.coarse_model.element_tensors()                # #elements x 6 x 6, Mandel

DOFs are interleaved per node (x0 y0 z0 x1 y1 z1 ...). Symmetric tensors are in Mandel
notation (shear components scaled by sqrt(2)) unless "voigt" is asked for. Arrays the C++
objects own are read-only views (no copy); call .copy() for a writable one. Long calls release
the GIL; Ctrl-C stops them at their next phase boundary and raises KeyboardInterrupt.
"""

import json as _json
import os as _os

import numpy as _np

from ._core import (  # noqa: F401  (re-exported)
    CoarseModel,
    CoarsenResult,
    Error,
    FineModel,
    Hierarchy,
    Interrupted,
    InvalidScene,
    Level,
    MeshReadError,
    NewtonFailed,
    NotConverged,
    NotPositiveDefinite,
    Scene,
    SingularMatrix,
    StaticSolution,
    build_fine_model,
    demo_scene,
    directional_young,
    load_scene,
    method_names,
)
from . import _core

__all__ = [
    "CoarseModel", "CoarsenResult", "Error", "FineModel", "Hierarchy", "Interrupted",
    "InvalidScene", "Level", "MeshReadError", "ModeComparison", "Modes", "NewtonFailed",
    "NotConverged", "NotPositiveDefinite", "Run", "Scene", "Simulation", "SingularMatrix",
    "StaticSolution", "build_fine_model", "coarsen", "demo_scene", "directional_young",
    "load_scene", "method_names", "modes", "scene_from_dict", "simulate", "solve_static",
    "to_fine",
]

_MESH_ARRAYS = ("nodes", "elements")


def _to_json(value):
    """JSON text of a scene block: NumPy arrays and scalars become lists and numbers."""

    def default(o):
        if isinstance(o, _np.ndarray):
            return o.tolist()
        if isinstance(o, _np.generic):
            return o.item()
        raise TypeError(f"{type(o).__name__} is not a JSON value: {o!r}")

    return _json.dumps(value, default=default, allow_nan=False)


def _mesh_arrays(mesh, key):
    """The arrays of a mesh given as {"nodes", "elements", ...}, with its element type."""
    unknown = set(mesh) - {"nodes", "elements", "element", "material_ids", "C_mandel",
                           "C_voigt", "density"}
    if unknown:
        raise InvalidScene(f"{key}: unknown key(s) {sorted(unknown)}; expected nodes, elements, "
                           "element, material_ids, C_mandel or C_voigt, density")
    if "C_mandel" in mesh and "C_voigt" in mesh:
        raise InvalidScene(f"{key}: give one of C_mandel and C_voigt")
    out = dict(mesh)
    nodes = _np.asarray(mesh["nodes"], dtype=float)
    elements = _np.asarray(mesh["elements"])
    if "element" not in out:
        if nodes.ndim != 2 or elements.ndim != 2:
            raise InvalidScene(f"{key}: nodes and elements must be 2D arrays")
        by_shape = {(2, 3): "tri", (2, 4): "quad", (3, 4): "tet", (3, 8): "hex"}
        shape = (nodes.shape[1], elements.shape[1])
        if shape not in by_shape:
            raise InvalidScene(f"{key}: {shape[1]} nodes per element in {shape[0]}D; expected "
                               "tri (3) or quad (4) in 2D, tet (4) or hex (8) in 3D")
        out["element"] = by_shape[shape]
    out["nodes"], out["elements"] = nodes, elements
    if "density" in out:
        density = _np.asarray(out["density"], dtype=float)
        out["density"] = _np.broadcast_to(density, (elements.shape[0],)) \
            if density.ndim == 0 else density
    return out


def scene_from_dict(d, base_dir=".", source="<dict>"):
    """A Scene from a dict with the JSON scene's keys (docs/guide.md), values may be NumPy.

    The fine mesh and the coarse mesh may be given as arrays instead of files:
    ``d["mesh"]`` (and ``d["coarse"]["mesh"]``) a dict with

    - ``nodes``: #nodes x dim rest positions;
    - ``elements``: #elements x k node indices (VTK ordering, k = 3 tri, 4 quad or tet, 8 hex);
    - ``element`` (optional): "tri", "quad", "tet" or "hex" (default: from dim and k);
    - ``material_ids`` (optional, fine mesh): #elements ids into ``d["materials"]``;
    - ``C_mandel`` or ``C_voigt`` (optional, fine mesh): #elements x n x n tensor per element
      (n = 6 in 3D, 3 in 2D) with ``density`` (#elements, or one number): one material per
      element, so ``d`` has no "materials" or "material_field".

    Relative file names are resolved against ``base_dir``; ``source`` names the scene in
    messages. Raises InvalidScene naming the key, as the command-line tool does.
    """
    if not isinstance(d, dict):
        raise InvalidScene(f"{source}: expected a dict with the scene's keys")
    d = dict(d)
    mesh = coarse_mesh = None
    if isinstance(d.get("mesh"), dict) and any(k in d["mesh"] for k in _MESH_ARRAYS):
        mesh = _mesh_arrays(d.pop("mesh"), "mesh")
    coarse = d.get("coarse")
    if isinstance(coarse, dict) and isinstance(coarse.get("mesh"), dict) \
            and any(k in coarse["mesh"] for k in _MESH_ARRAYS):
        coarse = dict(coarse)
        coarse_mesh = _mesh_arrays(coarse.pop("mesh"), "coarse.mesh")
        d["coarse"] = coarse
    return _core._parse_scene(_to_json(d), source, _os.fspath(base_dir), mesh, coarse_mesh)


def _with_coarse(scene, options):
    """The scene with its "coarse" block keys replaced by ``options`` (validated)."""
    return scene._with_coarse(_to_json(options)) if options else scene


Scene.with_coarse = lambda self, **options: _with_coarse(self, options)
Scene.with_coarse.__doc__ = """The scene with keys of its "coarse" block replaced or added.

Each keyword is a coarse.<key> of docs/guide.md (levels=2, refinement="dirac", boundary="mixed",
mesh={"file": "coarse.msh"}, ...); the block is validated again. Raises InvalidScene naming
coarse.<key>."""


def coarsen(scene, method="effective-tensor", *, fine=None, **options):
    """Builds a coarse model with ``method``, solves it and the fine model, and compares them.

    ``method`` is one of method_names(): "effective-tensor", "naive", "voigt", "reuss",
    "mra", "mra-linear", "mra-dirac", "mra-linear-blind", "mra-dirac-blind". Keyword
    ``options`` override the scene's "coarse" block keys (levels=3, boundary="mixed", ...).
    ``fine`` (optional): a FineModel of the same scene, solved once and reused by further
    calls (its solution is attached to it).

    Returns a CoarsenResult: ``.errors`` (the CLI's summary.json "errors" for this scene and
    method), ``.coarse_model`` (``.stiffness``, ``.mass``, ``.load``, ``.to_fine``,
    ``.element_tensors()``), ``.u``, ``.u_fine``, ``.fine_u``. This is exactly
    `coarsegrain coarsen SCENE --method METHOD` without its files. Raises Error (InvalidScene
    for a method the scene cannot run, naming the key) with the CLI's message.
    """
    if isinstance(method, (list, tuple)):
        raise TypeError("coarsen: one method at a time; call it once per method (fine= reuses "
                        "the fine solve)")
    return _core._coarsen(scene, method, _to_json(options) if options else "", fine)


def solve_static(model):
    """Solves a FineModel's static problem (FineModel.solve_static): a StaticSolution."""
    return model.solve_static()


class _FineMapOperator:
    """The map from coarse to fine DOFs of a model that never forms it (the hierarchy's
    Φ^{1,T} S, applied level by level): ``to_fine @ u`` for a coarse vector u (#fine), or
    for each column of a #coarse x k array U (#fine x k, all columns in one call without the
    GIL). Raises Error naming the expected shape if u or U has the wrong number of rows."""

    def __init__(self, model):
        self._model = model
        self.shape = tuple(model._to_fine_shape)
        self.dtype = _np.dtype(float)

    def __matmul__(self, u):
        u = _np.asarray(u, dtype=float)
        if u.ndim == 1:
            return self._model._apply_to_fine(u)
        if u.ndim == 2:
            return self._model._apply_to_fine_columns(u)
        raise ValueError(f"to_fine @ u: expected a vector or a matrix, got shape {u.shape}")

    def dot(self, u):
        """Same as ``self @ u``."""
        return self @ u

    def __repr__(self):
        return f"<coarsegrain to_fine operator {self.shape[0]}x{self.shape[1]} (not formed)>"


def to_fine(model):
    """The map from a CoarseModel's DOFs to the fine DOFs (CoarseModel.to_fine)."""
    matrix = model._to_fine_matrix
    return matrix if matrix is not None else _FineMapOperator(model)


CoarseModel.to_fine = property(to_fine, doc="""The map from coarse DOFs to the fine DOFs,
u_fine = to_fine @ u: a scipy.sparse.csc_matrix (effective tensors, baselines; read-only, no
copy), or for the hierarchy (mra) an operator with ``@`` and ``.shape`` that applies it without
forming it.""")


def _method_name(method):
    if method is not None and not isinstance(method, str):
        raise TypeError("one method at a time (or None for the fine model alone); call it once "
                        "per method")
    return method


class Run:
    """One model's run of a Simulation, on the fine mesh (T saved times, P probes, n fine DOFs).

    - ``probes``: T x P x dim displacements at the scene's probes;
    - ``frames``: T x n displacements on the fine mesh (a coarse model's carried there, post-warped
      as the scene asks), ``frames[i]`` at ``times[i]``; None if simulate(frames=False);
    - ``coarse_frames`` (a method's run): T x #coarse DOFs, the coarse model's own DOFs;
    - ``coarse_model`` (a method's run): the CoarseModel that was stepped;
    - ``entry``: the run's part of the summary (a method: the CLI's method keys; the linear fine
      model: summary["fine"]["linear"]).
    """

    def __init__(self, arrays, entry):
        self.probes = arrays["probes"]
        self.frames = arrays["frames"]
        self.coarse_frames = arrays.get("coarse_frames")
        self.coarse_model = arrays.get("coarse_model")
        self.entry = entry

    def __repr__(self):
        return f"<coarsegrain.Run {self.probes.shape[0]} frames>"


class Simulation:
    """The result of simulate(): the CLI's `coarsegrain simulate` without its files.

    - ``times``: the T saved times (t = 0 and every output_every-th step);
    - ``fine``: the fine model's Run (``frames`` are the fine displacements);
    - ``fine_linear``: with corotational kinematics, the linear fine model's Run beside it
      (summary["fine"]["linear"]); else None;
    - ``coarse``: the method's Run (None without a method);
    - ``summary``: the CLI's summary.json for the same scene and method, but the keys of its
      files ("plots", "animation_frames", "pvd"), with the same keys and values (the timings
      are this run's: their phases but "read" and "animation");
    - ``timings``: summary["timings"] ({"fine": ...} and with a method {"coarse": ...});
    - ``errors``: summary["errors"] with a method ("trajectory_l2_rel", "probe_max_rel",
      "phase"), None without;
    - ``speedup``: summary["speedup"] with a method, None without;
    - ``fine_model``: the FineModel that was stepped.
    """

    def __init__(self, d, method):
        self.method = method
        self.summary = d["summary"]
        self.times = d["times"]
        self.fine_model = d["fine_model"]
        self.fine = Run(d["fine"], self.summary["fine"])
        self.fine_linear = Run(d["fine_linear"], self.summary["fine"]["linear"]) \
            if d["fine_linear"] is not None else None
        self.coarse = Run(d["coarse"], {k: self.summary[k] for k in
                                        ("method", "coarse", "probes", "timings", "speedup",
                                         "errors")}) if d["coarse"] is not None else None
        self.timings = self.summary["timings"]
        self.errors = self.summary.get("errors") if method else None
        self.speedup = self.summary.get("speedup") if method else None

    def __repr__(self):
        return (f"<coarsegrain.Simulation {self.method or 'fine only'}, "
                f"{len(self.times)} frames>")


def simulate(scene, method=None, *, frames=True, **options):
    """Steps the scene's "dynamics" on the fine model and, with ``method``, on its coarse model.

    Exactly `coarsegrain simulate SCENE [--method METHOD]` without its files: the fine model is
    stepped from the scene's start (corotated with "kinematics": "corotational", and the linear
    fine model beside it; linear otherwise, post-warped with "warp": "rs"); the method's coarse
    model (built with the scene's "coarse" block, keyword ``options`` overriding its keys as in
    coarsen()) is stepped from the matching state, each saved frame carried to the fine mesh and
    compared with the fine frame of the same time. ``method`` is one name of method_names(), or
    None for the fine model alone. ``frames=False`` keeps only the probes (the frames on the fine
    mesh take T x n doubles per run).

    Returns a Simulation (times, fine / fine_linear / coarse runs with probes and frames as
    arrays, summary, timings, errors). Raises InvalidScene without a "dynamics" block or for a
    method the scene cannot run, Error with the CLI's message otherwise; Ctrl-C stops the run
    between steps (KeyboardInterrupt).
    """
    method = _method_name(method)
    d = _core._simulate(scene, method, _to_json(options) if options else "", bool(frames))
    return Simulation(d, method)


class ModeComparison:
    """A method's modes against the fine ones (Modes.coarse); k fine modes, k_c coarse ones.

    - ``frequencies_hz``, ``eigenvalues``: the coarse model's k_c lowest (ascending);
    - ``shapes``: #coarse DOFs x k_c mode shapes (mass-normalized);
    - ``shapes_fine``: #fine DOFs x k_c, the shapes carried to the fine mesh (to_fine @ shapes);
    - ``pairs``: per fine mode, the column of its coarse mode (largest MAC; int32);
    - ``mac``: per fine mode, the MAC of its pair;
    - ``frequency_rel``: per fine mode, |f_coarse - f_fine| / f_fine of its pair
      (summary["errors"]["frequency_rel"]);
    - ``coarse_model``: the CoarseModel.
    """

    def __init__(self, d, errors):
        self.frequencies_hz = d["frequencies_hz"]
        self.eigenvalues = d["eigenvalues"]
        self.shapes = d["shapes"]
        self.shapes_fine = d["shapes_fine"]
        self.pairs = d["pairs"]
        self.mac = d["mac"]
        self.frequency_rel = _np.asarray(errors["frequency_rel"])
        self.coarse_model = d["coarse_model"]


class Modes:
    """The result of modes(): the CLI's `coarsegrain modes` without its files.

    - ``frequencies_hz``, ``eigenvalues`` (ω²): the fine model's k lowest, ascending;
    - ``shapes``: #fine DOFs x k mode shapes, zero at the Dirichlet DOFs, mass-normalized and
      signed so that their largest entry is positive;
    - ``coarse``: a ModeComparison with a method, None without;
    - ``summary``: the CLI's summary.json (but "plots"), same keys and values;
    - ``timings``: the fine model's phases (summary["fine"]["timings"]: the CLI's, but "read"
      and "write" of its files);
    - ``errors``: summary["errors"] with a method ({"frequency_rel"}), None without;
    - ``fine_model``: the FineModel.
    """

    def __init__(self, d, method):
        self.method = method
        self.summary = d["summary"]
        self.fine_model = d["fine_model"]
        self.frequencies_hz = d["fine"]["frequencies_hz"]
        self.eigenvalues = d["fine"]["eigenvalues"]
        self.shapes = d["fine"]["shapes"]
        self.timings = self.summary["fine"]["timings"]
        self.errors = self.summary.get("errors") if method else None
        self.coarse = ModeComparison(d["coarse"], self.errors) \
            if d["coarse"] is not None else None

    def __repr__(self):
        return f"<coarsegrain.Modes {len(self.frequencies_hz)} modes, {self.method or 'fine only'}>"


def modes(scene, method=None, count=10, **options):
    """The ``count`` lowest natural frequencies and modes, fine and (with ``method``) coarse.

    Exactly `coarsegrain modes SCENE [--method METHOD] --count COUNT` without its files:
    K φ = ω² M φ with the Dirichlet DOFs held, M the scene's dynamics.mass (consistent without a
    "dynamics" block); the method's coarse modes are carried to the fine mesh and each fine mode
    is paired with the coarse mode of largest modal assurance criterion (MAC). ``options``
    override the scene's "coarse" block keys as in coarsen().

    Returns a Modes (frequencies, shapes and the MAC pairing as arrays, summary). Raises
    ValueError for a count outside 1..1000 (the CLI's --count range), InvalidScene / Error with
    the CLI's message for a method the scene cannot run.
    """
    method = _method_name(method)
    if isinstance(count, bool) or not isinstance(count, (int, _np.integer)) \
            or not 1 <= count <= 1000:
        raise ValueError(f"modes: count {count!r}: expected an integer in 1..1000")
    d = _core._modes(scene, method, int(count), _to_json(options) if options else "")
    return Modes(d, method)
