//! `komplex render --tile I/N` and `komplex merge`: the parts, read back by
//! the independent reader, are bands of the one-process render with the
//! whole image as their display window; merged, they are that render,
//! channel for channel (and byte for byte); `--tile auto/N` reads the
//! scheduler's index; `--resume` skips a complete part and only that.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::support::{komplex, komplex_env, komplex_ok, python, read_exr, scene, tempdir, text};

/// Renders `scene` with `args` in one process to `one.exr`, and as `n`
/// tiles (`img.tile-I-of-n.exr`), returning the one-process file and the
/// parts in tile order.
fn render_both(dir: &Path, scene: &Path, args: &[&str], n: u32) -> (PathBuf, Vec<PathBuf>) {
    let scene = scene.to_str().unwrap();
    komplex_ok(dir, &[&["render", scene, "-o", "one.exr"], args].concat());
    let parts = (0..n)
        .map(|i| {
            let tile = format!("{i}/{n}");
            let o = komplex_ok(dir, &[&["render", scene, "-o", "img.exr", "--tile", &tile], args].concat());
            let part = dir.join(format!("img.tile-{i}-of-{n}.exr"));
            assert!(String::from_utf8_lossy(&o.stderr).contains(&format!("tile {tile}")), "{}", text(&o));
            assert!(part.is_file(), "{} was not written", part.display());
            part
        })
        .collect();
    assert!(!dir.join("img.exr").exists(), "a tiled render wrote the whole image's name");
    (dir.join("one.exr"), parts)
}

/// Merges `parts` (in reverse order: the order given does not matter) into
/// `merged.exr`.
fn merge(dir: &Path, parts: &[PathBuf]) -> PathBuf {
    let mut args = vec!["merge".to_string()];
    args.extend(parts.iter().rev().map(|p| p.to_str().unwrap().to_string()));
    args.extend(["-o".into(), "merged.exr".into()]);
    komplex_ok(dir, &args.iter().map(String::as_str).collect::<Vec<_>>());
    dir.join("merged.exr")
}

/// The part's header and samples as the independent reader (Python's
/// OpenEXR) sees them; `None` where it is not installed (not under CI).
fn read_raw(path: &Path) -> Option<serde_json::Value> {
    let out = python("read_exr.py", &[path])?;
    Some(serde_json::from_slice(&out.stdout).unwrap())
}

/// Renders whole and in `n` tiles, checks every part against the rows of
/// the whole image and the merge against the whole image, channel for
/// channel, both read by the independent reader; returns the channel names.
fn check_merge(scene: &Path, args: &[&str], n: u32) -> Vec<String> {
    let dir = tempdir();
    let d = dir.path();
    let (one, parts) = render_both(d, scene, args, n);
    let merged = merge(d, &parts);
    // Equal byte for byte: the same channels, values and header.
    assert!(std::fs::read(&merged).unwrap() == std::fs::read(&one).unwrap(), "the merge differs from one.exr");
    let Some(whole) = read_exr(&one) else { return Vec::new() };
    let joined = read_exr(&merged).unwrap();
    assert_eq!((joined.width, joined.height), (whole.width, whole.height));
    assert_eq!(joined.channels.keys().collect::<Vec<_>>(), whole.channels.keys().collect::<Vec<_>>());
    for (name, c) in &whole.channels {
        assert_eq!(joined.channels[name].kind, c.kind, "channel {name}");
        // Bit for bit, NaN-free (compare as bits so that a NaN would count).
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(bits(&joined.channels[name].samples) == bits(&c.samples), "channel {name} differs");
    }
    let (w, h) = (whole.width, whole.height);
    let mut next_row = 0;
    for (i, part) in parts.iter().enumerate() {
        let raw = read_raw(part).unwrap();
        let first = i * h / n as usize;
        let end = (i + 1) * h / n as usize;
        assert_eq!(first, next_row, "the bands tile the image");
        next_row = end;
        assert_eq!(raw["display_window"], serde_json::json!([0, 0, w - 1, h - 1]), "{}", part.display());
        assert_eq!(raw["data_window"], serde_json::json!([0, first, w - 1, end - 1]), "{}", part.display());
        assert_eq!(raw["attributes"]["komplex.tile"], format!("{i}/{n}"));
        assert_eq!(raw["attributes"]["komplex.render"], read_raw(&parts[0]).unwrap()["attributes"]["komplex.render"]);
        for (name, c) in &whole.channels {
            let got = &raw["channels"][name];
            assert_eq!(got["type"], c.kind.as_str(), "{name}");
            let want = &c.samples[first * w..end * w];
            let got: Vec<f64> = got["samples"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| if v == "inf" { f64::INFINITY } else { v.as_f64().unwrap() })
                .collect();
            // serde_json's float parsing is not always correctly rounded in
            // f64; every sample is an f32 or smaller, so compare in f32.
            let f = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<_>>();
            assert!(
                f(&got) == f(want),
                "{} channel {name}: not rows {first}..{end} of the whole image",
                part.display()
            );
        }
    }
    assert_eq!(next_row, h);
    whole.channels.keys().cloned().collect()
}

