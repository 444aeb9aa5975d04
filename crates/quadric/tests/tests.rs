//! The quadric crate's integration tests, one binary; each topic lives in its own file.

mod fuzz_regressions;
