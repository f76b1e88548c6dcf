"""References for the tests: a brute-force ray-triangle test in float64 over every pair
(Moeller-Trumbore), and the detection of hits that graze an edge or a vertex, where float
precision decides and an f32 watertight test and an f64 test may legitimately differ."""

import numpy as np

# A hit whose smallest barycentric weight is below this (relative) grazes an edge.
GRAZE = 1e-5


def brute_force(triangles, origins, directions, tmin=0.0, tmax=np.inf, chunk=256):
    """Every (ray, triangle) hit: arrays ``ray``, ``tri``, ``t``, ``u``, ``v``, ``grazing``,
    sorted by ray, then t, then triangle. ``triangles`` (F, 3, 3)."""
    tri = np.asarray(triangles, dtype=np.float64)
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    n = len(o)
    lo = np.broadcast_to(np.asarray(tmin, dtype=np.float64), (n,))
    hi = np.broadcast_to(np.asarray(tmax, dtype=np.float64), (n,))
    v0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    out = {k: [] for k in ("ray", "tri", "t", "u", "v", "grazing")}
    for s in range(0, n, chunk):
        oc, dc = o[s : s + chunk, None, :], d[s : s + chunk, None, :]
        p = np.cross(dc, e2[None])
        det = np.einsum("rfk,fk->rf", p, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            tv = oc - v0[None]
            u = np.einsum("rfk,rfk->rf", tv, p) * inv
            q = np.cross(tv, e1[None])
            v = np.einsum("rfk,rk->rf", q, d[s : s + chunk]) * inv
            t = np.einsum("rfk,fk->rf", q, e2) * inv
        w = 1.0 - u - v
        ok = (det != 0) & (u >= -GRAZE) & (v >= -GRAZE) & (w >= -GRAZE)
        ok &= (t >= lo[s : s + chunk, None] - 1e-9) & (t <= hi[s : s + chunk, None])
        r, f = np.nonzero(ok)
        out["ray"].append(r + s)
        out["tri"].append(f)
        out["t"].append(t[r, f])
        out["u"].append(u[r, f])
        out["v"].append(v[r, f])
        m = np.minimum(np.minimum(u[r, f], v[r, f]), w[r, f])
        out["grazing"].append(np.abs(m) < GRAZE)
    res = {k: np.concatenate(vs) for k, vs in out.items()}
    order = np.lexsort((res["tri"], res["t"], res["ray"]))
    return {k: v[order] for k, v in res.items()}


def grazing_rays(ref, n):
    """(n,) bool: rays with at least one hit that grazes an edge."""
    g = np.zeros(n, dtype=bool)
    g[ref["ray"][ref["grazing"]]] = True
    return g


def per_ray_sets(rays, tris, n):
    """For each ray, the set of triangles it hits."""
    sets = [set() for _ in range(n)]
    for r, f in zip(rays.tolist(), tris.tolist()):
        sets[r].add(f)
    return sets


def random_rays(bounds, n, seed, inside_fraction=0.5):
    """Rays from around a box towards points inside it, and from inside in random directions."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(bounds[0], dtype=np.float64), np.asarray(bounds[1], dtype=np.float64)
    c, ext = (lo + hi) / 2, (hi - lo)
    k = int(n * inside_fraction)
    o_in = c + (rng.random((k, 3)) - 0.5) * ext * 0.8
    d_in = rng.normal(size=(k, 3))
    o_out = c + rng.normal(size=(n - k, 3)) * ext * 1.5
    target = c + (rng.random((n - k, 3)) - 0.5) * ext * 0.9
    o = np.vstack((o_in, o_out)).astype(np.float32)
    d = np.vstack((d_in, target - o_out)).astype(np.float32)
    return o, d
