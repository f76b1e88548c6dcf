#!/usr/bin/env bash
# Rebakes the field seeds of the fuzz corpus (fuzz/corpus/field_*) and fixtures/fields/tiny.vlf,
# after a change of the field format (docs/fuzzing.md, "The seeds"). Bakes are reproducible to the
# byte, so running it twice changes nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --bin vlf-bake -q
B=target/release/vlf-bake
C=fuzz/corpus/import_obj
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
$B gen random --count 40 --size 0.2 --seed 2 -o "$T/r40.obj"
$B gen grid --count 2 -o "$T/grid.obj"
$B bake "$C/box.obj" -o "$T/box-3x2.vlf" --directions 3 --tiles 2 --leaf-size 2 --max-depth 3 -q
$B bake "$C/random16.obj" -o "$T/random16-9x4.vlf" --directions 9 --tiles 4 --leaf-size 1 --max-depth 3 -q
$B bake "$T/r40.obj" -o "$T/random40-3x8.vlf" --directions 3 --tiles 8 --leaf-size 2 --max-depth 5 -q
$B bake "$T/grid.obj" -o "$T/grid-9x2-linear.vlf" --directions 9 --tiles 2 --max-depth 0 -q
$B bake fixtures/meshes/Box.gltf fixtures/meshes/small/groups.obj -o "$T/two-inputs-3x3.vlf" --directions 3 --tiles 3 -q
$B pack "$T/box-3x2.vlf" -o "$T/box-3x2-packed.vlf" -q
$B pack "$T/random16-9x4.vlf" -o "$T/random16-9x4-packed.vlf" -q
# The first seed with four rays appended (32-byte records of formats/rays.md), which the targets
# trace after their own.
python3 - "$T/box-3x2.vlf" "$T/box-3x2-with-rays.vlf" <<'PY'
import struct, sys
rays = [(0.5, 1.0, -5.0, 0.0, 0.0, 0.0, 1.0, float("inf")),
        (3.0, 3.0, 3.0, 0.0, -1.0, -1.0, -1.0, float("inf")),
        (0.5, 1.0, 1.5, 0.0, 0.3, -0.7, 0.2, 10.0),
        (-4.0, 1.0, 1.5, 1.0, 1.0, 0.0, 0.0, 2.0)]
data = open(sys.argv[1], "rb").read() + b"".join(struct.pack("<8f", *r) for r in rays)
open(sys.argv[2], "wb").write(data)
PY
for f in box-3x2 box-3x2-packed grid-9x2-linear random16-9x4 random16-9x4-packed random40-3x8 two-inputs-3x3; do
    cp "$T/$f.vlf" fuzz/corpus/field_open/
    cp "$T/$f.vlf" fuzz/corpus/field_resealed/
done
cp "$T/box-3x2-with-rays.vlf" fuzz/corpus/field_open/
$B bake fixtures/meshes/Box.gltf -o fixtures/fields/tiny.vlf --directions 9 --tiles 4 -q
echo "rebaked the field seeds and fixtures/fields/tiny.vlf"
