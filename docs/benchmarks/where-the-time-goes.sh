#!/usr/bin/env bash
# Where a field query's time goes (issue 12's breakdown): on the paper's 100K random scene baked at
# the default parameters, for primary rays from outside and inside and for incoherent rays,
#   - ns/ray as traced (`vlf-bake trace --threads 1`, median of 5),
#   - ns/ray with every byte the rays touch already in cache: 2,000 rays spread over the set,
#     traced 50 times over in one file (the first pass warms the caches),
#   - instructions, L1 data misses and last-level misses per ray under cachegrind, with a 16 MiB
#     last-level cache (larger than this machine's 1 MiB L2, so it counts the field's own working
#     set, not the simulated machine's), the cost of starting the process and opening the field
#     subtracted (a run on one ray).
# The difference of the first two is what memory costs; the misses say where.
#
#   bash docs/benchmarks/where-the-time-goes.sh
#
# Needs valgrind (`apt-get install valgrind`, installed when missing). Writes its files to
# target/where/ and the table to standard output; takes about ten minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
W=target/where
mkdir -p "$W"
if ! command -v valgrind >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind
fi
cargo build --release -q --bin vlf-bake
B=target/release/vlf-bake

[ -f "$W/r100k.obj" ] || $B gen random --count 100000 --size 0.05 --seed 1 -o "$W/r100k.obj" -q
# Baked every run: a field left by an older baker would measure that baker.
$B bake "$W/r100k.obj" -o "$W/r100k.vlf" -q
$B rays "$W/r100k.vlf" --view outside --width 316 --height 316 -o "$W/outside.bin" -q
$B rays "$W/r100k.vlf" --view inside --width 316 --height 316 -o "$W/inside.bin" -q

python3 - "$W" <<'PY'
import math, random, struct, sys
w = sys.argv[1]
rng = random.Random(1)
out = []
for _ in range(100_000):
    o = [rng.uniform(-1.0, 1.0) for _ in range(3)]
    z = rng.uniform(-1.0, 1.0)
    a = rng.uniform(0.0, 2.0 * math.pi)
    r = math.sqrt(1.0 - z * z)
    out.append(struct.pack("<8f", o[0], o[1], o[2], 0.0, r * math.cos(a), r * math.sin(a), z, float("inf")))
open(f"{w}/incoherent.bin", "wb").write(b"".join(out))
# 2,000 rays spread evenly over each set, 50 times over; and one ray, for the baseline.
for name in ("outside", "inside", "incoherent"):
    data = open(f"{w}/{name}.bin", "rb").read()
    n = len(data) // 32
    sample = b"".join(data[32 * i : 32 * i + 32] for i in range(0, n, n // 2000)[:2000])
    open(f"{w}/{name}-cached.bin", "wb").write(sample * 50)
    open(f"{w}/{name}-one.bin", "wb").write(data[:32])
PY

ns_per_ray() { # FILE: median over 5 runs of the traced seconds per ray, in ns
  for _ in 1 2 3 4 5; do
    $B trace "$W/r100k.vlf" --rays "$1" -o "$W/hits.bin" --threads 1 --json
  done | python3 -c '
import json, statistics, sys
runs = [json.loads(l) for l in sys.stdin]
per_ray = statistics.median(r["seconds"] / r["rays"] for r in runs)
print(round(per_ray * 1e9))'
}

grind() { # FILE: "instructions D1-misses LL-misses" of one traced run
  valgrind --tool=cachegrind --cache-sim=yes --LL=16777216,16,64 --cachegrind-out-file=/dev/null \
    $B trace "$W/r100k.vlf" --rays "$1" -o "$W/hits.bin" --threads 1 -q 2>&1 |
    python3 -c '
import re, sys
t = sys.stdin.read().replace(",", "")
get = lambda k: int(re.search(k + r"\s*:\s*(\d+)", t).group(1))
print(get("I\\s+refs"), get("D1\\s+misses"), get("LLd\\s+misses"))'
}

echo "| rays | traced ns/ray | cached ns/ray | instructions/ray | L1d misses/ray | LL misses/ray (16 MiB) |"
echo "| --- | ---: | ---: | ---: | ---: | ---: |"
for set in outside inside incoherent; do
  n=$(( $(stat -c %s "$W/$set.bin") / 32 ))
  traced=$(ns_per_ray "$W/$set.bin")
  cached=$(ns_per_ray "$W/$set-cached.bin")
  read -r i d l <<<"$(grind "$W/$set.bin")"
  read -r i0 d0 l0 <<<"$(grind "$W/$set-one.bin")"
  python3 -c "
n=$n
print(f'| $set ({n} rays) | $traced | $cached | {($i-$i0)/n:.0f} | {($d-$d0)/n:.1f} | {($l-$l0)/n:.1f} |')"
done
