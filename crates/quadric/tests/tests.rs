//! The quadric crate's integration tests, one binary; each topic lives in its own file.

mod accuracy;
mod bad_input;
mod compensated;
mod fuzz_regressions;
mod laws;
mod oracle;
mod slab;
mod stress;
mod table;
