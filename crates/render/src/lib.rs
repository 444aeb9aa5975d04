//! # render — Komplex scenes to images
//!
//! The edge of Komplex: the JSON scene format ([`scene`]), the camera of
//! SPEC §4 ([`camera`]), Whitted-style shading of SPEC §5 ([`shade`]), the
//! parallel render loop ([`frame`]) and the OpenEXR and PNG writers
//! ([`exr`], [`png`]). Only this crate knows JSON and image formats; the
//! kernel crates `quadric` and `complex` stay plain geometry.
//!
//! ```
//! let text = r#"{
//!   "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 8, "height": 6 },
//!   "lights": [ { "position": [2, 2, 5] } ],
//!   "materials": { "red": { "diffuse": [1, 0, 0] } },
//!   "blocks": [ { "name": "ball", "material": "red", "objects": [ { "sphere": {} } ] } ]
//! }"#;
//! let world = render::scene::SceneFile::from_json(text).unwrap().to_world().unwrap();
//! let (frame, _stats) = render::frame::render(&world, Default::default(), &|| {}).unwrap();
//! assert_eq!(frame.at(3, 4).block, 1); // the centre sees the ball
//! assert_eq!(frame.at(0, 0).block, 0); // a corner sees the background
//! ```
#![deny(missing_docs)]

pub mod bench;
pub mod camera;
pub mod check;
mod error;
pub mod exr;
pub mod frame;
pub mod generate;
mod locate;
mod output;
pub mod png;
pub mod pov;
pub mod scene;
pub mod shade;
pub mod trace;

use std::path::Path;

pub use complex::Precision;
pub use error::{nearest, Error, SceneError};
pub use output::check_writable;

/// Reads and converts a scene file.
pub fn load(path: &Path) -> Result<scene::World, Error> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io { path: path.to_path_buf(), source })?;
    let scene_error = |source| Error::Scene { file: path.to_path_buf(), source };
    // Bad encoding is bad input (exit 1), located like a syntax error.
    let text = String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let valid = std::str::from_utf8(valid).unwrap_or_default();
        let line = valid.matches('\n').count() + 1;
        let column = valid.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        let byte = e.as_bytes()[e.utf8_error().valid_up_to()];
        let message = format!("the file is not UTF-8 (byte 0x{byte:02x})");
        scene_error(SceneError::Parse { path: String::new(), line, column, message })
    })?;
    scene::SceneFile::load_str(&text).map_err(scene_error)
}

/// The JSON Schema (draft-07) of the scene format, pretty-printed.
///
/// Generated from the serde types, plus the two rules the types cannot
/// express: an object has exactly one shape key, and a `blocks` entry is
/// either a block (`objects`) or a group (`group` and `blocks`).
pub fn schema_json() -> String {
    let schema = schemars::schema_for!(scene::SceneFile);
    let mut value = serde_json::to_value(&schema).unwrap_or_default();
    let one_of = |alternatives: &[&[&str]]| {
        serde_json::Value::Array(alternatives.iter().map(|keys| serde_json::json!({ "required": keys })).collect())
    };
    if let Some(defs) = value.get_mut("definitions").and_then(|d| d.as_object_mut()) {
        if let Some(obj) = defs.get_mut("ObjectSpec").and_then(|o| o.as_object_mut()) {
            let shapes: Vec<&[&str]> = vec![
                &["sphere"],
                &["cylinder"],
                &["cone"],
                &["paraboloid"],
                &["hyperboloid"],
                &["quadric"],
                &["halfspace"],
            ];
            obj.insert("oneOf".into(), one_of(&shapes));
        }
        if let Some(entry) = defs.get_mut("Entry").and_then(|o| o.as_object_mut()) {
            entry.insert("oneOf".into(), one_of(&[&["objects"], &["group", "blocks"]]));
        }
    }
    // Serialising a JSON value cannot fail.
    let mut s = serde_json::to_string_pretty(&value).unwrap_or_default();
    s.push('\n');
    s
}
