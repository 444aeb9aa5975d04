#!/usr/bin/env bash
# The keep-or-drop check of a speed change (docs/benchmarks.md, "Comparing
# two builds"): two komplex binaries, the one before a change and the one after,
# must render the same images, and the figure that decides is the change in
# render-only instructions, which (unlike time on a shared machine) repeats.
#
# Images: every scene (default: scenes/*.json, scenes/bench/*.json and the
# generated sphereflake-4 and grid-100) rendered by both binaries at WxH
# (default 200x150) three ways — plain, `--samples 2` and `--precision fast`
# — and the EXR files compared byte for byte with `cmp`. Each pair that
# differs is printed; the exit status is 1 if any does.
#
# --instructions: also the render-only instructions of each scene and
# binary, counted by valgrind's callgrind (needs valgrind): `komplex bench
# SCENE --width 320 --height 240 --threads 1 --runs 2` minus the same with
# `--runs 1`, so that parsing and building the scene cancel out; printed
# with the change in per cent. Minutes for the large scenes.
#
# Usage: scripts/compare-builds.sh [--width W] [--height H] [--instructions]
#            BEFORE AFTER [SCENE...]
# BEFORE, AFTER: paths of komplex binaries, e.g. a copy of
# target/release/komplex made before the change, and the new build.
set -euo pipefail
cd "$(dirname "$0")/.."

width=200 height=150 instructions=0 bins=() scenes=()
while [ $# -gt 0 ]; do
    case "$1" in
        --width) width="$2"; shift 2 ;;
        --height) height="$2"; shift 2 ;;
        --instructions) instructions=1; shift ;;
        -h|--help) sed -n '2,22p' "$0"; exit 0 ;;
        -*) echo "compare-builds: unknown option '$1' (see --help)" >&2; exit 2 ;;
        *) if [ ${#bins[@]} -lt 2 ]; then bins+=("$1"); else scenes+=("$1"); fi; shift ;;
    esac
done
if [ ${#bins[@]} -ne 2 ]; then
    echo "compare-builds: two binaries needed, BEFORE and AFTER (see --help)" >&2
    exit 2
fi
for b in "${bins[@]}"; do
    [ -x "$b" ] || { echo "compare-builds: '$b' is not an executable file" >&2; exit 2; }
done
if [ "$instructions" = 1 ] && ! command -v valgrind >/dev/null; then
    echo "compare-builds: --instructions needs valgrind (apt-get install valgrind)" >&2
    exit 2
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(scenes/*.json scenes/bench/*.json)
    "${bins[1]}" generate sphereflake --level 4 -o "$work/sphereflake-4.json"
    "${bins[1]}" generate grid --count 100 -o "$work/grid-100.json"
    scenes+=("$work/sphereflake-4.json" "$work/grid-100.json")
fi

compared=0 differ=0
for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .json)
    for mode in plain "--samples 2" "--precision fast"; do
        opts=()
        [ "$mode" = plain ] || read -r -a opts <<<"$mode"
        for k in 0 1; do
            if ! "${bins[$k]}" render "$scene" --width "$width" --height "$height" "${opts[@]}" \
                -o "$work/$k.exr" >"$work/render.log" 2>&1; then
                echo "compare-builds: ${bins[$k]} failed on $scene ($mode):" >&2
                cat "$work/render.log" >&2
                exit 1
            fi
        done
        compared=$((compared + 1))
        if ! cmp -s "$work/0.exr" "$work/1.exr"; then
            differ=$((differ + 1))
            echo "differs: $name ($mode)"
        fi
    done
done
echo "images: $differ of $compared renders differ (${width}x$height, plain, --samples 2, --precision fast)"

if [ "$instructions" = 1 ]; then
    count() { # binary scene runs -> instructions of the whole process
        valgrind --tool=callgrind --callgrind-out-file="$work/cg.out" \
            "$1" bench "$2" --width 320 --height 240 --threads 1 --runs "$3" >/dev/null 2>&1
        awk '/^(summary|totals):/ { print $2; exit }' "$work/cg.out"
    }
    printf '%-24s %16s %16s %9s\n' scene before after change
    for scene in "${scenes[@]}"; do
        read -r -a ir <<<"$(for b in "${bins[@]}"; do echo $(($(count "$b" "$scene" 2) - $(count "$b" "$scene" 1))); done | tr '\n' ' ')"
        awk -v n="$(basename "$scene" .json)" -v a="${ir[0]}" -v b="${ir[1]}" \
            'BEGIN { printf "%-24s %16d %16d %+8.2f%%\n", n, a, b, 100 * (b - a) / a }'
    done
    echo "(render-only instructions at 320x240, one thread: --runs 2 minus --runs 1, under callgrind)"
fi
[ "$differ" = 0 ]