/// 37 rows in four parts: rows 0, 9, 18 and 27 on, two of them odd, so
/// the 2×2 packets of a band fall on other pixels than in the whole image.
#[test]
fn four_tiles_of_the_whitted_grid_merge_into_the_one_process_render() {
    let names = check_merge(&scene("table.json"), &["--width", "40", "--height", "37", "--samples", "2"], 4);
    assert!(names.is_empty() || names.contains(&"id.block".to_string()));
}

#[test]
fn four_tiles_of_the_path_integrator_merge_into_the_one_process_render() {
    check_merge(&scene("cornell.json"), &["--width", "24", "--height", "19", "--spp", "4"], 4);
}

/// Adaptive sampling (the `spp` and `error` channels), half-float colour,
/// and 3 parts of 37 rows (12, 12 and 13).
#[test]
fn three_tiles_of_adaptive_sampling_in_half_floats_merge_into_the_one_process_render() {
    let args = ["--width", "20", "--height", "37", "--spp", "32", "--noise", "0.3", "--half"];
    let names = check_merge(&scene("cornell.json"), &args, 3);
    assert!(names.is_empty() || (names.contains(&"spp".to_string()) && names.contains(&"error".to_string())));
}

#[test]
fn one_tile_is_the_whole_image() {
    check_merge(&scene("table.json"), &["--width", "16", "--height", "5"], 1);
}

/// `--tile auto/N` renders the part a Slurm job array or a Kubernetes
/// Indexed Job names, Slurm's first when both are set.
#[test]
fn auto_takes_the_index_from_slurm_or_kubernetes() {
    let dir = tempdir();
    let d = dir.path();
    let table = scene("table.json");
    let args = ["render", table.to_str().unwrap(), "-o", "a.exr", "--width", "16", "--height", "12", "--tile"];
    for (env, want) in [
        (&[("SLURM_ARRAY_TASK_ID", "1")][..], 1),
        (&[("JOB_COMPLETION_INDEX", "2")][..], 2),
        (&[("SLURM_ARRAY_TASK_ID", "0"), ("JOB_COMPLETION_INDEX", "2")][..], 0),
    ] {
        let o = komplex_env(d, &[&args[..], &["auto/3"]].concat(), env);
        assert!(o.status.success(), "{}", text(&o));
        let part = d.join(format!("a.tile-{want}-of-3.exr"));
        let explicit = d.join("explicit.exr");
        komplex_ok(d, &[&args[..2], &["-o", "explicit.exr"], &args[4..8], &["--tile", &format!("{want}/3")]].concat());
        let explicit = explicit.with_file_name(format!("explicit.tile-{want}-of-3.exr"));
        assert!(std::fs::read(&part).unwrap() == std::fs::read(&explicit).unwrap(), "{env:?}");
        std::fs::remove_file(part).unwrap();
    }
}

/// `--resume` leaves a complete part alone (the same file, not a new one
/// renamed over it) and renders a truncated or foreign one again.
#[test]
fn resume_skips_a_complete_part_and_renders_a_broken_one_again() {
    let dir = tempdir();
    let d = dir.path();
    let table = scene("table.json");
    let run = || {
        let args = ["render", table.to_str().unwrap(), "-o", "r.exr", "--width", "16", "--height", "12"];
        komplex_ok(d, &[&args[..], &["--tile", "1/2", "--resume"]].concat())
    };
    let part = d.join("r.tile-1-of-2.exr");
    let o = run();
    assert!(!String::from_utf8_lossy(&o.stderr).contains("skipped"), "{}", text(&o));
    let good = std::fs::read(&part).unwrap();
    let inode = std::fs::metadata(&part).unwrap().ino();
    let o = run();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("r.tile-1-of-2.exr: tile 1/2 is already complete; skipped (--resume)"), "{err}");
    assert_eq!(std::fs::metadata(&part).unwrap().ino(), inode, "the complete part was written again");
    // Truncated: rendered again, the same bytes as before.
    std::fs::write(&part, &good[..good.len() / 2]).unwrap();
    let o = run();
    assert!(String::from_utf8_lossy(&o.stderr).contains("rendering tile 1/2 again (--resume)"), "{}", text(&o));
    assert!(std::fs::read(&part).unwrap() == good);
    // Another render's part (another seed), or another tile, in its place.
    let args = ["render", table.to_str().unwrap(), "-o", "s.exr", "--width", "16", "--height", "12", "--tile"];
    komplex_ok(d, &[&args[..], &["1/2", "--seed", "7"]].concat());
    komplex_ok(d, &[&args[..], &["0/2"]].concat());
    for other in ["s.tile-1-of-2.exr", "s.tile-0-of-2.exr"] {
        std::fs::copy(d.join(other), &part).unwrap();
        let o = run();
        assert!(String::from_utf8_lossy(&o.stderr).contains("rendering tile 1/2 again"), "{other}: {}", text(&o));
        assert!(std::fs::read(&part).unwrap() == good, "{other}");
    }
}

