#!/usr/bin/env bash
# Single-ray time of several fields of one scene on the same rays: which parameters trace faster.
#
#   bash docs/benchmarks/single-ray-fields.sh [--full] SCENE FIELD... [-- ROUNDS]
#
# SCENE names the ray sets `docs/benchmarks/single-ray-sets.sh` wrote to target/single-ray/
# (`single-ray.sh` makes `r100k` and `dragon`): SCENE-outside.bin, -inside.bin, -incoherent.bin
# and -shadow.bin (any hit). Each round times every field in turn on every set (the `single_ray`
# example, three passes, their median), so that the machine's drift falls on all fields alike;
# the table is the median over rounds (default 5) in ns per ray, one thread. `--full` times the
# whole 512² views instead of their middle 64 rows, and cycles the incoherent rays to 100,000 and
# the shadow rays to 131,072: longer passes, steadier medians.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
full=0
[ "${1:-}" = --full ] && { full=1; shift; }
[ $# -ge 2 ] || { sed -n 2,12p "$0" >&2; exit 2; }
scene=$1; shift
fields=(); rounds=5
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then rounds=$2; break; fi
  fields+=("$1"); shift
done
W=target/single-ray
for r in outside inside incoherent shadow; do
  [ -f "$W/$scene-$r.bin" ] || { echo "no $W/$scene-$r.bin: run docs/benchmarks/single-ray.sh first" >&2; exit 1; }
done
cargo build --release -q -p vlf-runtime --example single_ray
S=target/release/examples/single_ray
out=$(mktemp); trap 'rm -f "$out"' EXIT
for ((round = 0; round < rounds; round++)); do
  for f in "${fields[@]}"; do
    for r in outside inside incoherent shadow; do
      any=(); [ "$r" = shadow ] && any=(--any)
      rays="$W/$scene-$r.bin"; count=()
      if [ $full = 1 ]; then
        case $r in
          outside | inside) rays="$W/$scene-$r-all.bin" ;;
          incoherent) count=(--count 100000) ;;
          shadow) count=(--count 131072) ;;
        esac
      fi
      ns=$($S "$f" "$rays" "${any[@]}" "${count[@]}" --rounds 3 | sed -nE 's/.*median ([0-9.]+) ns.*/\1/p')
      echo "$f $r $ns" >> "$out"
    done
  done
done
python3 - "$out" <<'PY'
import collections, os, statistics, sys
d = collections.defaultdict(list)
for line in open(sys.argv[1]):
    f, r, ns = line.split()
    d[(f, r)].append(float(ns))
sets = ["outside", "inside", "incoherent", "shadow"]
print("| field | bytes | " + " | ".join(sets) + " |")
print("| --- | ---: | " + " | ".join("---:" for _ in sets) + " |")
for f in dict.fromkeys(k[0] for k in d):
    cells = " | ".join(f"{statistics.median(d[(f, r)]):.0f}" for r in sets)
    print(f"| {f} | {os.path.getsize(f):,} | {cells} |")
PY
