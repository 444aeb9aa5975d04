#!/usr/bin/env bash
# Komplex vs POV-Ray 3.7 on the same scenes, the same image size and the
# same number of threads (docs/benchmarks.md). For each scene: `komplex export-pov`
# writes the POV-Ray version, POV-Ray renders it without anti-aliasing and
# reports its trace time on stderr, `komplex bench` renders the JSON scene
# once; the ratio is POV-Ray's trace time over ours (equal primary rays, so
# it is the ratio of primary rays per second). Parse and load times are
# excluded on both sides. The last two columns are the rays each traced
# (POV-Ray's rays and shadow-ray tests from its statistics, komplex's all
# rays), so a reader can see both did the same work.
#
# Usage: scripts/bench-vs-povray.sh [--width W] [--height H] [--threads N] [--runs R] [--precision MODE] [SCENE...]
# Each renderer renders each scene R times (default 3), alternating, and the
# fastest time of each is kept: single runs of a fraction of a second swing
# by tens of percent on a shared machine.
# A SCENE is a JSON file, or `sphereflake-L` / `grid-N` for a scene
# generated on the fly (`komplex generate`). Without scenes: the table, the
# glass scene, sphereflake levels 3 and 4 and the 1,000-block grid. POV-Ray
# takes minutes on larger grids (it tests every rotated box with every ray):
# run those at a smaller size, e.g. `--width 160 --height 120 grid-10000`.
# --precision: komplex's kernel mode (default `accurate`; `fast` evaluates in
# world space as POV-Ray does, see docs/accuracy.md for what it costs).
# KOMPLEX=path/to/komplex: measure that binary (no build).
set -euo pipefail
cd "$(dirname "$0")/.."

width=640 height=480 threads=1 runs=3 precision=accurate
scenes=()
while [ $# -gt 0 ]; do
    case "$1" in
        --width) width="$2"; shift 2 ;;
        --height) height="$2"; shift 2 ;;
        --threads) threads="$2"; shift 2 ;;
        --runs) runs="$2"; shift 2 ;;
        --precision) precision="$2"; shift 2 ;;
        -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
        *) scenes+=("$1"); shift ;;
    esac
done

command -v povray >/dev/null || { echo "povray is not installed (apt-get install povray)" >&2; exit 2; }
source scripts/komplex-bin.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(scenes/table.json scenes/glass.json scenes/bench/sphereflake-3.json sphereflake-4 scenes/bench/grid-1000.json)
fi
for i in "${!scenes[@]}"; do
    case "${scenes[$i]}" in
        sphereflake-[0-9]*)
            "$komplex" generate sphereflake --level "${scenes[$i]#sphereflake-}" -o "$work/${scenes[$i]}.json"
            scenes[$i]="$work/${scenes[$i]}.json" ;;
        grid-[0-9]*)
            "$komplex" generate grid --count "${scenes[$i]#grid-}" -o "$work/${scenes[$i]}.json"
            scenes[$i]="$work/${scenes[$i]}.json" ;;
    esac
done

printf '%-16s %8s %10s %10s %14s %14s %14s %8s %12s %12s\n' \
    scene blocks "pov s" "komplex s" "pov prim/s" "komplex prim/s" "komplex all/s" ratio "pov rays" "komplex rays"
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .json)
    "$komplex" export-pov "$scene" --width "$width" --height "$height" -o "$work/$name.pov"
    pov="" ours=""
    for _ in $(seq "$runs"); do
        # POV-Ray may only write next to its input: run it in the work directory.
        (cd "$work" && povray -A +FN -D -P "+W$width" "+H$height" "+WT$threads" "+I$name.pov" "+O$name.png") \
            2> "$work/$name.log" >/dev/null || { cat "$work/$name.log" >&2; exit 1; }
        p=$(sed -n 's/.*Trace Time:.*(\([0-9.]*\) seconds).*/\1/p' "$work/$name.log")
        # POV-Ray's rays (camera, reflected, refracted, transmitted) and
        # shadow-ray tests, which together are what komplex counts as all rays.
        pr=$(awk '/^Rays:/ { r = $2 } /^Shadow Ray Tests:/ { s = $4 } END { print r + s }' "$work/$name.log")
        # The data line of `komplex bench`: blocks in column 2, all rays in 7,
        # primary rays/s in 8, all rays/s in 9. The render time is taken as
        # pixels over primary rays/s, which keeps the digits that column 5
        # (render seconds to the millisecond) rounds away on small images.
        read -r blocks o kr a < <("$komplex" bench "$scene" --width "$width" --height "$height" --threads "$threads" \
            --precision "$precision" | awk -v px=$((width * height)) 'NR == 2 { printf "%s %.9f %s %s\n", $2, px / $8, $7, $9 }')
        if [ -z "$pov" ] || awk -v x="$p" -v y="$pov" 'BEGIN { exit !(x < y) }'; then pov=$p; fi
        if [ -z "$ours" ] || awk -v x="$o" -v y="$ours" 'BEGIN { exit !(x < y) }'; then ours=$o all=$a; fi
    done
    awk -v n="$name" -v b="$blocks" -v p="$pov" -v o="$ours" -v a="$all" -v pr="$pr" -v kr="$kr" -v px=$((width * height)) 'BEGIN { if (p <= 0) p = 0.001
        printf "%-16s %8d %10.3f %10.3f %14.0f %14.0f %14.0f %8.2f %12d %12d\n", n, b, p, o, px / p, px / o, a, p / o, pr, kr }'
done
echo "($width x $height, $threads thread(s), komplex --precision $precision, fastest of $runs runs each; ratio = POV-Ray trace time / komplex render time, > 1: komplex is faster;"
echo " rays: POV-Ray's rays plus its shadow-ray tests, and komplex's camera, shadow and secondary rays, per render: the work each did)"
