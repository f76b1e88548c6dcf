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
  bash docs/benchmarks/single-ray-sets.sh "$s"
  echo "| $s | $(count "$W/$s.vlf" "$W/$s-outside.bin") | $(count "$W/$s.vlf" "$W/$s-inside.bin") | $(count "$W/$s.vlf" "$W/$s-incoherent.bin") | $(count "$W/$s.vlf" "$W/$s-shadow.bin" --any) |"
done
