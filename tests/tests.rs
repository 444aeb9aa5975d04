//! End-to-end tests of the `komplex` binary (one test binary, topic modules).
#![allow(clippy::unwrap_used)]

mod geom;
mod support;

mod bench;
mod camera;
mod cli;
mod errors;
mod exr_output;
mod shading;
mod trace;

mod pov;
