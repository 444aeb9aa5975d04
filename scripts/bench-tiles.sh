#!/usr/bin/env bash
# Tiles against one process (the goals in docs/benchmarks.md, "Tiles"): each
# round renders the scene in one process, then as N tiles one after the
# other (`render --tile I/N`), then merges the parts (`komplex merge`).
# Printed per round: the one-process render time and the sum of the tiles'
# render times (each the render loop's time from its summary line, loading
# and writing left out), their ratio, the rays cast by each (equal: the
# tiles cast exactly the one-process render's rays), and the merge's time.
# Then the medians over the rounds.
#
# Usage: scripts/bench-tiles.sh [--scene FILE] [--width W] [--height H]
#            [--threads N] [--tiles N] [--rounds R]
# Defaults: scenes/table.json at 3840x2160, 2 threads, 4 tiles, 3 rounds.
# KOMPLEX=path/to/komplex: measure that binary (no build).
set -euo pipefail
cd "$(dirname "$0")/.."

scene=scenes/table.json width=3840 height=2160 threads=2 tiles=4 rounds=3
while [ $# -gt 0 ]; do
    case "$1" in
        --scene) scene="$2"; shift 2 ;;
        --width) width="$2"; shift 2 ;;
        --height) height="$2"; shift 2 ;;
        --threads) threads="$2"; shift 2 ;;
        --tiles) tiles="$2"; shift 2 ;;
        --rounds) rounds="$2"; shift 2 ;;
        -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
        *) echo "bench-tiles: unknown argument '$1' (see --help)" >&2; exit 2 ;;
    esac
done
. scripts/komplex-bin.sh
komplex="$(realpath "$komplex")"
scene="$(realpath "$scene")"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
cd "$dir"

# The render loop's seconds and the rays from a render's summary line
# (`OUT: WxH[ tile I/N, rows A..B,] in T s, R rays, ...`).
seconds() { sed -n 's/.* in \([0-9.]*\) s, \([0-9]*\) rays.*/\1 \2/p'; }

echo "$(basename "$scene") ${width}x${height}, $threads threads, $tiles tiles, $rounds rounds ($komplex)"
size=(--width "$width" --height "$height" --threads "$threads")
for r in $(seq 1 "$rounds"); do
    read -r one one_rays < <("$komplex" render "$scene" -o one.exr "${size[@]}" 2>&1 | seconds)
    sum=0 rays=0
    for i in $(seq 0 $((tiles - 1))); do
        read -r t n < <("$komplex" render "$scene" -o part.exr "${size[@]}" --tile "$i/$tiles" 2>&1 | seconds)
        sum=$(awk -v a="$sum" -v b="$t" 'BEGIN { print a + b }')
        rays=$((rays + n))
    done
    merge=$("$komplex" merge part.tile-*-of-"$tiles".exr -o merged.exr 2>&1 | sed -n 's/.* in \([0-9.]*\) s$/\1/p')
    awk -v r="$r" -v one="$one" -v sum="$sum" -v a="$one_rays" -v b="$rays" -v m="$merge" 'BEGIN {
        printf "round %s: one process %.2f s, tiles %.2f s (ratio %.3f); rays %d and %d; merge %.2f s\n", r, one, sum, sum / one, a, b, m }'
    echo "$one $sum $merge" >> rounds.txt
done
awk '{ one[NR] = $1; sum[NR] = $2; ratio[NR] = $2 / $1; merge[NR] = $3 }
    function median(a, n,   i, j, t) {
        for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (a[j] < a[i]) { t = a[i]; a[i] = a[j]; a[j] = t }
        return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
    }
    END { printf "median: one process %.2f s, tiles %.2f s, ratio %.3f, merge %.2f s\n",
        median(one, NR), median(sum, NR), median(ratio, NR), median(merge, NR) }' rounds.txt
