#!/usr/bin/env bash
# A profile-guided (PGO) release build of komplex: optional, for users who
# want the last few percent (docs/benchmarks.md, "Profile-guided build").
# Three steps: an instrumented build renders the committed scenes and two
# generated grids (the profile: which branches are taken, which calls are
# hot), llvm-profdata merges what it recorded, and a second build uses it to
# lay out and inline the code. The arithmetic is the same, so the images
# are byte for byte those of `cargo build --release` (--verify checks).
#
# Usage: scripts/build-pgo.sh [--verify]
# The binary: $CARGO_TARGET_DIR/pgo/release/komplex (target/ by default);
# the normal release build in target/release is not touched.
# --verify: also builds the normal release binary and fails unless both
# render every scene to identical EXR files (scripts/compare-builds.sh).
#
# Needs an llvm-profdata that reads the raw profiles of rustc's LLVM:
# LLVM_PROFDATA=path, else rustup's (`rustup component add llvm-tools`),
# else the newest llvm-profdata-NN on PATH (Debian: apt-get install
# llvm-19 reads the profiles of rustc 1.95's LLVM 22).
set -euo pipefail
cd "$(dirname "$0")/.."

verify=0
case "${1:-}" in
    "") ;;
    --verify) verify=1 ;;
    -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
    *) echo "build-pgo: unknown argument '$1' (see --help)" >&2; exit 2 ;;
esac

profdata="${LLVM_PROFDATA:-}"
if [ -z "$profdata" ]; then
    host=$(rustc -vV | sed -n 's/^host: //p')
    candidate="$(rustc --print sysroot)/lib/rustlib/$host/bin/llvm-profdata"
    if [ -x "$candidate" ]; then
        profdata=$candidate
    else
        profdata=$(compgen -c llvm-profdata- | sort -t- -k3 -n | tail -n 1 || true)
    fi
fi
if [ -z "$profdata" ] || ! command -v "$profdata" >/dev/null; then
    echo "build-pgo: no llvm-profdata found: set LLVM_PROFDATA, or run 'rustup component add llvm-tools'," >&2
    echo "  or install one (Debian: apt-get install llvm-19)" >&2
    exit 2
fi

target="${CARGO_TARGET_DIR:-target}"
data="$target/pgo-profile"
rm -rf "$data"
mkdir -p "$data"
data=$(cd "$data" && pwd)
# RUSTFLAGS replaces the flags of .cargo/config.toml, so they are asked for again.
base=""
if [ "$(uname -m)" = x86_64 ]; then base="-C target-feature=+fma,+popcnt"; fi

echo "== instrumented build ($target/pgo-gen)"
RUSTFLAGS="$base -C profile-generate=$data" CARGO_TARGET_DIR="$target/pgo-gen" \
    cargo build --release --quiet --bin komplex
gen="$target/pgo-gen/release/komplex"

echo "== training renders"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$gen" generate grid --count 100 -o "$work/grid-100.json"
"$gen" generate grid --count 100000 -o "$work/grid-100000.json"
# The default precision only: a profile that also ran `--precision
# certified` made the default renders 2–3 % slower than this one.
for scene in scenes/*.json scenes/bench/*.json "$work/grid-100000.json"; do
    "$gen" bench "$scene" --width 320 --height 240 --threads 1 >/dev/null
done

echo "== merge ($profdata)"
# A raw profile this llvm-profdata cannot read is only a warning: make it an error.
if ! "$profdata" merge -o "$data/merged.profdata" "$data"/*.profraw 2>"$work/merge.log" ||
    grep -q . "$work/merge.log"; then
    cat "$work/merge.log" >&2
    echo "build-pgo: $profdata cannot read rustc's profiles (its LLVM is older than rustc's: $(rustc -vV | sed -n 's/^LLVM version: //p'))" >&2
    exit 1
fi

echo "== optimised build ($target/pgo)"
RUSTFLAGS="$base -C profile-use=$data/merged.profdata" CARGO_TARGET_DIR="$target/pgo" \
    cargo build --release --quiet --bin komplex
echo "$target/pgo/release/komplex"

if [ "$verify" = 1 ]; then
    echo "== verify: the same images as the normal release build"
    cargo build --release --quiet --bin komplex
    # Every committed and generated bench scene, plain, `--samples 2` and
    # `--precision fast`, compared byte for byte (fails if any differ).
    bash scripts/compare-builds.sh --width 160 --height 120 "$target/release/komplex" "$target/pgo/release/komplex"
fi
