# Shared fixtures of the Python module's tests (run by ctest as python_module, python/CMakeLists.txt):
# the build and source trees, and the characterize program whose JSON the module must reproduce.
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("METRO_SOURCE_DIR", pathlib.Path(__file__).parents[2])).resolve()
BINARY_DIR = pathlib.Path(os.environ.get("METRO_BINARY_DIR", SOURCE_DIR / "build")).resolve()
CHARACTERIZE = BINARY_DIR / "apps" / "characterize" / "characterize"
DATASETS = SOURCE_DIR / "datasets"


def run_cli(*args, cwd=None):
    """Runs characterize; returns (exit code, stdout bytes, stderr text)."""
    done = subprocess.run([str(CHARACTERIZE), *map(str, args)], capture_output=True, cwd=cwd)
    return done.returncode, done.stdout, done.stderr.decode()


@pytest.fixture(scope="session")
def cli():
    if not CHARACTERIZE.exists():
        pytest.fail(f"{CHARACTERIZE} is not built (cmake --build build --target characterize)")
    return run_cli
