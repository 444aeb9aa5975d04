# Komplex task runner (https://github.com/casey/just). Every recipe is a plain
# cargo command, so nothing here is required to build or test.

default: test

# Run every test (the README's command).
test:
    cargo test --workspace

# What CI runs.
ci:
    bash .ci/run

# Komplex vs POV-Ray 3.7 (needs povray): primary rays/s of both and the ratio.
# Pass options through, e.g. `just bench-pov --threads 2 --width 320 --height 240`.
bench-pov *ARGS:
    bash scripts/bench-vs-povray.sh {{ARGS}}

# Per-ray cost from the 100-block to the 100,000-block grid, in
# alternating rounds; `--instructions` adds callgrind's count (needs valgrind).
bench-scaling *ARGS:
    bash scripts/bench-scaling.sh {{ARGS}}

# Tiles against one process: the sum of the tiles' render times, the rays,
# the merge's time (default: the table at 3840x2160 in 4 tiles, 2 threads).
bench-tiles *ARGS:
    bash scripts/bench-tiles.sh {{ARGS}}

# The keep-or-drop check of a speed change: two komplex binaries (before,
# after) render every scene to identical EXR files; `--instructions` adds
# callgrind's render-only instruction counts. See the script's --help.
compare-builds *ARGS:
    bash scripts/compare-builds.sh {{ARGS}}

# A profile-guided release build in target/pgo/release/komplex (needs
# llvm-profdata; see the script). `--verify` checks its images are identical.
build-pgo *ARGS:
    bash scripts/build-pgo.sh {{ARGS}}

# Mutation testing of the numeric core (needs `cargo install cargo-mutants`):
# every mutant of the compensated primitives (roots.rs), the lane arithmetic
# and the normals must be caught by a test or be listed, with the reason, as
# equivalent in .cargo/mutants.toml. About 25 s a mutant on two cores (181
# mutants); survivors are listed in mutants.out/missed.txt.
mutants *ARGS:
    cargo mutants -p quadric --file crates/quadric/src/roots.rs --file crates/quadric/src/lanes.rs --file crates/quadric/src/normal.rs {{ARGS}}

fmt:
    cargo fmt --all

lint:
    cargo clippy --workspace --all-targets -- -D warnings

# Fuzz the kernel: each cargo-fuzz target for `seconds` (default 30), on
# stable Rust (`cargo install cargo-fuzz`; no nightly: `--sanitizer none`),
# with debug assertions, from the committed seeds (regenerated first) and
# the kept crash inputs of fuzz/regressions/<target>/ (replayed first). A
# crash stops the recipe and leaves its input in fuzz/artifacts/<target>/.
# RUSTFLAGS replaces .cargo/config.toml's flags, so FMA and POPCNT are asked for again.
fuzz-kernel seconds="30":
    cargo run --quiet --manifest-path fuzz/Cargo.toml --example seeds
    for t in quadric_intervals complex_queries; do \
        mkdir -p fuzz/corpus/$t && \
        RUSTFLAGS="{{ if arch() == "x86_64" { "-Ctarget-feature=+fma,+popcnt" } else { "" } }}" \
        cargo fuzz run --sanitizer none --debug-assertions $t fuzz/corpus/$t fuzz/seeds/$t \
            $(test -d fuzz/regressions/$t && echo fuzz/regressions/$t) -- \
            -max_total_time={{ seconds }} -print_final_stats=1 || exit 1; \
    done

# Fuzz scene loading (`fuzz/fuzz_targets/scene.rs`): arbitrary bytes through
# text -> SceneFile -> World, then camera rays, `cast_ray` and shading; same
# flags as fuzz-kernel, plus the JSON dictionary fuzz/scene.dict. The seeds
# are scenes/*.json (copied in first) and the committed fuzz/seeds/scene/.
fuzz-scene seconds="60":
    cp scenes/*.json fuzz/seeds/scene/
    mkdir -p fuzz/corpus/scene
    RUSTFLAGS="{{ if arch() == "x86_64" { "-Ctarget-feature=+fma,+popcnt" } else { "" } }}" \
    cargo fuzz run --sanitizer none --debug-assertions scene fuzz/corpus/scene fuzz/seeds/scene -- \
        -dict=fuzz/scene.dict -max_total_time={{ seconds }} -print_final_stats=1

# Every fuzz target, `seconds` each (the documented run: 60).
fuzz seconds="60": (fuzz-kernel seconds) (fuzz-scene seconds)
