#!/usr/bin/env bash
# Issue 2's figures: bake time, file size and trace throughput at the default (automatic)
# parameters for the bunny and the paper's random-triangle scenes of 10K and 100K triangles, and
# dump time on the largest field next to the smallest. Release mode, all cores.
#
#   bash docs/benchmarks/core-pipeline.sh [WORKDIR]     (default WORKDIR: target/core-pipeline)
set -euo pipefail
cd "$(dirname "$0")/../.."
exec </dev/null
cargo build --release -q --bin vlf-bake
B=$PWD/target/release/vlf-bake
W=${1:-target/core-pipeline}
mkdir -p "$W"
cp fixtures/meshes/bunny.obj "$W/bunny.obj"
[ -f "$W/random-10k.obj" ] || $B gen random --count 10000 --seed 1 -o "$W/random-10k.obj"
[ -f "$W/random-100k.obj" ] || $B gen random --count 100000 --seed 1 -o "$W/random-100k.obj"
echo "| scene | triangles | parameters | bake s | peak RSS MiB | field | outside Mrays/s | inside Mrays/s |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for m in bunny random-10k random-100k; do
  /usr/bin/time -f "%M" -o "$W/$m.rss" $B bake "$W/$m.obj" -o "$W/$m.vlf" --json > "$W/$m.bake.json"
  row=$(python3 -c "
import json; d=json.load(open('$W/$m.bake.json'))
print(f\"| $m | {d['triangles']} | {d['directions']} dirs × {d['tile_resolution']}² tiles | {d['seconds']:.2f} | {int(open('$W/$m.rss').read())/1024:.0f} | {d['bytes']/2**20:.1f} MiB |\", end='')")
  for v in outside inside; do
    $B rays "$W/$m.vlf" --view $v --width 512 --height 512 -o "$W/$m-$v.rays"
    $B trace "$W/$m.vlf" --rays "$W/$m-$v.rays" -o "$W/$m-$v.hits" > /dev/null   # warm-up
    med=$(for i in 1 2 3 4 5 6 7; do $B trace "$W/$m.vlf" --rays "$W/$m-$v.rays" -o "$W/$m-$v.hits" --json; done \
      | python3 -c "import sys,json,statistics; print('%.2f' % statistics.median(json.loads(l)['mrays_per_s'] for l in sys.stdin))")
    row="$row $med |"
  done
  echo "$row"
done
echo
smallest=$W/box.vlf
$B bake fixtures/meshes/Box.gltf -o "$smallest" --quiet
for f in "$smallest" "$W/random-100k.vlf"; do
  printf "dump %s (%s bytes): " "$(basename "$f")" "$(stat -c %s "$f")"
  python3 - "$B" "$f" <<'PY'
import subprocess, sys, time, statistics
b, f = sys.argv[1], sys.argv[2]
ts = []
for _ in range(20):
    t = time.perf_counter(); subprocess.run([b, "dump", f], check=True, stdout=subprocess.DEVNULL); ts.append(time.perf_counter() - t)
print(f"median {statistics.median(ts)*1e3:.1f} ms over 20 runs (whole process)")
PY
done
