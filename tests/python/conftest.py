"""Fixtures of the Python module's tests: the source tree, the CLI built beside the module, and
small scenes. ctest runs them with PYTHONPATH at build/python and VTB_CLI at the vtb binary."""

import os
import pathlib
import shutil
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("VTB_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
SCENES = SOURCE / "experiments" / "scenes"


@pytest.fixture(scope="session")
def source_dir() -> pathlib.Path:
    return SOURCE


@pytest.fixture(scope="session")
def cli() -> str:
    """The vtb CLI of the same build (VTB_CLI), or build/bin/vtb."""
    path = os.environ.get("VTB_CLI") or str(SOURCE / "build" / "bin" / "vtb")
    if not os.access(path, os.X_OK):
        pytest.fail(f"no vtb CLI at {path} (set VTB_CLI)")
    return path


def run_cli(cli: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=600)


@pytest.fixture
def plate_scene(tmp_path) -> pathlib.Path:
    """The structured 451-node plate of plate_step.toml, 0.2 s: a deterministic run of a second."""
    text = (SCENES / "plate_step.toml").read_text().replace("duration = 2.0", "duration = 0.2")
    p = tmp_path / "plate.toml"
    p.write_text(text)
    return p


@pytest.fixture
def plate517_scene() -> pathlib.Path:
    return SCENES / "plate517_step.toml"
