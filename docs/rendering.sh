#!/usr/bin/env bash
# Regenerates the pictures of docs/rendering.md into docs/images/, with exactly the commands that
# page shows (intermediate meshes and fields go to target/rendering/). About a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
# Tools must never read our standard input (see .ci/run).
exec < <(:)
cargo build --release -q --bin vlf-bake
mkdir -p target/rendering docs/images
vlf-bake() { target/release/vlf-bake "$@"; }
set -x

# The bunny in the fixture room: materials, camera and lights from the glTF.
vlf-bake bake fixtures/meshes/cornell/cornell.gltf fixtures/meshes/bunny.obj -o target/rendering/cornell-bunny.vlf -q
vlf-bake render target/rendering/cornell-bunny.vlf -o docs/images/cornell-bunny.png --samples 3 \
    --work-image docs/images/cornell-bunny-tests.png

# The bunny scene: no materials, camera or lights in the file, so the defaults.
vlf-bake bake fixtures/meshes/bunny_scene.glb -o target/rendering/bunny-scene.vlf -q
vlf-bake render target/rendering/bunny-scene.vlf -o docs/images/bunny-scene.png --samples 3

# The paper's Figure 5: 9000 random triangles from outside, 16000 from inside.
vlf-bake gen random --count 9000 -o target/rendering/random-9k.obj
vlf-bake bake target/rendering/random-9k.obj -o target/rendering/random-9k.vlf -q
vlf-bake render target/rendering/random-9k.vlf -o docs/images/random-9k-outside.png --view outside --samples 3
vlf-bake gen random --count 16000 -o target/rendering/random-16k.obj
vlf-bake bake target/rendering/random-16k.obj -o target/rendering/random-16k.vlf -q
vlf-bake render target/rendering/random-16k.vlf -o docs/images/random-16k-inside.png --view inside --samples 3 \
    --width 512 --height 384 --work-image docs/images/random-16k-inside-tests.png
vlf-bake render target/rendering/random-16k.vlf -o target/rendering/random-16k-inside.png --view inside --samples 3 \
    --width 512 --height 384 --work-image docs/images/random-16k-inside-tiles.png --work tiles
