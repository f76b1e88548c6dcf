#!/usr/bin/env bash
# Nanoseconds per ray of the single-ray queries, this tree against an earlier revision, on the same
# fields and rays: the two builds of `examples/single_ray` run in turn, three times each, on every
# ray set of `single-ray.sh` (which must have run first: it bakes the fields and writes the rays).
# Timings of one build vary by a few percent between runs, so the two are interleaved rather than
# run one after the other; each figure printed is the median of five rounds over the set.
#
#   bash docs/benchmarks/single-ray-time.sh REVISION [REPEATS]
#
# REVISION is any git revision (the earlier build is made in a temporary worktree, whose target
# directory is kept in target/single-ray-time/ for the next run). The fields must be readable by
# both builds (same format version).
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
rev=${1:?usage: single-ray-time.sh REVISION [REPEATS]}
repeats=${2:-3}
W=target/single-ray
[ -f "$W/r100k.vlf" ] || { echo "run docs/benchmarks/single-ray.sh first" >&2; exit 1; }
T=target/single-ray-time
mkdir -p "$T"
tree=$(mktemp -d)
trap 'git worktree remove --force "$tree" >/dev/null 2>&1 || true' EXIT
git worktree add -q --detach "$tree" "$rev"
CARGO_TARGET_DIR="$PWD/$T/target" cargo build --release -q -p vlf-runtime --example single_ray --manifest-path "$tree/Cargo.toml"
cargo build --release -q -p vlf-runtime --example single_ray
before="$T/target/release/examples/single_ray"
after=target/release/examples/single_ray
ns() { "$1" "$2" "$3" ${4:-} --rounds 5 | sed -E 's/.*median ([0-9.]+) ns.*/\1/'; }
echo "| scene | rays | $rev (ns per ray) | this tree | change |"
echo "| --- | --- | ---: | ---: | ---: |"
scenes="r100k"
[ -f "$W/dragon.vlf" ] && scenes="$scenes dragon"
for s in $scenes; do
  for set in outside inside incoherent shadow; do
    any=""
    [ "$set" = shadow ] && any=--any
    a=() b=()
    for _ in $(seq "$repeats"); do
      a+=("$(ns "$before" "$W/$s.vlf" "$W/$s-$set.bin" $any)")
      b+=("$(ns "$after" "$W/$s.vlf" "$W/$s-$set.bin" $any)")
    done
    python3 - "$s" "$set" "${a[*]}" "${b[*]}" <<'PY'
import statistics, sys
s, rays, a, b = sys.argv[1], sys.argv[2], [float(x) for x in sys.argv[3].split()], [float(x) for x in sys.argv[4].split()]
ma, mb = statistics.median(a), statistics.median(b)
print(f"| {s} | {rays} | {ma:.1f} | {mb:.1f} | {100 * (mb / ma - 1):+.1f}% |")
PY
  done
done
