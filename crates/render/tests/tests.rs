//! Integration tests of `render` (one test binary, topic modules).
#![allow(clippy::unwrap_used)]

mod module_graph;
mod openmc;
mod openmc_oracle;
