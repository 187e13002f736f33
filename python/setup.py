"""Builds the wheel of the package occgt from python/occgt and the extension module that the
CMake project built (target _occgt, in $OCCGT_BUILD_DIR/python/occgt, OCCGT_BUILD_DIR
defaulting to the project's build/). Nothing is compiled here and nothing is downloaded:

    /usr/bin/python3 -m venv --system-site-packages VENV
    VENV/bin/pip install --no-build-isolation ./python

(docs/PYTHON.md). setuptools' scratch files go to the build folder, not to the source tree.
"""
import importlib.machinery
import os
import re
import shutil

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

HERE = os.path.dirname(os.path.abspath(__file__))
BUILD_DIR = os.path.abspath(os.environ.get("OCCGT_BUILD_DIR", os.path.join(HERE, "..", "build")))
MODULE_DIR = os.path.join(BUILD_DIR, "python", "occgt")


def project_version() -> str:
    """VERSION of project(occgt ...) in the top-level CMakeLists.txt."""
    with open(os.path.join(HERE, "..", "CMakeLists.txt")) as f:
        match = re.search(r"project\(occgt\s+VERSION\s+([0-9.]+)", f.read())
    if not match:
        raise SystemExit("occgt setup.py: no 'project(occgt VERSION x.y.z)' in ../CMakeLists.txt")
    return match.group(1)


def built_module() -> str:
    """Path of _occgt<suffix> for this interpreter's extension suffix."""
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]  # .cpython-311-x86_64-linux-gnu.so
    path = os.path.join(MODULE_DIR, "_occgt" + suffix)
    if not os.path.isfile(path):
        others = sorted(os.listdir(MODULE_DIR)) if os.path.isdir(MODULE_DIR) else []
        raise SystemExit(
            f"occgt setup.py: the extension module {path} is missing (found: {others or 'nothing'}). "
            "Build it first (scripts/setup.sh, or cmake --build build -j1 --target _occgt) with the "
            "same Python (/usr/bin/python3), or point OCCGT_BUILD_DIR at the build folder.")
    return path


class BuildPyWithModule(build_py):
    """build_py, plus the module built by CMake copied next to the package's files."""

    def run(self) -> None:
        super().run()
        target = os.path.join(self.build_lib, "occgt")
        os.makedirs(target, exist_ok=True)
        shutil.copy2(built_module(), target)


class BinaryDistribution(Distribution):
    """A platform wheel (cpXY-cpXY-linux_x86_64): the package contains a compiled module."""

    def has_ext_modules(self) -> bool:
        return True


built_module()  # fail early, with the message above, before setuptools writes anything
scratch = os.path.join(BUILD_DIR, "python", "setuptools")
os.makedirs(scratch, exist_ok=True)
setup(
    version=project_version(),
    cmdclass={"build_py": BuildPyWithModule},
    distclass=BinaryDistribution,
    options={"build": {"build_base": os.path.join(scratch, "build")},
             "egg_info": {"egg_base": scratch}},
)
