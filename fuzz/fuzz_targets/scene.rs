//! Scene files: arbitrary bytes through the scene loader (text → `SceneFile`
//! → `World` with its `Complex`), seeded from `scenes/*.json` and steered by
//! the JSON dictionary `fuzz/scene.dict`. Checks: no panic; an error has a
//! non-empty message and names its place (a parse error its line and column,
//! a semantic error its JSON path, with a line and column inside the text
//! when given); `SceneFile::load_str` agrees with `from_json` + `to_world`;
//! a loaded world's camera gives finite unit rays through the four corner
//! pixels and the centre, `cast_ray` along them returns a finite hit beyond
//! ε, and shading them gives no NaN colour.
#![no_main]

use libfuzzer_sys::fuzz_target;
use quadric::Ray;
use render::format::SceneFile;
use render::shade::{Scratch, Shader};
use render::world::World;
use render::SceneError;

/// Bounces per shaded ray in this target: a scene may ask for up to 64, and
/// with both `reflect` and `transmit` set each bounce doubles the rays.
const FUZZ_MAX_DEPTH: u32 = 3;

fn check_error(e: &SceneError, text: &str) {
    let shown = e.to_string();
    assert!(!shown.is_empty(), "empty error message for {e:?}");
    match e {
        SceneError::Parse { line, column, message, .. } => {
            assert!(!message.is_empty(), "empty parse message: {shown}");
            assert!(*line >= 1, "parse error without a line: {shown}");
            // serde_json counts columns from 1, and 0 only at a line's start (EOF on an empty line).
            let lines = text.split('\n').count();
            assert!(*line <= lines, "line {line} past the end ({lines} lines): {shown}");
            assert!(shown.contains(&format!("line {line}, column {column}")), "{shown}");
        }
        SceneError::Semantic { place, position, message } => {
            assert!(!message.is_empty(), "empty message: {shown}");
            assert!(!place.is_empty(), "semantic error without a place: {shown}");
            assert!(shown.starts_with(place.as_str()), "{shown}");
            if let Some((line, column)) = position {
                let lines: Vec<&str> = text.split('\n').collect();
                assert!(*line >= 1 && *line <= lines.len(), "line {line} of {}: {shown}", lines.len());
                let width = lines[line - 1].chars().count();
                assert!(*column >= 1 && *column <= width, "column {column} of {width}: {shown}");
            }
        }
    }
}

fn check_ray(ray: &Ray, what: &str) {
    let (o, d) = (ray.origin(), ray.direction());
    assert!(o.iter().all(|x| x.is_finite()), "{what}: origin {o:?}");
    assert!(d.iter().all(|x| x.is_finite()) && (d.norm() - 1.0).abs() < 1e-9, "{what}: direction {d:?}");
}

fn check_world(world: &mut World) {
    let camera = world.camera;
    let (w, h) = (camera.width(), camera.height());
    let pixels = [(0, 0), (0, w - 1), (h - 1, 0), (h - 1, w - 1), (h / 2, w / 2)];
    let eps = world.complex.epsilon();
    assert!(eps.is_finite() && eps >= 0.0, "epsilon {eps}");
    for (i, j) in pixels {
        let ray = camera.ray(i, j);
        check_ray(&ray, &format!("pixel ({i}, {j})"));
        if let Some(hit) = world.complex.cast_ray(&ray, f64::INFINITY) {
            assert!(hit.t.is_finite() && hit.t > eps, "pixel ({i}, {j}): t = {} (ε = {eps})", hit.t);
            assert!(hit.point.iter().all(|x| x.is_finite()), "pixel ({i}, {j}): point {:?}", hit.point);
            assert!(hit.normal.iter().all(|x| x.is_finite()), "pixel ({i}, {j}): normal {:?}", hit.normal);
            assert!(hit.block.index() < world.complex.len());
        }
    }
    world.settings.max_depth = world.settings.max_depth.min(FUZZ_MAX_DEPTH);
    let shader = Shader::new(world);
    let mut scratch = Scratch::default();
    for (i, j) in pixels {
        let (colour, hit) = shader.primary(&camera.ray(i, j), &mut scratch);
        assert!(!colour.iter().any(|c| c.is_nan()), "pixel ({i}, {j}): colour {colour:?}");
        if let Some(s) = hit {
            assert!(s.t.is_finite() && s.normal.iter().all(|x| x.is_finite()), "pixel ({i}, {j}): {s:?}");
        }
    }
}

fuzz_target!(|data: &[u8]| {
    // Invalid UTF-8 is replaced, as `render::load` reports it before parsing.
    let text = String::from_utf8_lossy(data);
    let loaded = SceneFile::load_str(&text);
    let parsed = SceneFile::from_json(&text);
    match (&parsed, &loaded) {
        (Err(e), Err(l)) => {
            assert_eq!(e, l, "load_str and from_json disagree");
            check_error(e, &text);
        }
        (Err(e), Ok(_)) => panic!("from_json fails ({e}) but load_str succeeds"),
        (Ok(scene), _) => match (scene.to_world(), loaded) {
            (Ok(_), Ok(mut world)) => check_world(&mut world),
            (Err(_), Err(l)) => check_error(&l, &text),
            (a, b) => panic!("to_world and load_str disagree: {:?} vs {:?}", a.err(), b.err()),
        },
    }
});
