//! `komplex render --tile I/N` and `komplex merge`: the parts, read back by
//! the independent reader, are bands of the one-process render with the
//! whole image as their display window; merged, they are that render,
//! channel for channel; `--tile auto/N` reads the scheduler's index;
//! `--resume` skips a complete part and only that.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::support::{komplex, komplex_env, komplex_ok, python, scene, tempdir, text};

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

/// The files' headers and samples as the independent reader (Python's
/// OpenEXR) sees them, in one run of it; `None` where it is not installed
/// (not under CI).
fn read_raw(paths: &[&Path]) -> Option<Vec<serde_json::Value>> {
    let out = python("read_exr.py", paths)?;
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    Some(if paths.len() == 1 { vec![v] } else { v.as_array().unwrap().clone() })
}

/// Every channel of an EXR file decoded by the `exr` crate: its name and
/// samples (as bits, type by type).
fn decoded(path: &Path) -> Vec<(String, Vec<u64>)> {
    use exr::prelude::*;
    let image = read().no_deep_data().largest_resolution_level().all_channels().first_valid_layer().all_attributes();
    let image = image.from_file(path).unwrap();
    let bits = |s: &FlatSamples| match s {
        FlatSamples::F16(v) => v.iter().map(|x| u64::from(x.to_bits()) | 1 << 40).collect(),
        FlatSamples::F32(v) => v.iter().map(|x| u64::from(x.to_bits()) | 2 << 40).collect(),
        FlatSamples::U32(v) => v.iter().map(|&x| u64::from(x) | 3 << 40).collect(),
    };
    image.layer_data.channel_data.list.iter().map(|c| (c.name.to_string(), bits(&c.sample_data))).collect()
}

/// A channel's samples as the reader printed them, in f32 (serde_json's
/// float parsing is not always correctly rounded in f64; every sample is
/// an f32 or narrower).
fn samples(channel: &serde_json::Value) -> Vec<f32> {
    let number = |v: &serde_json::Value| match v.as_str() {
        Some("inf") => f32::INFINITY,
        Some(other) => panic!("sample {other}"),
        None => v.as_f64().unwrap() as f32,
    };
    channel["samples"].as_array().unwrap().iter().map(number).collect()
}

