"""Builds the extension coarsegrain._core with the project's CMake (pyproject.toml has the
metadata and says how to install). CMake builds only the module and the library it links (no
tests, benchmarks or install rules) for the running interpreter, in Release, with
CMAKE_BUILD_PARALLEL_LEVEL jobs (default 2), into build/pip of the checkout, and with ccache if
installed: build/pip lies as deep as build/release, so the compiler sees the same relative paths
and ccache reuses the objects of `scripts/build.sh release`."""
import os
import pathlib
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = ROOT / "build" / "pip"
        build.mkdir(parents=True, exist_ok=True)
        flags = [
            "-DCMAKE_BUILD_TYPE=Release",
            "-DCOARSEGRAIN_BUILD_PYTHON=ON",
            "-DCOARSEGRAIN_BUILD_TESTS=OFF",
            "-DCOARSEGRAIN_BUILD_BENCH=OFF",
            "-DCOARSEGRAIN_INSTALL=OFF",
            f"-DPython_EXECUTABLE={sys.executable}",
        ]
        env = dict(os.environ)
        if shutil.which("ccache"):
            flags.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
            env.setdefault("CCACHE_BASEDIR", str(ROOT))
        if shutil.which("ninja"):
            flags += ["-G", "Ninja"]
        env.setdefault("CMAKE_BUILD_PARALLEL_LEVEL", "2")
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build), *flags], check=True, env=env)
        subprocess.run(["cmake", "--build", str(build), "--target", "coarsegrain_python"],
                       check=True, env=env)
        built = next((build / "python" / "coarsegrain").glob("_core*.so"))
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, target)


setup(ext_modules=[Extension("coarsegrain._core", sources=[])], cmdclass={"build_ext": CMakeBuild})
