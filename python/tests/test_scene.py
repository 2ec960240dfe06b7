"""Scenes: from files, from dicts, from NumPy arrays; bad input raises the CLI's message."""
import json

import numpy as np
import pytest

import coarsegrain as cg
from conftest import EXAMPLES, cli_error, example_scene, write_scene

SQUARE = EXAMPLES / "bimaterial_square" / "bimaterial_square.json"


def test_load_scene_reads_the_file():
    scene = cg.load_scene(str(SQUARE))
    assert scene.source == str(SQUARE)
    assert scene.dimension == 2 and scene.element == "quad"
    # a 32 x 32 quad grid on the unit square
    assert scene.num_nodes == 33 * 33 and scene.num_elements == 32 * 32
    assert scene.nodes.shape == (33 * 33, 2) and scene.elements.shape == (32 * 32, 4)
    assert scene.nodes.min() == 0 and scene.nodes.max() == 1
    # checkerboard of 4 x 4 cells per square: ids 1 and 2 on half the elements each
    assert sorted(np.unique(scene.material_ids)) == [1, 2]
    assert (scene.material_ids == 1).sum() == 512
    assert scene.configured_methods() == ["effective-tensor", "naive", "voigt", "reuss",
                                          "mra-linear", "mra-dirac"]
    assert scene.coarse_options == example_scene("bimaterial_square")["coarse"]
    assert scene.kinematics == "linear" and scene.warp == "none"
    assert scene.base_dir == str(SQUARE.parent)


def test_arrays_are_read_only_views():
    scene = cg.load_scene(str(SQUARE))
    a, b = scene.nodes, scene.nodes
    assert np.shares_memory(a, b)  # two reads, one storage: no copy
    assert not a.flags.writeable
    with pytest.raises(ValueError):
        a[0, 0] = 1.0


def test_dict_equals_file():
    from_file = cg.build_fine_model(cg.load_scene(str(SQUARE)))
    from_dict = cg.build_fine_model(cg.scene_from_dict(example_scene("bimaterial_square")))
    assert abs(from_file.stiffness - from_dict.stiffness).max() == 0
    np.testing.assert_array_equal(from_file.load, from_dict.load)


def grid_arrays(scene):
    return {"nodes": np.array(scene.nodes), "elements": np.array(scene.elements)}


def test_mesh_arrays_equal_the_grid():
    """The square's grid given as NumPy arrays with its material ids: the same fine model. The
    grid's elements are congruent and share one element matrix; an array mesh computes each
    element's: round-off, relative 1e-12 of the largest entry."""
    scene = cg.load_scene(str(SQUARE))
    d = example_scene("bimaterial_square")
    del d["material_field"]
    d["mesh"] = dict(grid_arrays(scene), material_ids=np.array(scene.material_ids))
    arrays = cg.scene_from_dict(d)
    assert arrays.element == "quad"  # from 2D nodes and 4 nodes per element
    K, Ka = cg.build_fine_model(scene).stiffness, cg.build_fine_model(arrays).stiffness
    assert abs(K - Ka).max() <= 1e-12 * abs(K).max()


@pytest.mark.parametrize("notation", ["C_mandel", "C_voigt"])
def test_per_element_tensors(notation):
    """One tensor per element (the fine model's own, as arrays) gives the same stiffness; in
    Voigt notation too. Anisotropic materials from isotropic tensors: round-off."""
    scene = cg.load_scene(str(SQUARE))
    fine = cg.build_fine_model(scene)
    d = example_scene("bimaterial_square")
    for key in ("material_field", "materials"):
        del d[key]
    d["mesh"] = dict(grid_arrays(scene), element="quad", density=fine.element_densities())
    d["mesh"][notation] = fine.element_tensors("mandel" if notation == "C_mandel" else "voigt")
    per_element = cg.build_fine_model(cg.scene_from_dict(d))
    K = fine.stiffness
    assert abs(K - per_element.stiffness).max() <= 1e-12 * abs(K).max()
    np.testing.assert_allclose(per_element.element_tensors(), fine.element_tensors(), rtol=1e-13,
                               atol=1e-13 * abs(fine.element_tensors()).max())
    # one density for all elements
    d["mesh"]["density"] = 1.0
    assert cg.scene_from_dict(d).num_elements == scene.num_elements


