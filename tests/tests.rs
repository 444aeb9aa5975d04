//! End-to-end tests of the `komplex` binary (one test binary, topic modules).
#![allow(clippy::unwrap_used)]

mod geom;
mod support;

mod anim;
mod bench;
mod camera;
mod cli;
mod determinism;
mod errors;
mod exr_output;
mod instances;
mod interrupt;
mod measure;
mod mutations;
mod openmc;
mod shading;
mod slice;
mod textures;
mod tiles;
mod trace;

mod path;
mod pov;
mod rays;
