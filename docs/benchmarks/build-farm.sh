#!/usr/bin/env bash
# Build-farm figures (docs/build-farms.md): the paper's 100K random-triangle scene at 128² tiles and
# 129 directions baked whole, in 2 shards and in 4 shards (each shard run alone, one after the
# other, so that each has the machine, as it would have its own), with the parameters pinned and
# with the directions chosen automatically; the merge of each set (checked byte-identical to the
# whole bake); and a cold bake against a cache hit.
# Every number is read from the commands' --report files. Release mode, all cores.
#
#   bash docs/benchmarks/build-farm.sh [WORKDIR]     (default WORKDIR: target/build-farm)
#
# Writes docs/benchmarks/build-farm.md; needs about 3 GiB of disk in WORKDIR.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec </dev/null
cargo build --release -q --bin vlf-bake
B=$PWD/target/release/vlf-bake
W=${1:-target/build-farm}
OUT=docs/benchmarks/build-farm.md
mkdir -p "$W"
[ -f "$W/random-100k.obj" ] || $B gen random --count 100000 --seed 1 -o "$W/random-100k.obj"
load_before=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown)

# sharded NAME N PARAMS...: shards 0..N-1 one after the other, then the merge, checked against the
# whole bake NAME-whole.vlf.
sharded() {
  local name=$1 n=$2
  shift 2
  for ((k = 0; k < n; k++)); do
    echo "$name: shard $k/$n" >&2
    $B bake "$W/random-100k.obj" "$@" --shard "$k/$n" -o "$W/$name-s$n-$k.vlfs" --no-cache --quiet \
      --report "$W/$name-s$n-$k.json"
  done
  echo "$name: merge of $n" >&2
  $B merge "$W/$name-s$n-"*.vlfs -o "$W/$name-merged-$n.vlf" --no-cache --quiet --report "$W/$name-merge-$n.json"
  cmp "$W/$name-whole.vlf" "$W/$name-merged-$n.vlf"
  rm -f "$W/$name-s$n-"*.vlfs "$W/$name-merged-$n.vlf"
}

# Parameters pinned, as a farm should run: no shard repeats the automatic search.
PINNED=(--directions 129 --tiles 128)
echo "pinned: whole bake" >&2
$B bake "$W/random-100k.obj" "${PINNED[@]}" -o "$W/pinned-whole.vlf" --no-cache --quiet --report "$W/pinned-whole.json"
sharded pinned 2 "${PINNED[@]}"
sharded pinned 4 "${PINNED[@]}"

# Directions chosen automatically: every shard runs the search.
AUTO=(--tiles 128)
echo "auto: whole bake" >&2
$B bake "$W/random-100k.obj" "${AUTO[@]}" -o "$W/auto-whole.vlf" --no-cache --quiet --report "$W/auto-whole.json"
sharded auto 4 "${AUTO[@]}"
rm -f "$W/auto-whole.vlf"

echo "cache: cold, then hit" >&2
rm -rf "$W/cache"
$B bake "$W/random-100k.obj" "${PINNED[@]}" -o "$W/cold.vlf" --cache-dir "$W/cache" --quiet --report "$W/cold.json"
$B bake "$W/random-100k.obj" "${PINNED[@]}" -o "$W/hit.vlf" --cache-dir "$W/cache" --quiet --report "$W/hit.json"
cmp "$W/cold.vlf" "$W/hit.vlf"
cmp "$W/cold.vlf" "$W/pinned-whole.vlf"
rm -rf "$W/cache" "$W/cold.vlf" "$W/hit.vlf" "$W/pinned-whole.vlf"
load_after=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo unknown)

