"""Fixtures of the Python API tests: the flowire executable and scene files written per test."""
import os
import pathlib
import textwrap

import pytest


@pytest.fixture
def flowire_exe():
    exe = os.environ.get("FLOWIRE_EXE")
    if not exe or not os.path.exists(exe):
        pytest.skip("FLOWIRE_EXE (the flowire executable) is not set: run these tests through ctest")
    return exe


@pytest.fixture
def shared_dir():
    d = pathlib.Path(os.environ.get("FLOWIRE_SHARED_DIR", ""))
    if not (d / "data" / "real").is_dir():
        pytest.skip(f"the shared reference data is not at '{d}' (set FLOWIRE_SHARED_DIR)")
    return d


@pytest.fixture
def write_scene(tmp_path):
    """write_scene(text, name='scene.yaml') -> path of a scene file with that text."""
    def write(text, name="scene.yaml"):
        p = tmp_path / name
        p.write_text(textwrap.dedent(text))
        return p
    return write
