"""The example script: the layered beam built from NumPy arrays is the demo beam."""
import json
import os
import subprocess
import sys

import pytest

import coarsegrain as cg
from conftest import EXAMPLES, run_cli


def test_layered_beam_example(tmp_path):
    script = EXAMPLES / "python_layered_beam" / "layered_beam.py"
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, str(script), "--out", str(tmp_path), "--scale", "0.25"],
                       capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "effective_young.png").stat().st_size > 10000
    result = json.loads((tmp_path / "result.json").read_text())
    # The same beam, conditions, load and coarse mesh as the demo scene, whose fine grid and
    # isotropic materials the script builds as arrays (its own node numbering, one anisotropic
    # material per element): the same model up to round-off, which the direct solves amplify by
    # the condition number of K (~1e6 for the demo's contrast 1e3): relative 1e-7.
    demo = cg.coarsen(cg.scene_from_dict(cg.demo_scene(0.25)), "effective-tensor")
    assert result["errors"].keys() == demo.errors.keys()
    for key, value in demo.errors.items():
        assert result["errors"][key] == pytest.approx(value, rel=1e-7), key
    # The effective moduli it plots are the demo run's tensors' (same coarse grid, same order).
    tensors = demo.coarse_model.element_tensors()
    for axis, d in (("x", [1, 0, 0]), ("y", [0, 1, 0]), ("z", [0, 0, 1])):
        expected = [cg.directional_young(C, d) for C in tensors]
        assert result["effective_young"][axis] == pytest.approx(expected, rel=1e-7), axis


def test_swinging_beam_example(tmp_path):
    script = EXAMPLES / "python_swinging_beam" / "swing.py"
    env = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, str(script), "--small", "--out", str(tmp_path)],
                       capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "swing.png").stat().st_size > 10000
    result = json.loads((tmp_path / "result.json").read_text())
    # The script's figures are those of the command-line tool on the scene it wrote: the same
    # library run, equal to round-off (1e-9, as test_dynamics.py).
    scene = tmp_path / "scene.json"
    run_cli("simulate", scene, "--method", "effective-tensor", "--out", tmp_path / "sim")
    sim = json.loads((tmp_path / "sim" / "summary.json").read_text())
    for key in ("trajectory_l2_rel", "probe_max_rel"):
        assert result["errors"][key] == pytest.approx(sim["errors"][key], rel=1e-9), key
    assert result["fine_linear_errors"]["trajectory_l2_rel"] == pytest.approx(
        sim["fine"]["linear"]["errors"]["trajectory_l2_rel"], rel=1e-9)
    tip_z = [u[2] for u in sim["probes"][0]["u"]]
    assert result["tip_lowest_z"]["coarse"] == pytest.approx(min(tip_z), rel=1e-9)
    run_cli("modes", scene, "--method", "effective-tensor", "--count", 6, "--out",
            tmp_path / "modes")
    modes = json.loads((tmp_path / "modes" / "summary.json").read_text())
    assert result["frequencies_hz"]["fine"] == pytest.approx(modes["fine"]["frequencies_hz"],
                                                             rel=1e-9)
    assert result["mac"] == pytest.approx(modes["mac"], rel=1e-9)
    # the corotated fine tip swings down by a large fraction of the 4-long beam
    assert result["tip_lowest_z"]["fine"] < -0.5
