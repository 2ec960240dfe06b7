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
    Interrupted,
    InvalidScene,
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
    "CoarseModel", "CoarsenResult", "Error", "FineModel", "Interrupted", "InvalidScene",
    "MeshReadError", "NewtonFailed", "NotConverged", "NotPositiveDefinite", "Scene",
    "SingularMatrix", "StaticSolution", "build_fine_model", "coarsen", "demo_scene",
    "directional_young", "load_scene", "method_names", "scene_from_dict", "solve_static",
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
    Φ^{1,T} S, applied level by level): ``to_fine @ u`` for a coarse vector u, or for each
    column of a #coarse x k array."""

    def __init__(self, model):
        self._model = model
        self.shape = tuple(model._to_fine_shape)
        self.dtype = _np.dtype(float)

    def __matmul__(self, u):
        u = _np.asarray(u, dtype=float)
        if u.ndim == 1:
            return self._model._apply_to_fine(u)
        if u.ndim == 2:
            return _np.column_stack([self._model._apply_to_fine(u[:, j])
                                     for j in range(u.shape[1])]) \
                if u.shape[1] else _np.zeros((self.shape[0], 0))
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
