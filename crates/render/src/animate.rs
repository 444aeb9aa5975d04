//! Animation (docs/model.md §6.1): the scene document at a frame number,
//! every keyed value replaced by its value there (`SceneFile::at_frame`),
//! and a scene read once for the frames of a render ([`Animation`]).
//! Everything after the document (the world, the kernel, the render) sees
//! a static scene.

use std::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use crate::convert::read_text;
use crate::error::{Error, SceneError};
use crate::format::{CameraSpec, Entry, SceneFile, Step};
use crate::keys::{slerp, Animated, Segment};
use crate::world::{Triple, World};

impl SceneFile {
    /// Whether any value of the scene is keyed.
    pub fn is_animated(&self) -> bool {
        let c = &self.camera;
        c.eye.is_keyed()
            || c.direction.is_keyed()
            || c.up.is_keyed()
            || c.focus_distance.as_ref().is_some_and(Animated::is_keyed)
            || self.blocks.iter().any(entry_is_animated)
            || self.definitions.values().flat_map(|d| &d.blocks).any(entry_is_animated)
    }

    /// The static document at `frame`: each keyed value at that frame (held
    /// before its first key and after its last, linear between two keys;
    /// the camera's `direction` and `up` turn spherically), no `animation`.
    /// A static document comes back unchanged but for `animation`.
    ///
    /// ```
    /// use render::format::SceneFile;
    /// let text = r#"{ "camera": { "eye": { "keys": [ { "frame": 1, "value": [0, 0, 4] },
    ///                                                { "frame": 3, "value": [2, 0, 4] } ] },
    ///                             "direction": [0, 0, -1] },
    ///                 "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#;
    /// let scene = SceneFile::from_json(text).unwrap();
    /// let world = scene.at_frame(2.0).unwrap().to_world().unwrap();
    /// assert_eq!(world.camera.eye().coords.as_slice(), [1.0, 0.0, 4.0]);
    /// ```
    pub fn at_frame(&self, frame: f64) -> Result<SceneFile, SceneError> {
        let mut scene = self.clone();
        scene.resolve(frame)?;
        Ok(scene)
    }

    /// [`SceneFile::at_frame`] in place.
    fn resolve(&mut self, frame: f64) -> Result<(), SceneError> {
        self.animation = None;
        resolve_camera(&mut self.camera, frame)?;
        for entry in self.blocks.iter_mut().chain(self.definitions.values_mut().flat_map(|d| &mut d.blocks)) {
            resolve_entry(entry, frame);
        }
        Ok(())
    }
}

fn steps_are_animated(steps: &[Step]) -> bool {
    steps.iter().any(|s| matches!(s, Step::Keyed(_)))
}

fn entry_is_animated(e: &Entry) -> bool {
    steps_are_animated(&e.transform)
        || e.objects.iter().flatten().any(|o| steps_are_animated(&o.transform))
        || e.blocks.iter().flatten().any(entry_is_animated)
}

fn resolve_steps(steps: &mut [Step], frame: f64) {
    for step in steps {
        if let Step::Keyed(k) = step {
            *step = k.at(frame);
        }
    }
}

// Recursion is bounded: the JSON reader refuses more than 128 levels of
// brackets (about 60 nested groups).
fn resolve_entry(e: &mut Entry, frame: f64) {
    resolve_steps(&mut e.transform, frame);
    for o in e.objects.iter_mut().flatten() {
        resolve_steps(&mut o.transform, frame);
    }
    for inner in e.blocks.iter_mut().flatten() {
        resolve_entry(inner, frame);
    }
}

fn resolve_camera(c: &mut CameraSpec, frame: f64) -> Result<(), SceneError> {
    c.eye = Animated::Fixed(c.eye.at(frame));
    c.direction = Animated::Fixed(turned(&c.direction, frame, "camera.direction", "direction")?);
    c.up = Animated::Fixed(turned(&c.up, frame, "camera.up", "up vector")?);
    if let Some(f) = &mut c.focus_distance {
        *f = Animated::Fixed(f.at(frame));
    }
    Ok(())
}

/// A keyed direction at `frame`: spherical interpolation between two keys
/// (the camera turns at a constant rate), which needs both non-zero and
/// not opposite. `place` names the value, `what` it in a message.
fn turned(v: &Animated<Triple>, frame: f64, place: &str, what: &str) -> Result<Triple, SceneError> {
    let keys = match v {
        Animated::Fixed(t) => return Ok(*t),
        Animated::Keyed(k) => k,
    };
    match keys.segment(frame) {
        Segment::Held(t) => Ok(*t),
        Segment::Between { from, to, t, index } => slerp(from, to, t).ok_or_else(|| {
            let zero = |v: &Triple| !v.iter().all(|x| x.is_finite()) || v.iter().all(|x| *x == 0.0);
            let (at, msg) = if zero(from) || zero(to) {
                let i = if zero(from) { index - 1 } else { index };
                (i, format!("the {what} is zero or not finite, so the frames next to this key have no direction"))
            } else {
                let msg = format!(
                    "keys {} and {index} point in opposite directions: the turn between them could go any way; \
                     add a key in between",
                    index - 1
                );
                (index, msg)
            };
            SceneError::semantic(&format!("{place}.keys[{at}]"), msg)
        }),
    }
}

