#!/usr/bin/env bash
# The single-ray field against Embree, ray class by ray class: nanoseconds and instructions per
# ray of each, on the same rays in one process. Tells work from waiting: a contestant that
# executes more instructions per ray loses even when both find their data in cache.
#
#   bash docs/benchmarks/against-embree.sh SCENE
#
# Reads target/single-ray/SCENE.vlf and its ray sets (make them first with
# `bash docs/benchmarks/single-ray-sets.sh SCENE MESH`): the whole outside view split by what
# each ray does (misses the scene's box, "away"; enters the box and misses the scene, "box
# miss"; hits, "hit"), warm sets of the last two (300 rays of the class, 100 times over: every
# line they touch stays cached), the inside view's middle rows, and the incoherent rays, cold
# and warm. For each set it prints, for the field and for Embree 3
# (`rtcIntersect1`, built over the field's own triangles):
#   - ns per ray: `vs_embree`, the two in turn, median of 7 rounds, on one core (`taskset -c 1`);
#   - instructions per ray: one round under callgrind, counting only inside each contestant's
#     single-ray call (`--toggle-collect` on `FieldView::closest_with` and on the Embree shim's
#     `vlf_embree_intersect1`, which sets up Embree's ray and calls `rtcIntersect1`).
#
# Installs what it needs (Debian's libembree-dev and valgrind) when missing. About five minutes
# for a scene of a million triangles on 2 cores, most of it Embree's build under callgrind.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
[ $# -eq 1 ] || { sed -n 2,21p "$0" >&2; exit 2; }
s=$1
W=target/single-ray
for f in "$s.vlf" "$s-outside-hit.bin" "$s-inside.bin" "$s-incoherent.bin" "$s-incoherent-warm.bin"; do
  [ -f "$W/$f" ] || { echo "no $W/$f: run docs/benchmarks/single-ray-sets.sh $s MESH first" >&2; exit 1; }
done
if [ ! -f /usr/include/embree3/rtcore.h ] || ! command -v valgrind >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libembree-dev valgrind
fi
cargo build --release -q -p vlf-bench --features embree --example vs_embree
V=target/release/examples/vs_embree
PIN=()
command -v taskset >/dev/null && PIN=(taskset -c 1)

echo "| $s rays | count | field ns | Embree ns | field / Embree | field instructions | Embree instructions |"
echo "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"
for set in outside-away outside-box-miss outside-box-miss-warm outside-hit outside-hit-warm inside incoherent incoherent-warm; do
  f="$W/$s-$set.bin"
  [ -s "$f" ] || continue
  line=$("${PIN[@]}" "$V" "$W/$s.vlf" 7 "$f" | tail -1)
  n=$(echo "$line" | sed -E 's/^[^ ]+ +([0-9]+) rays.*/\1/')
  field_ns=$(echo "$line" | sed -E 's/.*field +([0-9.]+) ns, embree.*/\1/')
  embree_ns=$(echo "$line" | sed -E 's/.*embree +([0-9.]+) ns,.*/\1/')
  ratio=$(echo "$line" | sed -E 's/.*field\/embree ([0-9.]+).*/\1/')
  out=$(mktemp)
  valgrind --tool=callgrind --toggle-collect='*FieldView*closest_with*' --toggle-collect='vlf_embree_intersect1' \
    --callgrind-out-file="$out" "$V" "$W/$s.vlf" 1 "$f" >/dev/null 2>&1
  counts=$(callgrind_annotate --inclusive=yes "$out" 2>/dev/null)
  rm -f "$out"
  per_ray() { echo "$counts" | grep -m1 "$1" | awk -v n="$n" '{gsub(",", "", $1); printf "%.0f", $1 / n}'; }
  echo "| $set | $n | $field_ns | $embree_ns | $ratio | $(per_ray closest_with) | $(per_ray vlf_embree_intersect1) |"
done
