import os
import pathlib

import numpy as np
import pytest

import vlf

ROOT = pathlib.Path(__file__).resolve().parents[3]
FIXTURES = ROOT / "fixtures" / "meshes"

# Small bakes: the tests are about answers, not speed.
SMALL = dict(directions=33, tiles=16, no_cache=True)


def load_obj(path):
    """Vertices and triangular faces of a plain OBJ file (v and f lines)."""
    vs, fs = [], []
    for line in open(path):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            vs.append([float(x) for x in parts[1:4]])
        elif parts[0] == "f":
            idx = [int(p.split("/")[0]) - 1 for p in parts[1:]]
            for k in range(1, len(idx) - 1):
                fs.append([idx[0], idx[k], idx[k + 1]])
    return np.array(vs), np.array(fs, dtype=np.int64)


def random_soup(n, seed, size=0.15):
    rng = np.random.default_rng(seed)
    centers = rng.random((n, 1, 3)) * 2 - 1
    tris = centers + (rng.random((n, 3, 3)) - 0.5) * size
    return tris.reshape(-1, 3), np.arange(3 * n).reshape(n, 3)


@pytest.fixture(scope="session")
def bunny():
    v, f = load_obj(FIXTURES / "bunny.obj")
    return v, f, vlf.bake_arrays(v, f, **SMALL)


@pytest.fixture(scope="session")
def soup():
    v, f = random_soup(1500, 3)
    return v, f, vlf.bake_arrays(v, f, **SMALL)


@pytest.fixture(scope="session")
def icosphere():
    trimesh = pytest.importorskip("trimesh")
    return trimesh.creation.icosphere(subdivisions=3)


@pytest.fixture
def cache_dir(tmp_path):
    return tmp_path / "cache"


@pytest.fixture(autouse=True, scope="session")
def _no_user_cache(tmp_path_factory):
    # The shims cache by default: keep the tests' bakes out of the user's cache.
    os.environ["VLF_CACHE_DIR"] = str(tmp_path_factory.mktemp("vlf-cache"))