/// Renders whole and in `n` tiles, checks every part against the rows of
/// the whole image and the merge against the whole image, channel for
/// channel, all read by the independent reader; returns the channel names.
fn check_merge(scene: &Path, args: &[&str], n: u32) -> Vec<String> {
    let dir = tempdir();
    let d = dir.path();
    let (one, parts) = render_both(d, scene, args, n);
    let merged = merge(d, &parts);
    // Decoded by the `exr` crate too, so that the comparison runs where
    // Python's OpenEXR is missing.
    assert!(decoded(&merged) == decoded(&one), "the merge's channels differ from one.exr's");
    let files: Vec<&Path> =
        [one.as_path(), merged.as_path()].into_iter().chain(parts.iter().map(PathBuf::as_path)).collect();
    let Some(raw) = read_raw(&files) else { return Vec::new() };
    let (whole, joined, parts_raw) = (&raw[0], &raw[1], &raw[2..]);
    // The merge: the whole image's windows and channels, no tile attribute,
    // the parts' compression (one row a block).
    for key in ["display_window", "data_window", "parts"] {
        assert_eq!(joined[key], whole[key], "{key}");
    }
    assert_eq!(joined["data_window"], joined["display_window"]);
    assert_eq!(joined["compression"], "ZIPS_COMPRESSION");
    assert_eq!(joined["attributes"], serde_json::json!({}), "the merge keeps no tile attribute");
    let channels = whole["channels"].as_object().unwrap();
    let names: Vec<&String> = channels.keys().collect();
    assert_eq!(joined["channels"].as_object().unwrap().keys().collect::<Vec<_>>(), names);
    for (name, c) in channels {
        assert_eq!(joined["channels"][name]["type"], c["type"], "channel {name}");
        assert!(samples(&joined["channels"][name]) == samples(c), "channel {name} differs");
    }
    // The parts: bands of the whole image's rows, the whole image as their
    // display window, one fingerprint.
    let [_, _, w1, h1] = [0, 1, 2, 3].map(|k| whole["display_window"][k].as_u64().unwrap() as usize);
    let (w, h) = (w1 + 1, h1 + 1);
    let mut next_row = 0;
    for (i, (raw, part)) in parts_raw.iter().zip(&parts).enumerate() {
        let (first, end) = (i * h / n as usize, (i + 1) * h / n as usize);
        assert_eq!(first, next_row, "the bands tile the image");
        next_row = end;
        assert_eq!(raw["display_window"], whole["display_window"], "{}", part.display());
        assert_eq!(raw["data_window"], serde_json::json!([0, first, w - 1, end - 1]), "{}", part.display());
        assert_eq!(raw["attributes"]["komplex.tile"], format!("{i}/{n}"));
        assert_eq!(raw["attributes"]["komplex.render"], parts_raw[0]["attributes"]["komplex.render"]);
        for (name, c) in channels {
            assert_eq!(raw["channels"][name]["type"], c["type"], "{name}");
            let want = &samples(c)[first * w..end * w];
            let got = samples(&raw["channels"][name]);
            assert!(got == want, "{} channel {name}: not rows {first}..{end} of the whole image", part.display());
        }
    }
    assert_eq!(next_row, h);
    names.into_iter().cloned().collect()
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
    // A truncated part, without --png (which reads every pixel first): the
    // copy of its blocks fails and names it.
    let good = std::fs::read(&parts[1]).unwrap();
    std::fs::write(d.join("cut.exr"), &good[..good.len() - 100]).unwrap();
    let o = komplex(d, &["merge", p(0), "cut.exr", p(2), "-o", "m.exr"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cut.exr: not a readable OpenEXR file"), "{}", text(&o));
    assert!(!d.join("m.exr").exists());
    // The same parts all given: the merge and its preview are written, the
    // preview that of the one-process render.
    komplex_ok(d, &["merge", p(0), p(1), p(2), "-o", "m.exr", "--png", "m.png", "--exposure", "1"]);
    let one = ["render", t, "-o", "one.exr", "--width", "16", "--height", "12", "--png", "one.png"];
    komplex_ok(d, &[&one[..], &["--exposure", "1"]].concat());
    assert!(std::fs::read(d.join("m.png")).unwrap() == std::fs::read(d.join("one.png")).unwrap());
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
    crafted_encoded(exr::prelude::Encoding::UNCOMPRESSED, size, rows, names, attributes, layers)
}

/// [`crafted_part`] in another `encoding` (compression and blocks).
pub(crate) fn crafted_encoded(
    encoding: exr::prelude::Encoding,
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
        Layer::new((size.0, rows.1 - rows.0), attributes, encoding, AnyChannels::sort(channels))
    };
    let display = IntegerBounds::new(Vec2(0, 0), Vec2(size.0, size.1));
    let image = Image::from_layers(ImageAttributes::new(display), (0..layers).map(layer).collect::<Vec<_>>());
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).unwrap();
    bytes.into_inner()
}

/// Without `-o`, the part goes to the scene's stem in the current
/// directory, with the tile before the extension.
#[test]
fn the_default_output_gets_the_tile_before_its_extension() {
    let dir = tempdir();
    let table = scene("table.json");
    komplex_ok(dir.path(), &["render", table.to_str().unwrap(), "--width", "8", "--height", "6", "--tile", "1/2"]);
    let names: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names, ["table.tile-1-of-2.exr"]);
}

#[test]
fn tiles_of_a_frame_merge_into_that_frame_and_are_foreign_to_another_frame() {
    let dir = tempdir();
    let d = dir.path();
    let orbit = scene("orbit.json");
    let o = orbit.to_str().unwrap();
    let size = ["--width", "12", "--height", "10"];
    komplex_ok(d, &[&["render", o, "-o", "one.exr", "--frame", "5"], &size[..]].concat());
    for frame in ["5", "6"] {
        for tile in ["0/2", "1/2"] {
            komplex_ok(d, &[&["render", o, "-o", "img.exr", "--frame", frame, "--tile", tile], &size[..]].concat());
        }
    }
    let part = |frame: &str, i: u32| d.join(format!("img.000{frame}.tile-{i}-of-2.exr"));
    let merged = merge(d, &[part("5", 0), part("5", 1)]);
    assert_eq!(decoded(&merged), decoded(&d.join("one.0005.exr")));
    // Frame 6's part is a tile of another render, even if only transforms move.
    let (a, b) = (part("5", 0), part("6", 1));
    let out = crate::support::komplex(d, &["merge", a.to_str().unwrap(), b.to_str().unwrap(), "-o", "mixed.exr"]);
    assert!(!out.status.success() && text(&out).contains("a foreign part"), "{}", text(&out));
    assert!(!d.join("mixed.exr").exists());
}
