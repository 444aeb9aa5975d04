//! # render — Komplex scenes to images
//!
//! The edge of Komplex: the JSON scene format ([`format`](mod@format)) and
//! the world it converts into ([`world`], by [`load`] or
//! `SceneFile::to_world`), the camera of docs/model.md §4 ([`camera`]),
//! Whitted-style shading of docs/model.md §5 ([`shade`]), the parallel render loop
//! ([`frame`]) and the OpenEXR and PNG writers ([`exr`], [`png`]). The path
//! integrator of docs/model.md §5.10 is [`path`], built from [`sampling`]
//! (random numbers), [`warp`] (warps and their densities), [`bsdf`] (the
//! lobes) and [`lobes`] (a material as a sum of lobes). Only this
//! crate knows JSON and image formats; the kernel crates `quadric` and
//! `complex` stay plain geometry.
//!
//! ```
//! let text = r#"{
//!   "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 8, "height": 6 },
//!   "lights": [ { "position": [2, 2, 5] } ],
//!   "materials": { "red": { "diffuse": [1, 0, 0] } },
//!   "blocks": [ { "name": "ball", "material": "red", "objects": [ { "sphere": {} } ] } ]
//! }"#;
//! let world = render::format::SceneFile::from_json(text).unwrap().to_world().unwrap();
//! let (frame, _stats) = render::frame::render(&world, Default::default(), &|| {}).unwrap();
//! assert_eq!(frame.at(3, 4).block, 1); // the centre sees the ball
//! assert_eq!(frame.at(0, 0).block, 0); // a corner sees the background
//! ```
#![deny(missing_docs)]

pub mod animate;
pub mod bench;
pub mod bsdf;
pub mod camera;
pub mod check;
#[cfg(test)]
mod chi_square;
mod convert;
mod error;
pub mod exr;
mod flatten;
pub mod format;
pub mod frame;
pub mod generate;
pub mod keys;
pub mod limits;
pub mod lobes;
mod locate;
pub mod measure;
pub mod openmc;
pub mod output;
pub mod path;
pub mod png;
pub mod pov;
pub mod rays;
pub mod sampling;
pub mod shade;
pub mod slice;
pub mod texture;
pub mod tiles;
pub mod trace;
pub mod warp;
pub mod world;

/// The kernel's precision modes: `quadric`'s type, re-exported (one type, documented there).
#[doc(no_inline)]
pub use complex::Precision;
pub use convert::{load, load_timed, LoadTimes};
pub use error::{nearest, Error, SceneError};
