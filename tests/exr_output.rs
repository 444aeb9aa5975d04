//! Every scene renders through the CLI, and the EXR read back by an
//! independent reader has the promised layout, types and values.

use crate::support::{all_scenes, komplex_ok, read_exr, render_frame, tempdir, world, Exr};

const COLOUR: [&str; 4] = ["A", "B", "G", "R"];
const ALL: [&str; 10] = ["A", "B", "G", "N.X", "N.Y", "N.Z", "R", "Z", "id.block", "id.object"];

fn check_layout(exr: &Exr, colour_type: &str, w: usize, h: usize) {
    assert_eq!(exr.parts, 1);
    assert_eq!(exr.compression, "ZIP_COMPRESSION");
    assert_eq!(exr.storage, "scanlineimage");
    assert_eq!((exr.width, exr.height), (w, h));
    let names: Vec<&str> = exr.channels.keys().map(String::as_str).collect();
    assert_eq!(names, ALL);
    for (name, c) in &exr.channels {
        let want = match name.as_str() {
            n if COLOUR.contains(&n) => colour_type,
            "id.block" | "id.object" => "u32",
            _ => "f32",
        };
        assert_eq!(c.kind, want, "channel {name}");
        assert_eq!(c.samples.len(), w * h, "channel {name}");
    }
}

/// The laws every pixel obeys, whatever the scene. The AOVs come from the
/// ray through the pixel centre; with `centre_only` (Whitted, one ray a
/// pixel) the colour does too, so the coverage `A` is whether that ray hit.
fn check_values(exr: &Exr, blocks: usize, centre_only: bool) {
    for i in 0..exr.height {
        for j in 0..exr.width {
            let a = exr.at("A", i, j);
            let z = exr.at("Z", i, j);
            let n = [exr.at("N.X", i, j), exr.at("N.Y", i, j), exr.at("N.Z", i, j)];
            let (b, o) = (exr.at("id.block", i, j), exr.at("id.object", i, j));
            for c in ["R", "G", "B"] {
                let v = exr.at(c, i, j);
                assert!(v.is_finite() && v >= 0.0, "{c} at ({i},{j}) = {v}");
            }
            assert!((0.0..=1.0).contains(&a), "A at ({i},{j}) = {a}");
            if centre_only {
                assert_eq!(a, if b == 0.0 { 0.0 } else { 1.0 }, "A at ({i},{j})");
            }
            if b == 0.0 {
                assert_eq!(z, f64::INFINITY, "miss at ({i},{j}) has Z {z}");
                assert_eq!(n, [0.0; 3]);
                assert_eq!(o, 0.0);
            } else {
                assert!(z.is_finite() && z > 0.0, "hit at ({i},{j}) has Z {z}");
                let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-6, "normal at ({i},{j}) has length {len}");
                assert!(b >= 1.0 && b <= blocks as f64, "id.block {b}");
                assert!(o >= 1.0, "id.object {o}");
            }
        }
    }
}

#[test]
fn every_scene_renders_and_reads_back() {
    let dir = tempdir();
    let (w, h) = (48usize, 36usize);
    for scene in all_scenes() {
        let out = dir.path().join("out.exr");
        let png = dir.path().join("out.png");
        let (ws, hs) = (w.to_string(), h.to_string());
        let args = ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--png", png.to_str().unwrap()];
        // One sample a pixel (a scene may ask for more, e.g. dof.json), so
        // that a Whitted scene's coverage is 0 or 1 (`check_values`); a
        // path scene keeps its `spp` random samples.
        komplex_ok(dir.path(), &[&args[..], &["--width", &ws, "--height", &hs, "--samples", "1"]].concat());
        assert!(png.exists());
        let mut wd = world(&scene, Some((w as u32, h as u32)));
        wd.settings.samples = 1;
        let frame = render_frame(&wd);
        let hits = frame.pixels().filter(|p| p.block != 0).count();
        assert!(hits > w * h / 10, "{}: only {hits} pixels hit anything", scene.display());
        let Some(exr) = read_exr(&out) else { return };
        check_layout(&exr, "f32", w, h);
        check_values(&exr, wd.complex.blocks().len(), wd.settings.integrator.is_whitted());
        // The file holds exactly what the renderer computed.
        for (k, p) in frame.pixels().enumerate() {
            let (i, j) = (k / w, k % w);
            // serde_json's float parsing is not always correctly rounded in
            // f64; every sample is an f32, so compare in f32.
            let got = |c: &str| exr.at(c, i, j) as f32;
            assert_eq!([got("R"), got("G"), got("B")], p.rgb, "{} ({i},{j})", scene.display());
            assert_eq!(got("Z"), p.depth);
            assert_eq!([got("N.X"), got("N.Y"), got("N.Z")], p.normal);
            assert_eq!(
                (exr.at("id.block", i, j), exr.at("id.object", i, j)),
                (f64::from(p.block), f64::from(p.object))
            );
        }
    }
}

#[test]
fn half_writes_f16_colour_and_f32_aovs() {
    let dir = tempdir();
    let scene = crate::support::scene("table.json");
    let out = dir.path().join("half.exr");
    komplex_ok(
        dir.path(),
        &["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--half", "--width", "32", "--height", "24"],
    );
    let Some(exr) = read_exr(&out) else { return };
    check_layout(&exr, "f16", 32, 24);
    let frame = render_frame(&world(&scene, Some((32, 24))));
    for (k, p) in frame.pixels().enumerate() {
        let r = exr.channels["R"].samples[k];
        let want = f64::from(p.rgb[0]);
        // f16 keeps 11 significant bits.
        assert!((r - want).abs() <= want.abs() * 1e-3 + 1e-7, "R {r} vs {want}");
    }
}

#[test]
fn a_frame_with_a_short_plane_is_an_error_and_writes_nothing() {
    let dir = tempdir();
    let scene = crate::support::scene("table.json");
    let mut frame = render_frame(&world(&scene, Some((8, 6))));
    frame.normal[1].pop();
    let out = dir.path().join("short.exr");
    let e = render::exr::write_exr(frame, &out, render::exr::ColorType::F32).unwrap_err();
    let text = e.to_string();
    assert!(text.contains("short.exr") && text.contains("every plane needs 48 samples"), "{text}");
    assert!(text.contains("47"), "{text}");
    assert!(!out.exists());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "a temporary file was left behind");
}

/// A colour-only frame (`Options::colour_only`: no AOV planes) is written
/// with `R G B A` alone, read back by the independent reader with the full
/// frame's colours.
#[test]
fn a_colour_only_frame_writes_rgba_alone() {
    let dir = tempdir();
    let w = world(&crate::support::scene("table.json"), Some((20, 14)));
    let options = render::frame::Options { threads: Some(2), colour_only: true, ..Default::default() };
    let (frame, _) = render::frame::render(&w, options, &|| {}).unwrap();
    let full = render_frame(&w);
    let out = dir.path().join("colour.exr");
    render::exr::write_exr(frame, &out, render::exr::ColorType::F32).unwrap();
    let Some(exr) = read_exr(&out) else { return };
    let names: Vec<&str> = exr.channels.keys().map(String::as_str).collect();
    assert_eq!(names, COLOUR);
    for (k, p) in full.pixels().enumerate() {
        let (i, j) = (k / 20, k % 20);
        for (c, want) in [("R", p.rgb[0]), ("G", p.rgb[1]), ("B", p.rgb[2]), ("A", p.alpha)] {
            assert_eq!(exr.at(c, i, j), f64::from(want), "{c} at ({i},{j})");
        }
    }
}