def test_coarse_mesh_arrays():
    """coarse.mesh as arrays: the same coarse model as the grid it copies."""
    d = example_scene("bimaterial_square")
    grid_scene = cg.scene_from_dict(d)
    coarse_of_grid = cg.coarsen(grid_scene, "naive").coarse_model
    d["coarse"]["mesh"] = {"nodes": np.array(coarse_of_grid.nodes),
                           "elements": np.array(coarse_of_grid.elements)}
    arrays = cg.coarsen(cg.scene_from_dict(d), "naive").coarse_model
    assert abs(arrays.stiffness - coarse_of_grid.stiffness).max() <= \
        1e-12 * abs(coarse_of_grid.stiffness).max()


def test_bad_scene_raises_the_cli_message(tmp_path):
    d = example_scene("bimaterial_square")
    d["materials"]["2"]["nu"] = 0.5
    path = write_scene(tmp_path / "bad.json", d)
    expected = cli_error("solve", path, "--out", tmp_path / "out")
    assert "materials.2" in expected
    with pytest.raises(cg.InvalidScene) as e:
        cg.load_scene(str(path))
    assert str(e.value) == expected
    with pytest.raises(cg.InvalidScene) as e:
        cg.scene_from_dict(d, source=str(path))
    assert str(e.value) == expected


def test_missing_file_raises_the_cli_message(tmp_path):
    missing = tmp_path / "missing.json"
    expected = cli_error("solve", missing, "--out", tmp_path / "out")
    with pytest.raises(cg.InvalidScene) as e:
        cg.load_scene(str(missing))
    assert str(e.value) == expected


def test_exception_hierarchy():
    assert issubclass(cg.InvalidScene, cg.Error) and issubclass(cg.Error, RuntimeError)
    for e in (cg.MeshReadError, cg.NotPositiveDefinite, cg.NotConverged, cg.NewtonFailed,
              cg.SingularMatrix):
        assert issubclass(e, cg.Error)
    assert issubclass(cg.Interrupted, KeyboardInterrupt)


def test_bad_arrays():
    scene = cg.load_scene(str(SQUARE))
    d = example_scene("bimaterial_square")
    del d["material_field"]
    mesh = grid_arrays(scene)
    mesh["elements"] = mesh["elements"].copy()
    mesh["elements"][7, 2] = scene.num_nodes
    with pytest.raises(cg.InvalidScene, match=r"mesh.elements\[7\]\[2\] = 1089"):
        cg.scene_from_dict(dict(d, mesh=mesh))
    with pytest.raises(cg.InvalidScene, match="mesh.nodes: expected a #nodes x 3 array"):
        cg.scene_from_dict(dict(d, mesh=dict(grid_arrays(scene), element="hex")))
    with pytest.raises(cg.InvalidScene, match="5 nodes per element"):
        cg.scene_from_dict(dict(d, mesh={"nodes": scene.nodes,
                                         "elements": np.zeros((2, 5), int)}))
    inverted = grid_arrays(scene)
    inverted["elements"] = inverted["elements"][:, ::-1].copy()
    with pytest.raises(cg.InvalidScene, match="<dict>: mesh"):
        cg.scene_from_dict(dict(d, mesh=inverted))
    with pytest.raises(cg.InvalidScene, match="unknown key"):
        cg.scene_from_dict(dict(d, mesh=dict(grid_arrays(scene), colour=1)))
    # a tensor that is not positive definite names the element
    fine = cg.build_fine_model(scene)
    C = fine.element_tensors()
    C[3] = -C[3]
    d2 = {k: v for k, v in d.items() if k != "materials"}
    with pytest.raises(cg.InvalidScene, match=r"mesh.C_mandel\[3\]"):
        cg.scene_from_dict(dict(d2, mesh=dict(grid_arrays(scene), C_mandel=C, density=1.0)))
    with pytest.raises(cg.InvalidScene, match="need \"density\""):
        cg.scene_from_dict(dict(d2, mesh=dict(grid_arrays(scene), C_mandel=C)))
    with pytest.raises(cg.InvalidScene, match="expected a dict"):
        cg.scene_from_dict([1, 2])
    with pytest.raises(TypeError, match="not a JSON value"):
        cg.scene_from_dict(dict(d, description=object()))


def test_demo_scene_is_the_cli_demo():
    d = cg.demo_scene(0.25)
    assert d["mesh"]["grid"]["cells"] == [16, 4, 4]
    scene = cg.scene_from_dict(d)
    assert scene.num_elements == 16 * 4 * 4
    assert json.loads(json.dumps(d)) == d  # plain JSON values
