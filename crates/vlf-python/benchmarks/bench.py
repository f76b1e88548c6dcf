"""The Python package against trimesh (with embreex) and Open3D's RaycastingScene on the same
arrays: the time from a mesh file to the first answered ray, and rays per second for closest-hit,
any-hit and all-hits queries. Prints the Markdown tables of docs/benchmarks/python.md.

    crates/vlf-python/benchmarks/run.sh            # creates the environment, then runs this

Scenes: the bunny (fixtures/meshes/bunny.obj), a random scene of 100K triangles, and every mesh
of at least 500K triangles found under $VLF_SCAN_DIR (default /work/shared/meshes) as .obj/.ply/
.stl. Rays: 1M from around the scene towards points inside its box (so most hit). Threads: the
queries of vlf and Open3D run on $VLF_BENCH_THREADS threads (default 2); trimesh's embreex
intersector has no thread setting.
"""

import glob
import os
import shutil
import sys
import tempfile
import time

import numpy as np

import vlf

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
THREADS = int(os.environ.get("VLF_BENCH_THREADS", "2"))
RAYS = int(os.environ.get("VLF_BENCH_RAYS", "1000000"))
MAX_HITS = 16


def timed(f, repeat=1):
    best = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    return best, out


def rays_for(vertices, n, seed=0):
    rng = np.random.default_rng(seed)
    lo, hi = vertices.min(0), vertices.max(0)
    c, ext = (lo + hi) / 2, hi - lo
    o = c + rng.normal(size=(n, 3)) * ext * 1.5
    d = c + (rng.random((n, 3)) - 0.5) * ext * 0.9 - o
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return o.astype(np.float32), d.astype(np.float32)


def random_scene(path, n=100_000, seed=1):
    rng = np.random.default_rng(seed)
    centers = rng.random((n, 1, 3)) * 2 - 1
    tris = centers + (rng.random((n, 3, 3)) - 0.5) * 0.05
    with open(path, "w") as f:
        for p in tris.reshape(-1, 3):
            f.write(f"v {p[0]:.7f} {p[1]:.7f} {p[2]:.7f}\n")
        for i in range(n):
            f.write(f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}\n")


def scenes(tmp):
    out = [("bunny", os.path.join(ROOT, "fixtures", "meshes", "bunny.obj"))]
    soup = os.path.join(tmp, "random100k.obj")
    random_scene(soup)
    out.append(("random 100K", soup))
    scan_dir = os.environ.get("VLF_SCAN_DIR", "/work/shared/meshes")
    import trimesh

    for p in sorted(glob.glob(os.path.join(scan_dir, "*"))):
        if p.lower().endswith((".obj", ".ply", ".stl")) and "bunny" not in os.path.basename(p):
            try:
                m = trimesh.load(p, force="mesh")
            except Exception:
                continue
            if len(m.faces) >= 500_000:
                out.append((os.path.basename(p), p))
    return out


def main():
    import trimesh

    try:
        from trimesh.ray.ray_pyembree import RayMeshIntersector as Embree
    except ImportError:
        Embree = None
    try:
        import open3d as o3d
    except ImportError:
        o3d = None
    tmp = tempfile.mkdtemp(prefix="vlf-bench-")
    first_rows, rate_rows = [], []
    try:
        for name, path in scenes(tmp):
            mesh = trimesh.load(path, force="mesh", process=False)
            v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces)
            o, d = rays_for(v, RAYS)
            one_o, one_d = o[:1], d[:1]
            field_path = os.path.join(tmp, name.replace(" ", "_") + ".vlf")
            cache = os.path.join(tmp, "cache")
            bake_s, _ = timed(lambda: vlf.bake(path, field_path, cache_dir=cache, threads=THREADS))
            again_s, _ = timed(lambda: vlf.bake(path, field_path + ".2", cache_dir=cache, threads=THREADS))

            def ours_first():
                field = vlf.open(field_path)
                field.closest_hits(one_o, one_d)
                return field

            first = {"vlf (open a baked field)": timed(ours_first, 3)[0]}
            field = vlf.open(field_path)
            if Embree is not None:

                def embree_first():
                    m = trimesh.load(path, force="mesh", process=False)
                    r = Embree(m)
                    r.intersects_first(one_o, one_d)
                    return r

                first["trimesh + embreex (load, build)"] = timed(embree_first, 3)[0]
            if o3d is not None:

                def o3d_first():
                    m = o3d.t.io.read_triangle_mesh(path)
                    s = o3d.t.geometry.RaycastingScene()
                    s.add_triangles(m)
                    s.cast_rays(o3d.core.Tensor(np.hstack((one_o, one_d))))
                    return s

                first["Open3D (read, build)"] = timed(o3d_first, 3)[0]
            first_rows.append((name, len(f), bake_s, again_s, first))

            rates = {}
            rates["vlf"] = {
                "closest": RAYS / timed(lambda: field.closest_hits(o, d, threads=THREADS), 2)[0],
                "any": RAYS / timed(lambda: field.any_hits(o, d, threads=THREADS), 2)[0],
                "all": RAYS / timed(lambda: field.all_hits(o, d, max_hits=MAX_HITS, threads=THREADS), 2)[0],
            }
            if Embree is not None:
                r = Embree(mesh)
                r.intersects_first(one_o, one_d)
                rates["trimesh + embreex"] = {
                    "closest": RAYS / timed(lambda: r.intersects_first(o, d))[0],
                    "any": RAYS / timed(lambda: r.intersects_any(o, d))[0],
                    "all": RAYS / timed(lambda: r.intersects_id(o, d, multiple_hits=True, max_hits=MAX_HITS))[0],
                }
            if o3d is not None:
                s = o3d.t.geometry.RaycastingScene()
                s.add_triangles(o3d.core.Tensor(v.astype(np.float32)), o3d.core.Tensor(f.astype(np.uint32)))
                rt = o3d.core.Tensor(np.hstack((o, d)))
                s.cast_rays(rt[:1])
                rates["Open3D"] = {
                    "closest": RAYS / timed(lambda: s.cast_rays(rt, nthreads=THREADS), 2)[0],
                    "any": RAYS / timed(lambda: s.test_occlusions(rt, nthreads=THREADS), 2)[0],
                    "all": RAYS / timed(lambda: s.list_intersections(rt, nthreads=THREADS), 2)[0],
                }
            rate_rows.append((name, len(f), rates))
            print(f"# done: {name}", file=sys.stderr)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    print("## From a mesh file to the first answered ray\n")
    print("| scene | triangles | vlf bake (once) | vlf bake, cache hit | contestant | to the first ray |")
    print("| --- | ---: | ---: | ---: | --- | ---: |")
    for name, tris, bake_s, again_s, first in first_rows:
        for i, (who, s) in enumerate(first.items()):
            lead = f"| {name} | {tris:,} | {bake_s:.2f} s | {again_s:.3f} s |" if i == 0 else "| | | | |"
            print(f"{lead} {who} | {s * 1000:.1f} ms |")
    print(f"\n## Rays per second ({RAYS:,} rays; all-hits at most {MAX_HITS} per ray)\n")
    print("| scene | contestant | closest hit | any hit | all hits |")
    print("| --- | --- | ---: | ---: | ---: |")
    for name, tris, rates in rate_rows:
        for i, (who, r) in enumerate(rates.items()):
            lead = f"| {name} ({tris:,}) |" if i == 0 else "| |"
            print(f"{lead} {who} | {r['closest'] / 1e6:.2f} M | {r['any'] / 1e6:.2f} M | {r['all'] / 1e6:.2f} M |")


if __name__ == "__main__":
    main()
