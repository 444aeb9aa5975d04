#!/usr/bin/env bash
# Per-ray cost from a small to a large random grid (the goal in docs/benchmarks.md:
# per-ray cost grows at most 3x from 100 to 100,000 blocks). Both grids come from
# `komplex generate grid --count N` (same seed, same camera framing the
# cube). Each round renders the small grid and then the large one with
# `komplex bench --runs K` (the scene loaded once, the fastest of K renders
# kept); the rounds alternate the two so that a slow phase of the machine
# hits both. Cost per ray is render seconds over all rays traced (camera,
# shadow and reflection rays), so the growth is
#   (t_large / rays_large) / (t_small / rays_small).
# Printed: each round's growth, then the growth of the fastest renders
# overall and the median of the rounds' growths.
#
# Usage: scripts/bench-scaling.sh [--width W] [--height H] [--threads N]
#            [--rounds R] [--runs K] [--small N] [--large N] [--instructions]
# Defaults: 640x480, one thread per core, 5 rounds of 3 runs, 100 and
# 100,000 blocks. --instructions also counts instructions with valgrind's
# callgrind (needs valgrind; minutes at 100,000 blocks): the difference of
# two whole runs at 320x240 and 160x120 on one thread, over the difference
# of their rays, which leaves out loading and is free of the machine's
# timing noise.
# KOMPLEX=path/to/komplex: measure that binary (no build).
set -euo pipefail
cd "$(dirname "$0")/.."

width=640 height=480 threads="" rounds=5 runs=3 small=100 large=100000 instructions=0
while [ $# -gt 0 ]; do
    case "$1" in
        --width) width="$2"; shift 2 ;;
        --height) height="$2"; shift 2 ;;
        --threads) threads="$2"; shift 2 ;;
        --rounds) rounds="$2"; shift 2 ;;
        --runs) runs="$2"; shift 2 ;;
        --small) small="$2"; shift 2 ;;
        --large) large="$2"; shift 2 ;;
        --instructions) instructions=1; shift ;;
        -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
        *) echo "bench-scaling: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
for v in "$width" "$height" "$rounds" "$runs" "$small" "$large" ${threads:+"$threads"}; do
    case "$v" in
        ''|*[!0-9]*|0) echo "bench-scaling: '$v' is not a positive whole number" >&2; exit 2 ;;
    esac
done

source scripts/komplex-bin.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$komplex" generate grid --count "$small" -o "$work/small.json"
"$komplex" generate grid --count "$large" -o "$work/large.json"

# `komplex bench`'s data line: all rays in column 7 and all rays per second
# (of the fastest render) in 9; the seconds in column 5 are rounded to ms.
bench() {
    "$komplex" bench "$1" --width "$width" --height "$height" ${threads:+--threads "$threads"} --runs "$runs" |
        awk 'NR == 2 { printf "%.9g %d\n", $7 / $9, $7 }'
}

echo "grid $small vs $large blocks, ${width}x${height}, threads: ${threads:-one per core}, $rounds rounds of $runs runs"
printf '%-6s %12s %12s %12s %12s %8s\n' round "small s" "small rays" "large s" "large rays" growth
best_s="" best_l=""
for r in $(seq "$rounds"); do
    read -r ts rs < <(bench "$work/small.json")
    read -r tl rl < <(bench "$work/large.json")
    awk -v r="$r" -v ts="$ts" -v rs="$rs" -v tl="$tl" -v rl="$rl" 'BEGIN {
        printf "%-6s %12.6f %12d %12.6f %12d %8.2f\n", r, ts, rs, tl, rl, (tl / rl) / (ts / rs) }' | tee -a "$work/rounds"
    if [ -z "$best_s" ] || awk -v x="$ts" -v y="$best_s" 'BEGIN { exit !(x < y) }'; then best_s=$ts; fi
    if [ -z "$best_l" ] || awk -v x="$tl" -v y="$best_l" 'BEGIN { exit !(x < y) }'; then best_l=$tl; fi
done
awk -v ts="$best_s" -v rs="$rs" -v tl="$best_l" -v rl="$rl" 'BEGIN {
    printf "growth per ray, fastest renders: %.2fx (%.6f s and %.6f s)\n", (tl / rl) / (ts / rs), ts, tl }'
sort -n -k6 "$work/rounds" | awk '{ g[NR] = $6 } END {
    m = (NR % 2) ? g[(NR + 1) / 2] : (g[NR / 2] + g[NR / 2 + 1]) / 2
    printf "growth per ray, median of %d rounds: %.2fx\n", NR, m }'

if [ "$instructions" = 1 ]; then
    command -v valgrind >/dev/null || { echo "bench-scaling: --instructions needs valgrind" >&2; exit 2; }
    # Instructions and rays of one single-threaded run at W x H.
    count() {
        local rays refs
        rays=$("$komplex" bench "$1" --width "$2" --height "$3" --threads 1 | awk 'NR == 2 { print $7 }')
        refs=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null \
            "$komplex" bench "$1" --width "$2" --height "$3" --threads 1 2>&1 >/dev/null |
            sed -n 's/.*I *refs: *\([0-9,]*\).*/\1/p' | tr -d ,)
        echo "$refs $rays"
    }
    per_ray() {
        read -r i1 r1 < <(count "$1" 160 120)
        read -r i2 r2 < <(count "$1" 320 240)
        awk -v i1="$i1" -v r1="$r1" -v i2="$i2" -v r2="$r2" 'BEGIN { printf "%.1f", (i2 - i1) / (r2 - r1) }'
    }
    s=$(per_ray "$work/small.json")
    l=$(per_ray "$work/large.json")
    awk -v s="$s" -v l="$l" -v a="$small" -v b="$large" 'BEGIN {
        printf "instructions per ray (callgrind, 320x240 minus 160x120, 1 thread): %s blocks %.0f, %s blocks %.0f: growth %.2fx\n", a, s, b, l, l / s }'
fi
