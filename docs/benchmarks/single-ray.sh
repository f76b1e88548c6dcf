#!/usr/bin/env bash
# Instructions per ray of the single-ray queries (`Field::closest_hit`, `Field::any_hit`), the
# calls the peers benchmark times, counted by callgrind: the firm measure of a change to the
# query path, where the peers' timings vary by up to a third between two runs of the same field.
#
#   bash docs/benchmarks/single-ray.sh
#
# Scenes: the paper's random 100K scene (fixed size, seed 1) and, if the peers benchmark has
# fetched it (target/peers/dragon.obj), the Stanford dragon, both baked at the default parameters.
# Rays: the middle 64 rows of 512² primary views from outside and inside (`vlf-bake rays`), 20,000
# incoherent rays (origins in the scene's box, random directions, seed 1), and shadow rays (any
# hit) from the inside view's hits towards the peers' light, `centre + (0.3, 3, 0.2)·R`. Each
# count is a run over the rays minus a run over one ray, divided by the rays. Needs valgrind
# (installed when missing). Writes its files to target/single-ray/; takes about five minutes.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
W=target/single-ray
mkdir -p "$W"
if ! command -v valgrind >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind
fi
cargo build --release -q --bin vlf-bake
cargo build --release -q -p vlf-runtime --example single_ray
B=target/release/vlf-bake
S=target/release/examples/single_ray

[ -f "$W/r100k.obj" ] || $B gen random --count 100000 --size 0.05 --seed 1 -o "$W/r100k.obj" -q
scenes="r100k"
if [ -f target/peers/dragon.obj ]; then
  cp -u target/peers/dragon.obj "$W/dragon.obj"
  scenes="$scenes dragon"
fi

count() { # FIELD RAYS [--any]: instructions per ray
  local n=$(( $(stat -c %s "$2") / 32 ))
  local all one
  all=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null $S "$1" "$2" --count "$n" --rounds 1 ${3:-} 2>&1 | sed -nE 's/.*Collected : ([0-9]+).*/\1/p')
  one=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null $S "$1" "$2" --count 1 --rounds 1 ${3:-} 2>&1 | sed -nE 's/.*Collected : ([0-9]+).*/\1/p')
  echo $(( (all - one) / (n - 1) ))
}

echo "| scene | outside | inside | incoherent | shadow (from inside hits) |"
echo "| --- | ---: | ---: | ---: | ---: |"
for s in $scenes; do
  # Baked every run: a field left by an older baker would measure that baker.
  $B bake "$W/$s.obj" -o "$W/$s.vlf" -q
  for view in outside inside; do
    $B rays "$W/$s.vlf" --view $view --width 512 --height 512 -o "$W/$s-$view-all.bin" -q
  done
  $B trace "$W/$s.vlf" --rays "$W/$s-inside-all.bin" -o "$W/$s-inside-hits.bin" -q
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
rng = random.Random(1)
out = []
for _ in range(20_000):
    o = [rng.uniform(lo[k], hi[k]) for k in range(3)]
    z = rng.uniform(-1.0, 1.0)
    a = rng.uniform(0.0, 2.0 * math.pi)
    q = math.sqrt(1.0 - z * z)
    out.append(struct.pack("<8f", *o, 0.0, q * math.cos(a), q * math.sin(a), z, float("inf")))
open(f"{w}/{s}-incoherent.bin", "wb").write(b"".join(out))
# Shadow rays, as the peers make them: from each hit of the inside view towards the light, on
# [1e-4, 1 - 1e-4] of the segment.
light = [c[0] + 0.3 * r, c[1] + 3.0 * r, c[2] + 0.2 * r]
rays = open(f"{w}/{s}-inside-all.bin", "rb").read()
hits = open(f"{w}/{s}-inside-hits.bin", "rb").read()
out = []
for i in range(0, len(rays) // 32, 8):
    ray = struct.unpack_from("<8f", rays, 32 * i)
    t = struct.unpack_from("<f", hits, 16 * i)[0]
    if math.isinf(t):
        continue
    p = [ray[k] + t * ray[4 + k] for k in range(3)]
    p = [struct.unpack("<f", struct.pack("<f", v))[0] for v in p]
    out.append(struct.pack("<8f", *p, 1e-4, *[light[k] - p[k] for k in range(3)], 1.0 - 1e-4))
open(f"{w}/{s}-shadow.bin", "wb").write(b"".join(out))
PY
  echo "| $s | $(count "$W/$s.vlf" "$W/$s-outside.bin") | $(count "$W/$s.vlf" "$W/$s-inside.bin") | $(count "$W/$s.vlf" "$W/$s-incoherent.bin") | $(count "$W/$s.vlf" "$W/$s-shadow.bin" --any) |"
done
