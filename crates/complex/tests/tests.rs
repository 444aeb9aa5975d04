//! The complex crate's one integration-test binary (see `Cargo.toml`).

mod alloc;
mod assembly;
mod batch;
mod bounds;
mod common;
mod furniture;
mod fuzz_regressions;
mod kernel;
mod large;
mod options;
mod oracle;
mod points;
mod secondary;
mod stress;
mod transparency;
mod volume;
