#!/usr/bin/env bash
# The ray sets of the single-ray measurements for one scene, and its field at the default
# parameters: what `single-ray.sh`, `single-ray-time.sh` and `single-ray-fields.sh` read.
#
#   bash docs/benchmarks/single-ray-sets.sh SCENE [MESH]
#
# Bakes target/single-ray/SCENE.obj (copied from MESH if given) to SCENE.vlf at the default
# parameters, and writes next to it: SCENE-outside-all.bin and SCENE-inside-all.bin (512² primary
# views, `vlf-bake rays`) and their middle 64 rows (SCENE-outside.bin, SCENE-inside.bin); 20,000
# incoherent rays (origins in the scene's box, random directions, seed 1) and 262,144 more
# (SCENE-incoherent-big.bin, seed 2, as many as the peers trace); and shadow rays (any
# hit) from every eighth inside hit towards the peers' light, `centre + (0.3, 3, 0.2)·R`; and
# ambient-occlusion (`-ao-shadow`) and bounce rays from every fourth inside hit; and the whole
# outside view split by what each ray does (SCENE-outside-away/-box-miss/-hit.bin, with warm sets
# of the last two), which `against-embree.sh` reads. Two warm sets,
# whose field lines stay cached from one pass to the next, tell a query's work from its waiting
# on memory: SCENE-incoherent-warm.bin (the first 500 incoherent rays, 40 times) and
# SCENE-outside-warm.bin (the outside view's middle row, 512 rays, 40 times). For the
# random scenes of the peers benchmark, make the mesh first, e.g.
# `vlf-bake gen random --count 100000 --size 0.0232 --seed 1 -o target/single-ray/r100kd.obj`.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
[ $# -ge 1 ] || { sed -n 2,20p "$0" >&2; exit 2; }
s=$1
W=target/single-ray
mkdir -p "$W"
[ $# -ge 2 ] && cp -u "$2" "$W/$s.obj"
[ -f "$W/$s.obj" ] || { echo "no $W/$s.obj: pass the mesh as the second argument" >&2; exit 1; }
cargo build --release -q --bin vlf-bake
B=target/release/vlf-bake
# Baked every run: a field left by an older baker would measure that baker.
$B bake "$W/$s.obj" -o "$W/$s.vlf" -q
for view in outside inside; do
  $B rays "$W/$s.vlf" --view $view --width 512 --height 512 -o "$W/$s-$view-all.bin" -q
done
for view in outside inside; do
  $B trace "$W/$s.vlf" --rays "$W/$s-$view-all.bin" -o "$W/$s-$view-hits.bin" -q
done
$B dump "$W/$s.vlf" --json > "$W/$s.json"
python3 - "$W" "$s" <<'PY'
import json, math, random, struct, sys
w, s = sys.argv[1], sys.argv[2]
info = json.load(open(f"{w}/{s}.json"))
c, r = info["center"], info["radius"]
lo = [c[k] + info["aabb_min"][k] for k in range(3)]
hi = [c[k] + info["aabb_max"][k] for k in range(3)]
for view in ("outside", "inside"):
    data = open(f"{w}/{s}-{view}-all.bin", "rb").read()
    open(f"{w}/{s}-{view}.bin", "wb").write(data[32 * 512 * 224 : 32 * 512 * 288])


def incoherent(count, seed):
    """`count` incoherent rays: origins uniform in the scene's box, directions uniform."""
    rng = random.Random(seed)
    out = []
    for _ in range(count):
        o = [rng.uniform(lo[k], hi[k]) for k in range(3)]
        z = rng.uniform(-1.0, 1.0)
        a = rng.uniform(0.0, 2.0 * math.pi)
        q = math.sqrt(1.0 - z * z)
        out.append(struct.pack("<8f", *o, 0.0, q * math.cos(a), q * math.sin(a), z, float("inf")))
    return out


out = incoherent(20_000, 1)
open(f"{w}/{s}-incoherent.bin", "wb").write(b"".join(out))
open(f"{w}/{s}-incoherent-warm.bin", "wb").write(b"".join(out[:500]) * 40)
# As many as the peers trace (262,144), for `fields-against-embree.sh`.
open(f"{w}/{s}-incoherent-big.bin", "wb").write(b"".join(incoherent(262_144, 2)))
data = open(f"{w}/{s}-outside-all.bin", "rb").read()
open(f"{w}/{s}-outside-warm.bin", "wb").write(data[32 * 512 * 256 : 32 * 512 * 257] * 40)
# Shadow rays, as the peers make them: from each hit of the inside view towards the light, on
# [1e-4, 1 - 1e-4] of the segment.
light = [c[0] + 0.3 * r, c[1] + 3.0 * r, c[2] + 0.2 * r]
rays = open(f"{w}/{s}-inside-all.bin", "rb").read()
hits = open(f"{w}/{s}-inside-hits.bin", "rb").read()


def inside_hits(step):
    """Every `step`-th ray of the inside view that hits: the ray, and its hit point in f32."""
    for i in range(0, len(rays) // 32, step):
        ray = struct.unpack_from("<8f", rays, 32 * i)
        t = struct.unpack_from("<f", hits, 16 * i)[0]
        if not math.isinf(t):
            p = [ray[k] + t * ray[4 + k] for k in range(3)]
            yield ray, [struct.unpack("<f", struct.pack("<f", v))[0] for v in p]


out = []
for ray, p in inside_hits(8):
    out.append(struct.pack("<8f", *p, 1e-4, *[light[k] - p[k] for k in range(3)], 1.0 - 1e-4))
open(f"{w}/{s}-shadow.bin", "wb").write(b"".join(out))
# Rays leaving every fourth inside hit in a random direction on the camera's side (seed 3):
# ambient occlusion (any hit within 0.3 R) and bounces (closest hit, unbounded), what
# `examples/batch_choice.rs` times through the batch queries.
rng = random.Random(3)
ao, bounce = [], []
for ray, p in inside_hits(4):
    z = rng.uniform(-1.0, 1.0)
    a = rng.uniform(0.0, 2.0 * math.pi)
    q = math.sqrt(1.0 - z * z)
    d = [q * math.cos(a), q * math.sin(a), z]
    if sum(d[k] * ray[4 + k] for k in range(3)) > 0:
        d = [-v for v in d]
    ao.append(struct.pack("<8f", *p, 1e-4 * r, *d, 0.3 * r))
    bounce.append(struct.pack("<8f", *p, 1e-4 * r, *d, float("inf")))
open(f"{w}/{s}-ao-shadow.bin", "wb").write(b"".join(ao))
open(f"{w}/{s}-bounce.bin", "wb").write(b"".join(bounce))
# The whole outside view by what each ray does, for `against-embree.sh`: misses the scene's box
# grown by the margin ("away"), enters it and misses the scene ("box-miss"), or hits ("hit");
# and a warm set of each of the last two (300 rays from the middle of the class, 100 times over).
m = info["margin"]
view = open(f"{w}/{s}-outside-all.bin", "rb").read()
view_hits = open(f"{w}/{s}-outside-hits.bin", "rb").read()


def enters_box(r):
    t0, t1 = r[3], r[7]
    for k in range(3):
        o, d = r[k], r[4 + k]
        if d == 0.0:
            if not lo[k] - m <= o <= hi[k] + m:
                return False
            continue
        ta, tb = (lo[k] - m - o) / d, (hi[k] + m - o) / d
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    return t0 <= t1


classes = {"away": [], "box-miss": [], "hit": []}
for i in range(len(view) // 32):
    record = view[32 * i : 32 * i + 32]
    if not math.isinf(struct.unpack_from("<f", view_hits, 16 * i)[0]):
        classes["hit"].append(record)
    elif enters_box(struct.unpack("<8f", record)):
        classes["box-miss"].append(record)
    else:
        classes["away"].append(record)
for name, records in classes.items():
    open(f"{w}/{s}-outside-{name}.bin", "wb").write(b"".join(records))
    if name != "away" and records:
        middle = len(records) // 2
        open(f"{w}/{s}-outside-{name}-warm.bin", "wb").write(b"".join(records[middle : middle + 300]) * 100)
PY
