#!/usr/bin/env bash
# Regenerates docs/images/dynamic-room.png, the animation of docs/dynamic.md: the bunny, baked once,
# placed twice in the bundled room (once mirrored and squashed), one instance travelling across the
# room and turning a full circle, the room's yellow block removed by name. The fields go to
# target/dynamic/ (docs/dynamic/room.json refers to them there). About a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
# Tools must never read our standard input (see .ci/run).
exec < <(:)
cargo build --release -q --bin vlf-bake
mkdir -p target/dynamic docs/images
vlf-bake() { target/release/vlf-bake "$@"; }
set -x

vlf-bake bake fixtures/meshes/cornell/cornell.gltf -o target/dynamic/room.vlf -q
vlf-bake bake fixtures/meshes/bunny.obj -o target/dynamic/bunny.vlf -q
vlf-bake render --scene docs/dynamic/room.json -o docs/images/dynamic-room.png \
    --frames 30 --move 1 --path 20,0,0 --spin 360 --frame-ms 80 \
    --eye 0,12,52 --target 0,9,-2 --fov 38 --light 0,21,0,300 --light 0,14,40,900 \
    --width 320 --samples 2
