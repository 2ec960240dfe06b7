"""Shared helpers of the Python tests: the command-line tool and the example scenes.

ctest sets COARSEGRAIN_CLI (the tool of the same build) and COARSEGRAIN_SOURCE (the checkout);
run by hand: PYTHONPATH=build/release/python COARSEGRAIN_CLI=build/release/coarsegrain
/usr/bin/python3 -m pytest python/tests
"""
import json
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("COARSEGRAIN_SOURCE",
                                     pathlib.Path(__file__).resolve().parents[2]))
CLI = os.environ.get("COARSEGRAIN_CLI", str(SOURCE / "build" / "release" / "coarsegrain"))
EXAMPLES = SOURCE / "examples"


def run_cli(*args, check=True):
    """Runs the command-line tool quietly; returns the CompletedProcess (text output)."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([CLI, "--quiet", *map(str, args)], capture_output=True, text=True, env=env)
    if check and p.returncode != 0:
        raise AssertionError(f"{CLI} {' '.join(map(str, args))} failed ({p.returncode}):\n"
                             f"{p.stdout}\n{p.stderr}")
    return p


def cli_error(*args):
    """The message of the tool's one `error: ...` line for a run that fails with exit code 1."""
    p = run_cli(*args, check=False)
    assert p.returncode == 1, (p.returncode, p.stdout, p.stderr)
    lines = [line for line in p.stderr.splitlines() if line.startswith("error: ")]
    assert len(lines) == 1, p.stderr
    return lines[0][len("error: "):]


def write_scene(path, scene):
    path.write_text(json.dumps(scene, indent=1))
    return path


def example_scene(name):
    """The JSON dict of examples/<name>/<name>.json."""
    return json.loads((EXAMPLES / name / f"{name}.json").read_text())


@pytest.fixture
def cli():
    return run_cli