/// A scene file read once, for rendering any of its frames.
#[derive(Debug)]
pub struct Animation {
    file: PathBuf,
    text: String,
    scene: SceneFile,
    animated: bool,
}

impl Animation {
    /// Reads and parses the scene file (not yet converted: errors that
    /// depend on the frame come from [`Animation::world_at`]).
    pub fn read(path: &Path) -> Result<Self, Error> {
        let text = read_text(path)?;
        let scene = SceneFile::from_json(&text).map_err(|source| Error::Scene { file: path.to_path_buf(), source })?;
        let animated = scene.is_animated();
        Ok(Animation { file: path.to_path_buf(), text, scene, animated })
    }

    /// The scene's `animation.frames`, if it has them.
    pub fn frames(&self) -> Option<RangeInclusive<u32>> {
        self.scene.animation.as_ref().map(|a| a.frames[0]..=a.frames[1])
    }

    /// Whether any value of the scene is keyed.
    pub fn is_animated(&self) -> bool {
        self.animated
    }

    /// The world at `frame`. An error names the frame (`at frame 7: ...`)
    /// besides its place.
    pub fn world_at(&self, frame: u32) -> Result<World, Error> {
        let located = |e: SceneError| Error::Scene {
            file: self.file.clone(),
            source: e.located(&self.text).with_owner(&format!("at frame {frame}")),
        };
        if !self.animated {
            // Nothing to resolve: no copy of the document.
            return self.scene.world_parts().and_then(|p| p.build()).map_err(located);
        }
        let scene = self.scene.at_frame(f64::from(frame)).map_err(located)?;
        let parts = scene.world_parts().map_err(located)?;
        // As `SceneFile::load_str` does: the copy goes before the build.
        drop(scene);
        parts.build().map_err(located)
    }
}

