#!/usr/bin/env bash
# The dynamic-scene benchmark of issue 13: 1,000 instances of a 10K-triangle field against
# Embree 3's two-level instancing (primary and incoherent rays, closest and any hit), 100
# instance transforms updated per frame against Embree's top-level rebuild, and the paper's
# delete and reinsert of 1K- and 10K-triangle objects in a 100K-triangle field with the query
# speed as moves accumulate. Writes docs/benchmarks/dynamic.md from this run.
#
#   bash docs/benchmarks/dynamic.sh [extra vlf-bench dynamic options]
#
# Installs Debian's libembree-dev (3.13) when /usr/include/embree3/rtcore.h is missing. Fields are
# baked into target/bench-work/ and deleted after use (the 100K one takes about 400 MiB). A few
# minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
if [ ! -f /usr/include/embree3/rtcore.h ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libembree-dev
fi
cargo build --release -q -p vlf-bench --features embree
target/release/vlf-bench dynamic --out docs/benchmarks "$@"
