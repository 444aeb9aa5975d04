# Sourced by the benchmark scripts (from the repository root): sets
# `komplex` to $KOMPLEX if given (measure that binary, no build), else
# builds this checkout's release binary and points at it.
if [ -n "${KOMPLEX:-}" ]; then
    komplex="$KOMPLEX"
else
    cargo build --release --quiet
    komplex="${CARGO_TARGET_DIR:-target}/release/komplex"
fi
