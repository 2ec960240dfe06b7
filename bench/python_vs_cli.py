#!/usr/bin/python3
"""Wall-clock overhead of the Python module's coarsen() against `coarsegrain coarsen`.

Both run one method on the same scene (default: the demo beam, `coarsegrain demo`'s scene at
--scale 1: 48 x 12 x 12 hexes, 24,843 DOFs, effective tensors), --repeat times each (default 5),
alternating, and the best time of each is kept:

- cli:      the whole `coarsegrain --quiet coarsen SCENE --method M --out DIR` process, which
            also writes solution_fine.vtu, solution_coarse.vtu, the method's files and
            summary.json, and repeats a coarse solve shorter than 0.1 s up to 5 times to time it;
- cli work: its summary.json phases that the Python call also runs: read, assemble, factorize
            and solve of the fine model, the coarse build and one coarse factorize and solve
            (the fastest of the repeats, a lower bound of the first);
- c++ calls: the library calls behind the Python call, made by a C++ program
            (bench/bench_coarsen_call.cpp, the better of two calls in one process): load_scene,
            validate_method, build_fine_model, coarsen::solve_fine, coarsen::run_method;
- python:   coarsegrain.load_scene(SCENE) and coarsegrain.coarsen(scene, M) in this process;
- python process: a fresh /usr/bin/python3 that imports coarsegrain, loads and coarsens.

The overhead of the binding is python / c++ calls - 1 (what the call costs beyond the same
library calls); python / cli and python process / cli are the end-to-end ratios (the CLI also
writes its files; "cli work" leaves out what it does outside its phases, e.g. the comparison).
Both get the same threads (OMP_NUM_THREADS if set, else all cores) and OPENBLAS_NUM_THREADS=1.

Usage:
    PYTHONPATH=build/release/python /usr/bin/python3 bench/python_vs_cli.py \
        [--cli build/release/coarsegrain] [--bench build/release/bench/bench_coarsen_call]
        [--method effective-tensor] [--scale 1] [--repeat 5]
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

os.environ["OPENBLAS_NUM_THREADS"] = "1"
import coarsegrain as cg  # noqa: E402  (after the environment it reads)


def main():
    root = pathlib.Path(__file__).resolve().parents[1]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cli", default=str(root / "build" / "release" / "coarsegrain"))
    parser.add_argument("--bench", default=str(root / "build" / "release" / "bench" /
                                               "bench_coarsen_call"))
    parser.add_argument("--method", default="effective-tensor")
    parser.add_argument("--scale", type=float, default=1.0)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        scene_path = tmp / "scene.json"
        scene_path.write_text(json.dumps(cg.demo_scene(args.scale)))
        child = ("import time, sys; t = time.perf_counter(); import coarsegrain as cg; "
                 f"r = cg.coarsen(cg.load_scene({str(scene_path)!r}), {args.method!r}); "
                 "print(r.errors['energy_rel'])")
        cli, work, calls, python, process = [], [], [], [], []
        errors = {}
        for _ in range(args.repeat):
            t = time.perf_counter()
            subprocess.run([args.cli, "--quiet", "coarsen", str(scene_path), "--method",
                            args.method, "--out", str(tmp / "out")], check=True,
                           stdout=subprocess.DEVNULL)
            cli.append(time.perf_counter() - t)
            summary = json.loads((tmp / "out" / "summary.json").read_text())
            fine, coarse = summary["fine"]["timings"], summary["coarse"]["timings"]
            work.append(sum(fine.get(p, 0) for p in ("read", "assemble", "factorize", "solve"))
                        + coarse["build"] + coarse["factorize"] + coarse["solve"])
            errors["cli"] = summary["errors"]

            # twice per process: the second call runs warm, as the Python calls after the first
            out = subprocess.run([args.bench, str(scene_path), args.method, "2"], check=True,
                                 capture_output=True, text=True).stdout.split()
            calls.append(float(out[1]))

            t = time.perf_counter()
            result = cg.coarsen(cg.load_scene(str(scene_path)), args.method)
            python.append(time.perf_counter() - t)
            errors["python"] = result.errors

            t = time.perf_counter()
            subprocess.run([sys.executable, "-c", child], check=True, stdout=subprocess.DEVNULL)
            process.append(time.perf_counter() - t)

    assert errors["cli"].keys() == errors["python"].keys()
    worst = max(abs(errors["python"][k] - v) / max(abs(v), 1e-300)
                for k, v in errors["cli"].items())
    best = {"cli": min(cli), "cli work": min(work), "c++ calls": min(calls), "python": min(python),
            "python process": min(process)}
    print(f"{args.method} on the demo beam at scale {args.scale} "
          f"({result.fine_model.num_dofs} fine DOFs, {result.coarse_model.num_dofs} coarse), "
          f"best of {args.repeat}, threads {summary['threads']}:")
    for name, seconds in best.items():
        print(f"  {name:15s} {seconds:8.3f} s")
    print(f"  binding overhead   python / c++ calls - 1 = "
          f"{best['python'] / best['c++ calls'] - 1:+.1%}")
    print(f"  end to end         python / cli - 1 = {best['python'] / best['cli'] - 1:+.1%}, "
          f"python process / cli - 1 = {best['python process'] / best['cli'] - 1:+.1%}")
    print(f"  largest relative difference of the errors: {worst:.2e}")


if __name__ == "__main__":
    main()
