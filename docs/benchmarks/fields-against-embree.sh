#!/usr/bin/env bash
# Fields of one scene at several parameters against Embree, on the peers' whole views: which
# field a default should choose. Each field and Embree trace the same rays in one process
# (`vs_embree`, median of 7 rounds, one core), the fields taking turns, REPEATS times; it prints
# the medians over the repeats of each field's ns per ray, Embree's and their ratio (the ratio
# is the figure to read: the two run side by side, so a slow phase of the machine moves both).
#
#   bash docs/benchmarks/fields-against-embree.sh SCENE REPEATS DxN [DxN ...]
#   e.g. bash docs/benchmarks/fields-against-embree.sh r100kd 5 default 73x64 129x64
#
# Reads target/single-ray/SCENE.obj and SCENE.vlf and the whole 512² views SCENE-outside-all.bin
# and SCENE-inside-all.bin (make them with `bash docs/benchmarks/single-ray-sets.sh SCENE MESH`).
# `default` is SCENE.vlf as that script baked it; `DxN` bakes SCENE-DxN.vlf with `--directions D
# --tiles N` if it is missing. The incoherent rays are SCENE-incoherent-big.bin, 262,144 of them as
# the peers trace. Needs Debian's libembree-dev (installed when missing).
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
[ $# -ge 3 ] || { sed -n 2,15p "$0" >&2; exit 2; }
s=$1
repeats=$2
shift 2
W=target/single-ray
[ -f "$W/$s.vlf" ] && [ -f "$W/$s-outside-all.bin" ] && [ -f "$W/$s-incoherent-big.bin" ] || {
  echo "no $W/$s.vlf or its ray sets: run docs/benchmarks/single-ray-sets.sh $s MESH first" >&2
  exit 1
}
if [ ! -f /usr/include/embree3/rtcore.h ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libembree-dev
fi
cargo build --release -q --bin vlf-bake
cargo build --release -q -p vlf-bench --features embree --example vs_embree
B=target/release/vlf-bake
V=target/release/examples/vs_embree
PIN=()
command -v taskset >/dev/null && PIN=(taskset -c 1)
fields=()
for spec in "$@"; do
  if [ "$spec" = default ]; then
    fields+=("$s")
    continue
  fi
  [[ $spec =~ ^([0-9]+)x([0-9]+)$ ]] || { echo "$spec: give DxN (directions x tiles) or default" >&2; exit 2; }
  [ -f "$W/$s-$spec.vlf" ] || $B bake "$W/$s.obj" -o "$W/$s-$spec.vlf" -q \
    --directions "${BASH_REMATCH[1]}" --tiles "${BASH_REMATCH[2]}" --max-bytes 16GiB
  fields+=("$s-$spec")
done
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for set in outside-all inside-all incoherent-big; do
  for _ in $(seq "$repeats"); do
    for f in "${fields[@]}"; do
      line=$("${PIN[@]}" "$V" "$W/$f.vlf" 7 "$W/$s-$set.bin" | tail -1)
      echo "$set $f $(echo "$line" | sed -E 's/.*field +([0-9.]+) ns, embree +([0-9.]+) ns, field\/embree ([0-9.]+).*/\1 \2 \3/')" >>"$out"
    done
  done
done
python3 - "$out" "$W" "$s" "${fields[@]}" <<'PY'
import json, os, statistics as st, sys
out, w, scene, fields = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
rows = [l.split() for l in open(out)]
print("| rays | field | B/triangle | field ns | Embree ns | field / Embree | range |")
print("| --- | --- | ---: | ---: | ---: | ---: | --- |")
for s in ("outside-all", "inside-all", "incoherent-big"):
    for f in fields:
        r = [list(map(float, x[2:])) for x in rows if x[0] == s and x[1] == f and len(x) == 5]
        if not r:
            continue
        a, b, c = zip(*r)
        size = os.path.getsize(f"{w}/{f}.vlf")
        tris = json.load(open(f"{w}/{scene}.json"))["triangle_count"]
        print(f"| {s} | {f} | {size / tris:,.0f} | {st.median(a):.1f} | {st.median(b):.1f} | "
              f"{st.median(c):.2f} | {min(c):.2f}–{max(c):.2f} |")
PY
