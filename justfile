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

fmt:
    cargo fmt --all

lint:
    cargo clippy --workspace --all-targets -- -D warnings
