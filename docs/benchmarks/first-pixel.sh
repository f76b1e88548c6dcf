#!/usr/bin/env bash
# Time to first pixel: open a field and trace its first ray in a new process, for a ~1 MiB field
# and a >1 GiB field of the same scene, and for a >1 GiB field of the paper's 100K scene; with the
# file in the page cache (warm) and evicted from it (cold); through `Field::open` and through the
# same checks on a mapping advised MADV_RANDOM. Writes docs/benchmarks/first-pixel.md (and .json).
#
#   bash docs/benchmarks/first-pixel.sh [WORKDIR] [RUNS]
#
# WORKDIR (default target/first-pixel) needs about 3 GiB free; the fields are deleted on exit.
# RUNS (default 21) new processes per field, cache state and way of opening.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec < <(:)
W=${1:-target/first-pixel}
RUNS=${2:-21}
OUT=docs/benchmarks/first-pixel
mkdir -p "$W"
trap 'rm -f "$W"/*.vlf "$W"/*.obj' EXIT

cargo build --release -q -p vlf-cli -p vlf-bench
B=target/release/vlf-bake

# Same scene, two sizes: 2,500 random triangles (half-extent 0.2, so the centre ray hits), baked
# at 9 directions × 20² tiles (~0.9 MiB) and at 2049 directions × 128² tiles (~1.2 GiB).
$B gen random --count 2500 --size 0.2 --seed 1 -o "$W/r2500.obj"
$B bake "$W/r2500.obj" -o "$W/small-1mib.vlf" --directions 9 --tiles 20 --quiet
$B bake "$W/r2500.obj" -o "$W/same-scene-1gib.vlf" --directions 2049 --tiles 128 --max-bytes 4GiB --quiet
# The paper's 100K scene at 513 directions × 64² tiles (~1.4 GiB).
$B gen random --count 100000 --seed 1 -o "$W/r100k.obj"
$B bake "$W/r100k.obj" -o "$W/random-100k-1gib.vlf" --directions 513 --tiles 64 --max-bytes 4GiB --quiet

load=$(cut -d' ' -f1-3 /proc/loadavg)
fields=("$W/small-1mib.vlf" "$W/same-scene-1gib.vlf" "$W/random-100k-1gib.vlf")
table=$(target/release/vlf-bench first-pixel --quiet --runs "$RUNS" --cold --access open,random \
  --json "$OUT.json" "${fields[@]}")

dev=$(df --output=source "$W" | tail -1)
ra=$(cat "/sys/block/$(basename "$dev")/queue/read_ahead_kb" 2>/dev/null || echo "?")
{
  echo "# Time to first pixel"
  echo
  echo "Open a field and trace its first ray (the primary ray through the centre of the paper's outside"
  echo "view), each run in a new process: \`vlf-bench first-pixel\`, run by"
  echo "\`bash docs/benchmarks/first-pixel.sh\` ($RUNS runs per row; $(nproc) cores, $(uname -sr);"
  echo "device read-ahead ${ra} KiB; load average before the runs: $load). Times are medians in"
  echo "microseconds, with the range over the runs."
  echo
  echo "- **warm**: the pages the ray needs are in the page cache (a warm-up run read them)."
  echo "- **cold**: the file is evicted from the page cache before every run"
  echo "  (\`posix_fadvise(POSIX_FADV_DONTNEED)\`; *cached before* is the largest fraction of the file still"
  echo "  cached at a run's start, from \`mincore\`), so every page the process touches is read from disk."
  echo "  *read from disk* is how much of the file was cached after the run, read-ahead included."
  echo "- **\`Field::open\`** is the runtime as a renderer uses it; **map + \`MADV_RANDOM\`** is the same"
  echo "  mapping and checks (\`FieldView::from_bytes\`) with the kernel's read-ahead turned off before the"
  echo "  first read."
  echo "- *open* is \`Field::open\` (map, header, section table, content hash); *first ray* is one"
  echo "  \`closest_hit\`; *whole process* is the wall time of the child from the parent's side (exec,"
  echo "  dynamic loading, open, ray, exit)."
  echo
  for f in "${fields[@]}"; do
    echo "- \`$(basename "$f")\`: $(stat -c %s "$f") bytes, $($B dump "$f" | sed -n 's/^  triangles *\([0-9]*\).*/\1/p') triangles,"\
      "$($B dump "$f" | sed -n 's/^  directions *\([0-9]*\).*/\1/p') directions,"\
      "$($B dump "$f" | sed -n 's/^  tiles *\([0-9]*²\).*/\1/p') tiles"
  done
  echo
  echo "$table"
  echo
  echo "## How to read it"
  echo
  echo "Opening checks the header, the section table and their hash, and nothing else; a ray reads a"
  echo "few kilobytes (a lookup cell, a rotation, a beam record, the tiles and leaves it crosses, the"
  echo "triangles it tests). Neither depends on the file's size, so **warm** rows of fields of any size"
  echo "should agree within noise, and the cold rows' *read from disk* column shows how little of a"
  echo "large file the first pixel needs. What a cold first ray costs is page faults: one disk read"
  echo "per page not yet cached, and with \`Field::open\` the kernel reads ahead around each fault, up"
  echo "to the device's read-ahead, so a cold ray on a large file reads that much per fault, while a"
  echo "1 MiB file is read whole by the first fault or two. \`MADV_RANDOM\` turns read-ahead off: each"
  echo "fault then reads one page. It also makes a whole frame from a cold file read page by page,"
  echo "which is why it is measured here rather than made the runtime's default."
  echo
  echo "[big-field.md](big-field.md) times \`Field::open\` alone, in one process, for 1 MiB and 9.7 GiB."
} > "$OUT.md"
echo "wrote $OUT.md and $OUT.json"