python3 - "$W" "$OUT" "$load_before" "$load_after" <<'PY'
import json, os, subprocess, sys
w, out, load_before, load_after = sys.argv[1:]
r = lambda name: json.load(open(os.path.join(w, name + ".json")))
ph = lambda rep, name: sum(p["seconds"] for p in rep["phases"] if p["name"] == name)
mib = lambda b: f"{b / 2**20:.0f}"
whole = r("pinned-whole")
auto_whole = r("auto-whole")
cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "unknown CPU")
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
c = whole["parameters"]["chosen"]
lines = [
    "# Build farm: sharded bakes and the bake cache",
    "",
    f"Regenerate with `bash docs/benchmarks/build-farm.sh`. Commit {commit}; {os.cpu_count()} threads of {cpu};",
    f"load average {load_before} before the run and {load_after} after. The scene is the paper's 100K",
    "random triangles (`vlf-bake gen random --count 100000 --seed 1`) at 128² tiles with",
    f"{c['directions']} directions (what `--tiles 128` chooses automatically), a field of {mib(whole['output']['bytes'])} MiB.",
    "Each shard ran alone, one after the other, with every core, as it would on its own machine.",
    "Seconds are wall-clock, from the commands' `--report` files; every merged field was checked",
    "byte-identical to the whole bake with `cmp`.",
]
head = [
    "| bake | directions | import + prepare s | choose s | bake s | write s | total s | peak RSS MiB | file MiB |",
    "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
]
def row(label, rep, dirs):
    return (
        f"| {label} | {dirs} | {ph(rep, 'import') + ph(rep, 'prepare'):.2f} | {ph(rep, 'choose'):.2f} | {ph(rep, 'bake'):.2f} "
        f"| {ph(rep, 'write'):.2f} | {rep['seconds']:.2f} | {mib(rep['peak_memory']['bytes'] or 0)} | {mib(rep['output']['bytes'])} |"
    )
def table(name, whole, counts):
    out = head + [row("whole", whole, f"0..{whole['parameters']['chosen']['directions']}")]
    summary = []
    for n in counts:
        shards = [r(f"{name}-s{n}-{k}") for k in range(n)]
        out += [row(f"shard {k}/{n}", s, f"{s['shard']['first_direction']}..{s['shard']['end_direction']}") for k, s in enumerate(shards)]
        m = r(f"{name}-merge-{n}")
        out.append(
            f"| merge of {n} | all | | | {ph(m, 'check'):.2f} check + {ph(m, 'copy'):.2f} copy | {ph(m, 'write'):.2f} "
            f"| {m['seconds']:.2f} | {mib(m['peak_memory']['bytes'] or 0)} | {mib(m['output']['bytes'])} |"
        )
        slowest = max(s["seconds"] for s in shards)
        summary.append(
            f"- **{n} shards**: the slowest shard took {slowest:.2f} s and the merge {m['seconds']:.2f} s: {n} machines "
            f"finish in {slowest + m['seconds']:.2f} s against {whole['seconds']:.2f} s for one "
            f"({whole['seconds'] / (slowest + m['seconds']):.2f}× faster), and spend {sum(s['seconds'] for s in shards):.2f} s together."
        )
    return out + [""] + summary
lines += ["", "## Sharded bakes, parameters pinned (`--directions 129 --tiles 128`)", ""]
lines += table("pinned", whole, (2, 4))
lines += [
    "",
    "## Sharded bakes, directions chosen automatically (`--tiles 128`)",
    "",
    "Every shard runs the automatic search (the `choose` column: sample directions baked for real,",
    "`docs/benchmarks/parameters.md`), the same work as the whole bake, before its share of the",
    "directions. Pinning the parameters, as the recipes' `BAKE_ARGS` can, saves it on every shard.",
    "",
]
lines += table("auto", auto_whole, (4,))
cold, hit = r("cold"), r("hit")
lines += [
    "",
    "## The bake cache",
    "",
    "The same bake twice with `--cache-dir`: the first misses, bakes and stores the field; the second",
    "imports, hashes and copies the stored field (and checks the copy) instead of baking.",
    "",
    "| run | cache | import + prepare s | key s | lookup (copy + checks) s | choose + bake + write s | store s | total s |",
    "| --- | --- | --- | --- | --- | --- | --- | --- |",
]
for label, rep in (("cold", cold), ("again", hit)):
    lines.append(
        f"| {label} | {rep['cache']['status']} | {ph(rep, 'import') + ph(rep, 'prepare'):.2f} | {ph(rep, 'cache_key'):.3f} "
        f"| {ph(rep, 'cache_lookup'):.2f} | {ph(rep, 'choose') + ph(rep, 'bake') + ph(rep, 'write'):.2f} "
        f"| {ph(rep, 'cache_store'):.2f} | {rep['seconds']:.2f} |"
    )
lines += [
    "",
    f"A hit took {hit['seconds']:.2f} s against {cold['seconds']:.2f} s cold ({cold['seconds'] / hit['seconds']:.0f}× less): "
    f"the import of the {os.path.getsize(os.path.join(w, 'random-100k.obj')) / 2**20:.1f} MiB OBJ and the copy of the "
    f"{mib(hit['output']['bytes'])} MiB field are all it costs.",
]
open(out, "w").write("\n".join(lines) + "\n")
print(open(out).read())
PY
