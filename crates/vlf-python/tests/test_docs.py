"""The examples in the docstrings and the example script run and say what they claim."""

import doctest
import pathlib
import subprocess
import sys

import pytest

import vlf
import vlf.open3d
from conftest import FIXTURES

EXAMPLES = pathlib.Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("module", [vlf, vlf.open3d], ids=["vlf", "vlf.open3d"])
def test_docstring_examples(module):
    result = doctest.testmod(module)
    assert result.attempted > 0 and result.failed == 0


def test_trimesh_docstring_example():
    pytest.importorskip("trimesh")
    import vlf.trimesh

    result = doctest.testmod(vlf.trimesh)
    assert result.attempted > 0 and result.failed == 0


def test_example_script(tmp_path):
    out = tmp_path / "depth.pgm"
    run = subprocess.run(
        [sys.executable, str(EXAMPLES / "depth_image.py"), str(FIXTURES / "bunny.obj"), str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    assert out.read_bytes().startswith(b"P5 320 240 255\n") and len(out.read_bytes()) == 15 + 320 * 240
    assert "pixels see the mesh" in run.stdout and "meets surfaces at t = [" in run.stdout