/// A merge that fails writes nothing, and names the file or the missing
/// tile (the messages themselves are cases of `errors.rs`).
#[test]
fn a_failed_merge_names_the_part_and_writes_nothing() {
    let dir = tempdir();
    let d = dir.path();
    let table = scene("table.json");
    let (_, parts) = render_both(d, &table, &["--width", "16", "--height", "12"], 3);
    let t = table.to_str().unwrap();
    komplex_ok(
        d,
        &["render", t, "-o", "other.exr", "--width", "16", "--height", "12", "--tile", "1/3", "--samples", "2"],
    );
    let p = |i: usize| parts[i].to_str().unwrap();
    for (args, needle) in [
        (vec![p(0), p(2)], "tile 1/3 is missing: none of the 2 parts given holds it (tile 1 would be"),
        (vec![p(0), p(1), p(1), p(2)], "img.tile-1-of-3.exr: tile 1/3 again"),
        (
            vec![p(0), "other.tile-1-of-3.exr", p(2)],
            "other.tile-1-of-3.exr: a foreign part: it is a tile of another render",
        ),
        (vec![p(0), p(1), p(2), "one.exr"], "one.exr: not a tile of a render"),
    ] {
        let o = komplex(d, &[&["merge"], &args[..], &["-o", "m.exr", "--png", "m.png"]].concat());
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(String::from_utf8_lossy(&o.stderr).contains(needle), "{needle}\n{}", text(&o));
        assert!(!d.join("m.exr").exists() && !d.join("m.png").exists());
    }
    // The same parts all given: the merge and its preview are written, the
    // preview that of the one-process render.
    komplex_ok(d, &["merge", p(0), p(1), p(2), "-o", "m.exr", "--png", "m.png", "--exposure", "1"]);
    komplex_ok(
        d,
        &["render", t, "-o", "one.exr", "--width", "16", "--height", "12", "--png", "one.png", "--exposure", "1"],
    );
    assert!(std::fs::read(d.join("m.png")).unwrap() == std::fs::read(d.join("one.png")).unwrap());
    assert!(std::fs::read(d.join("m.exr")).unwrap() == std::fs::read(d.join("one.exr")).unwrap());
}

/// The bytes of an EXR file made with the `exr` crate, as a broken or
/// foreign part would be: `layers` parts (named when more than one), each
/// the rows `rows` (first, end) of an image `size`, with zero `f32`
/// channels `names` and the text attributes `attributes` in its header.
pub(crate) fn crafted_part(
    size: (usize, usize),
    rows: (usize, usize),
    names: &[&str],
    attributes: &[(&str, &str)],
    layers: usize,
) -> Vec<u8> {
    use exr::prelude::*;
    let n = size.0 * (rows.1 - rows.0);
    let layer = |k: usize| {
        let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> =
            names.iter().map(|&c| AnyChannel::new(c, FlatSamples::F32(vec![0.0; n]))).collect();
        let attributes = LayerAttributes {
            layer_name: (layers > 1).then(|| Text::from(format!("layer{k}").as_str())),
            layer_position: Vec2(0, rows.0 as i32),
            other: attributes.iter().map(|&(k, v)| (Text::from(k), AttributeValue::Text(Text::from(v)))).collect(),
            ..LayerAttributes::default()
        };
        Layer::new((size.0, rows.1 - rows.0), attributes, Encoding::UNCOMPRESSED, AnyChannels::sort(channels))
    };
    let display = IntegerBounds::new(Vec2(0, 0), Vec2(size.0, size.1));
    let image = Image::from_layers(ImageAttributes::new(display), (0..layers).map(layer).collect::<Vec<_>>());
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).unwrap();
    bytes.into_inner()
}