/// Reads `--frames A..B`: the first and the last frame, both rendered.
///
/// ```
/// assert_eq!(render::animate::parse_frames("1..24").unwrap(), 1..=24);
/// assert!(render::animate::parse_frames("24..1").is_err());
/// ```
pub fn parse_frames(text: &str) -> Result<RangeInclusive<u32>, Error> {
    let bad = || {
        Error::Options(format!(
            "--frames {text:?}: expected A..B, the first and the last frame (both rendered), \
             each a whole number from 0 to 4294967295"
        ))
    };
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?);
    if a > b {
        return Err(Error::Options(format!("--frames {a}..{b}: the first frame comes after the last")));
    }
    Ok(a..=b)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::format::Scale;

    fn scene(camera: &str, transform: &str) -> SceneFile {
        let text = format!(
            r#"{{ "camera": {{ {camera} }},
                 "blocks": [ {{ "group": "g", "transform": [ {transform} ],
                                "blocks": [ {{ "objects": [ {{ "sphere": {{}}, "transform": [ {transform} ] }} ] }} ] }} ] }}"#
        );
        SceneFile::from_json(&text).unwrap()
    }

    const CAMERA: &str = r#""eye": [0, 0, 5], "direction": [0, 0, -1]"#;

    fn steps(s: &SceneFile) -> [Vec<Step>; 2] {
        let group = &s.blocks[0];
        let object = &group.blocks.as_ref().unwrap()[0].objects.as_ref().unwrap()[0];
        [group.transform.clone(), object.transform.clone()]
    }

    #[test]
    fn keyed_steps_become_plain_steps_at_the_frame() {
        let s = scene(
            CAMERA,
            r#"{ "translate": { "keys": [ { "frame": 1, "value": [0, 0, 0] }, { "frame": 5, "value": [4, -8, 2] } ] } },
               { "rotate_y": { "keys": [ { "frame": 1, "value": 0 }, { "frame": 3, "value": 90 } ] } },
               { "scale": { "keys": [ { "frame": 2, "value": 1 }, { "frame": 4, "value": [3, 1, 2] } ] } },
               { "rotate_z": 30 }"#,
        );
        assert!(s.is_animated());
        // Keyed steps are written back as they are read.
        let text = serde_json::to_string(&s).unwrap();
        assert!(
            text.contains(r#"{"rotate_y":{"keys":[{"frame":1.0,"value":0.0},{"frame":3.0,"value":90.0}]}}"#),
            "{text}"
        );
        assert_eq!(serde_json::to_string(&SceneFile::from_json(&text).unwrap()).unwrap(), text);
        for (frame, translate, angle, scale) in [
            (0.0, [0.0, 0.0, 0.0], 0.0, [1.0, 1.0, 1.0]),
            (2.0, [1.0, -2.0, 0.5], 45.0, [1.0, 1.0, 1.0]),
            (3.0, [2.0, -4.0, 1.0], 90.0, [2.0, 1.0, 1.5]),
            (9.0, [4.0, -8.0, 2.0], 90.0, [3.0, 1.0, 2.0]),
        ] {
            let at = s.at_frame(frame).unwrap();
            assert!(!at.is_animated());
            for list in steps(&at) {
                assert!(matches!(list[0], Step::Translate(v) if v == translate), "{frame}: {:?}", list[0]);
                assert!(matches!(list[1], Step::RotateY(d) if d == angle), "{frame}: {:?}", list[1]);
                assert!(matches!(&list[2], Step::Scale(s) if s.per_axis() == scale), "{frame}: {:?}", list[2]);
                assert!(matches!(list[3], Step::RotateZ(d) if d == 30.0));
            }
        }
        // Uniform keys stay uniform.
        let s = scene(CAMERA, r#"{ "scale": { "keys": [ { "frame": 0, "value": 1 }, { "frame": 4, "value": 3 } ] } }"#);
        assert!(matches!(steps(&s.at_frame(1.0).unwrap())[0][0], Step::Scale(Scale::Uniform(x)) if x == 1.5));
    }

    #[test]
    fn the_camera_moves_linearly_and_turns_spherically() {
        let s = scene(
            r#""eye": { "keys": [ { "frame": 0, "value": [0, 0, 6] }, { "frame": 3, "value": [3, 0, 6] } ] },
               "direction": { "keys": [ { "frame": 0, "value": [0, 0, -1] }, { "frame": 3, "value": [2, 0, 0] } ] },
               "up": { "keys": [ { "frame": 0, "value": [0, 1, 0] }, { "frame": 3, "value": [-1, 0, 0] } ] },
               "focus_distance": { "keys": [ { "frame": 0, "value": 2 }, { "frame": 3, "value": 5 } ] }"#,
            "",
        );
        let c = s.at_frame(1.0).unwrap().camera;
        assert_eq!(*c.eye.first(), [1.0, 0.0, 6.0]);
        assert_eq!(*c.focus_distance.unwrap().first(), 3.0);
        // A third of the way from -z to +x is 30°; the length goes from 1 to 2.
        let d = *c.direction.first();
        let want = [0.5 * 4.0 / 3.0, 0.0, -(3f64.sqrt() / 2.0) * 4.0 / 3.0];
        assert!((0..3).all(|i| (d[i] - want[i]).abs() < 1e-15), "{d:?}");
        // +y to -x: 30° of the way is (-sin 30°, cos 30°, 0).
        let u = *c.up.first();
        assert!((u[0] + 0.5).abs() < 1e-15 && (u[1] - 3f64.sqrt() / 2.0).abs() < 1e-15 && u[2] == 0.0, "{u:?}");
        // On a key, the key's value exactly.
        assert_eq!(*s.at_frame(3.0).unwrap().camera.direction.first(), [2.0, 0.0, 0.0]);
    }

    #[test]
    fn opposite_or_zero_direction_keys_are_refused_between_them() {
        let cam = |keys: &str| scene(&format!(r#""eye": [0, 0, 5], "direction": {{ "keys": [ {keys} ] }}"#), "");
        let s = cam(r#"{ "frame": 0, "value": [0, 0, -1] }, { "frame": 2, "value": [0, 0, 3] }"#);
        let e = s.at_frame(1.0).unwrap_err().to_string();
        assert!(e.starts_with("camera.direction.keys[1]: keys 0 and 1 point in opposite directions"), "{e}");
        // On the keys themselves the direction is defined.
        assert!(s.at_frame(2.0).is_ok());
        let s = cam(r#"{ "frame": 0, "value": [0, 0, 0] }, { "frame": 2, "value": [0, 0, 3] }"#);
        let e = s.at_frame(1.0).unwrap_err().to_string();
        assert!(e.starts_with("camera.direction.keys[0]: the direction is zero"), "{e}");
    }

    #[test]
    fn a_static_scene_is_not_animated_and_resolves_to_itself() {
        let s = scene(CAMERA, r#"{ "translate": [1, 2, 3] }, { "matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]] }"#);
        assert!(!s.is_animated());
        let a = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::to_string(&s.at_frame(7.0).unwrap()).unwrap(), a);
    }

    #[test]
    fn frame_ranges_read_a_dot_dot_b() {
        assert_eq!(parse_frames("1..24").unwrap(), 1..=24);
        assert_eq!(parse_frames("0..0").unwrap(), 0..=0);
        assert_eq!(parse_frames("7..4294967295").unwrap(), 7..=u32::MAX);
        for bad in ["", "1", "1-3", "1...3", "..3", "1..", "a..b", "-1..3", "1..4294967296", " 1..3", "1..=3"] {
            let e = parse_frames(bad).unwrap_err().to_string();
            assert!(e.contains("expected A..B"), "{bad:?}: {e}");
        }
        let e = parse_frames("5..1").unwrap_err().to_string();
        assert_eq!(e, "--frames 5..1: the first frame comes after the last");
    }
}
