//! POV-Ray cross-check: `komplex export-pov --mask` rendered by
//! POV-Ray 3.7 must agree with our `id.block` channel. POV-Ray is an
//! independent implementation of the same geometry (its own root finder,
//! CSG and camera), so agreement checks the exporter and our tracer at once.

use std::path::Path;
use std::process::Command;

use crate::support::{all_scenes, bench_scenes, komplex_ok, render_frame, tempdir, text, world};

const WIDTH: u32 = 160;
const HEIGHT: u32 = 120;

/// Whether `povray` runs; under CI (`CI=true`) its absence is a failure.
fn have_povray() -> bool {
    let in_ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    match Command::new("povray").arg("--version").output() {
        Ok(_) => true,
        Err(e) => {
            assert!(!in_ci, "CI=true but povray cannot run ({e}); .ci/run installs it with apt-get");
            eprintln!("notice: skipping the POV-Ray cross-check: povray cannot run ({e}); apt-get install povray");
            false
        }
    }
}

/// POV-Ray's mask of `scene`, decoded to 1-based block ids, row-major.
fn pov_mask(dir: &Path, scene: &Path) -> Vec<u32> {
    let stem = scene.file_stem().unwrap().to_string_lossy().to_string();
    let pov = format!("{stem}.pov");
    let png = format!("{stem}.png");
    let (w, h) = (WIDTH.to_string(), HEIGHT.to_string());
    komplex_ok(dir, &["export-pov", scene.to_str().unwrap(), "--mask", "--width", &w, "--height", &h, "-o", &pov]);
    // -A: one ray through each pixel centre; File_Gamma=1.0 keeps the id
    // bytes as written; POV may only write in its working directory.
    let out = Command::new("povray")
        .args([
            "-A",
            "+FN",
            "-D",
            "-P",
            &format!("+W{w}"),
            &format!("+H{h}"),
            "File_Gamma=1.0",
            &format!("+I{pov}"),
            &format!("+O{png}"),
        ])
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "povray failed on {pov}:\n{}", text(&out));
    let img = image::open(dir.join(&png)).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (WIDTH, HEIGHT));
    img.pixels().map(|p| u32::from(p[0]) + 256 * u32::from(p[1]) + 65536 * u32::from(p[2])).collect()
}

#[test]
fn povray_masks_match_block_ids() {
    if !have_povray() {
        return;
    }
    let dir = tempdir();
    // The example scenes and the committed benchmark scenes (rotated boxes
    // and capped cylinders, hundreds of small spheres).
    for scene in all_scenes().into_iter().chain(bench_scenes()) {
        let ours: Vec<u32> = render_frame(&world(&scene, Some((WIDTH, HEIGHT)))).block;
        let theirs = pov_mask(dir.path(), &scene);
        let same = ours.iter().zip(&theirs).filter(|(a, b)| a == b).count();
        let share = same as f64 / ours.len() as f64;
        let blocks = ours.iter().filter(|b| **b != 0).collect::<std::collections::BTreeSet<_>>().len();
        // The mask must show the scene's blocks, else agreement would be trivial.
        assert!(blocks >= 2, "{}: only {blocks} blocks visible", scene.display());
        let first_bad = ours.iter().zip(&theirs).position(|(a, b)| a != b).map(|k| {
            let (i, j) = (k / WIDTH as usize, k % WIDTH as usize);
            format!("first difference at row {i}, column {j}: ours {}, POV-Ray {}", ours[k], theirs[k])
        });
        assert!(
            share >= 0.999,
            "{}: POV-Ray's mask agrees on {:.3}% of pixels (< 99.9%); {}",
            scene.display(),
            100.0 * share,
            first_bad.unwrap_or_default()
        );
    }
}

/// POV-Ray's orthographic camera, from the exported vectors, sees the blocks
/// on the pixels komplex's orthographic rays (model §4.5) do.
#[test]
fn povray_orthographic_masks_match_block_ids() {
    if !have_povray() {
        return;
    }
    let dir = tempdir();
    let text = std::fs::read_to_string(crate::support::scene("table.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["camera"]["projection"] = "orthographic".into();
    v["camera"]["diagonal"] = 5.0.into();
    v.as_object_mut().unwrap().remove("$schema");
    let scene = crate::support::write_scene(dir.path(), "ortho.json", &v.to_string());
    let ours: Vec<u32> = render_frame(&world(&scene, Some((WIDTH, HEIGHT)))).block;
    let theirs = pov_mask(dir.path(), &scene);
    let same = ours.iter().zip(&theirs).filter(|(a, b)| a == b).count();
    let blocks = ours.iter().filter(|b| **b != 0).collect::<std::collections::BTreeSet<_>>().len();
    assert!(blocks >= 2, "only {blocks} blocks visible");
    let share = same as f64 / ours.len() as f64;
    assert!(share >= 0.999, "POV-Ray's orthographic mask agrees on {:.3}% of pixels", 100.0 * share);
}

/// The numbers in a line of POV source (fractions like `3/255` are two numbers).
fn numbers(line: &str) -> Vec<f64> {
    line.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-')).filter_map(|t| t.parse().ok()).collect()
}

/// The camera vectors follow the issue's formulas: `direction` of length
/// `sqrt(W²+H²)/(2·tan(aperture/2))` along the view direction, `right` of
/// length W along `direction × up`, `up` of length H along `right × direction`.
#[test]
fn exported_camera_vectors_follow_the_formulas() {
    let dir = tempdir();
    let json = r#"{ "camera": { "eye": [1, 2, 3], "direction": [1, -0.5, -2], "up": [0.2, 1, 0],
                    "width": 200, "height": 100, "aperture": 40 },
                    "blocks": [ { "objects": [ { "sphere": {} } ] } ] }"#;
    let scene = crate::support::write_scene(dir.path(), "cam.json", json);
    let out = komplex_ok(dir.path(), &["export-pov", scene.to_str().unwrap()]);
    let text = String::from_utf8(out.stdout).unwrap();
    let get = |key: &str| -> [f64; 3] {
        let line = text.lines().find(|l| l.trim_start().starts_with(key)).unwrap();
        let n = numbers(line);
        [n[0], n[1], n[2]]
    };
    let (loc, d, r, u) = (get("location"), get("direction"), get("right"), get("up"));
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross =
        |a: [f64; 3], b: [f64; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    assert_eq!(loc, [1.0, 2.0, 3.0]);
    let f = (200.0f64 * 200.0 + 100.0 * 100.0).sqrt() / (2.0 * 20f64.to_radians().tan());
    assert!((norm(d) - f).abs() < 1e-9 * f, "{d:?}");
    let view = [1.0, -0.5, -2.0];
    assert!((dot(d, view) / (norm(d) * norm(view)) - 1.0).abs() < 1e-12, "direction not along the view");
    assert!((norm(r) - 200.0).abs() < 1e-9 && (norm(u) - 100.0).abs() < 1e-9);
    // right ∥ direction × up (the scene's up), up ∥ right × direction: not mirrored.
    let want_r = cross(view, [0.2, 1.0, 0.0]);
    assert!((dot(r, want_r) / (norm(r) * norm(want_r)) - 1.0).abs() < 1e-12, "{r:?}");
    let want_u = cross(r, d);
    assert!((dot(u, want_u) / (norm(u) * norm(want_u)) - 1.0).abs() < 1e-12, "{u:?}");
}

/// Whether `x` is inside one exported solid (a mask-mode line), evaluated
/// the way POV-Ray reads it: the quadric in its own frame through the
/// `matrix` (rows: images of the axes, then the translation), `inverse`
/// swapping inside and outside; a plane `n·(x − o) < d`.
fn pov_inside(line: &str, x: [f64; 3]) -> (bool, f64) {
    let n = numbers(line);
    let inverse = line.contains(" inverse");
    if line.trim_start().starts_with("quadric") {
        let t = [n[19], n[20], n[21]];
        let p = [x[0] - t[0], x[1] - t[1], x[2] - t[2]];
        // The matrix part is orthonormal, so its inverse is its transpose.
        let y: Vec<f64> = (0..3).map(|i| n[10 + 3 * i] * p[0] + n[11 + 3 * i] * p[1] + n[12 + 3 * i] * p[2]).collect();
        let f = n[0] * y[0] * y[0]
            + n[1] * y[1] * y[1]
            + n[2] * y[2] * y[2]
            + n[3] * y[0] * y[1]
            + n[4] * y[0] * y[2]
            + n[5] * y[1] * y[2]
            + n[6] * y[0]
            + n[7] * y[1]
            + n[8] * y[2]
            + n[9];
        ((f < 0.0) != inverse, f)
    } else {
        let o = if line.contains("translate") { [n[4], n[5], n[6]] } else { [0.0; 3] };
        let f = n[0] * (x[0] - o[0]) + n[1] * (x[1] - o[1]) + n[2] * (x[2] - o[2]) - n[3];
        ((f < 0.0) != inverse, f)
    }
}

/// Every block of the exported file contains the same sampled points as the
/// kernel's block (points within 1e-9 of a surface are skipped). Runs
/// without POV-Ray: this checks the exporter's algebra on its own.
#[test]
fn exported_solids_contain_the_same_points() {
    let dir = tempdir();
    for scene in all_scenes().into_iter().chain(bench_scenes()) {
        let out = komplex_ok(dir.path(), &["export-pov", scene.to_str().unwrap(), "--mask"]);
        let text = String::from_utf8(out.stdout).unwrap();
        let w = world(&scene, None);
        // The solids of each block, in order: lines after each `// block N` comment.
        let mut blocks: Vec<Vec<&str>> = vec![];
        for line in text.lines() {
            let l = line.trim_start();
            if l.starts_with("// block") {
                blocks.push(vec![]);
            } else if l.starts_with("quadric") || l.starts_with("plane") {
                blocks.last_mut().unwrap().push(line);
            }
        }
        assert_eq!(blocks.len(), w.complex.blocks().len(), "{}", scene.display());
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = |lo: f64, hi: f64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            lo + (hi - lo) * (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut inside, mut compared) = (0, 0);
        for (b, solids) in blocks.iter().enumerate() {
            assert_eq!(solids.len(), w.complex.blocks()[b].solids().len());
            let aabb = w.complex.block_aabb(complex::BlockId(b as u32));
            // Sample the block's box (or a box around the origin for unbounded blocks), a bit enlarged.
            let (lo, hi): (Vec<f64>, Vec<f64>) = (0..3)
                .map(|k| {
                    let (a, z) = (aabb.min[k].max(-20.0), aabb.max[k].min(20.0));
                    let pad = 0.1 * (z - a) + 1e-3;
                    (a - pad, z + pad)
                })
                .unzip();
            for _ in 0..300 {
                let x = [uniform(lo[0], hi[0]), uniform(lo[1], hi[1]), uniform(lo[2], hi[2])];
                let evals: Vec<(bool, f64)> = solids.iter().map(|s| pov_inside(s, x)).collect();
                if evals.iter().any(|(_, f)| f.abs() < 1e-9) {
                    continue;
                }
                let theirs = evals.iter().all(|(i, _)| *i);
                let ours = w.complex.blocks()[b].contains_point(&quadric::nalgebra::Point3::from(x));
                assert_eq!(theirs, ours, "{}: block {} at {x:?}", scene.display(), b + 1);
                compared += 1;
                inside += usize::from(ours);
            }
        }
        // The samples must reach inside blocks, else agreement says little.
        assert!(inside * 10 >= compared, "{}: only {inside} of {compared} samples inside", scene.display());
    }
}

/// `scripts/bench-vs-povray.sh` end to end on two scenes at a small size:
/// each ratio is POV-Ray's time over ours as printed (to the rounding of
/// the printed seconds), our ray count is `komplex bench`'s, and POV-Ray's
/// rays and shadow tests are of the same order as ours — an export that
/// traced deeper, dropped a light or shadows, or a script reading the
/// wrong column of either log would break it.
#[test]
fn bench_script_compares_the_same_work() {
    if !have_povray() {
        return;
    }
    let root = crate::support::root();
    let scenes = [root.join("scenes/table.json"), root.join("scenes/bench/sphereflake-3.json")];
    let out = Command::new("bash")
        .arg(root.join("scripts/bench-vs-povray.sh"))
        .args(["--width", "160", "--height", "120", "--runs", "1"])
        .args(&scenes)
        .env("KOMPLEX", env!("CARGO_BIN_EXE_komplex"))
        .output()
        .expect("bash runs");
    let printed = text(&out);
    assert!(out.status.success(), "{printed}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<Vec<&str>> = stdout
        .lines()
        .map(|l| l.split_whitespace().collect::<Vec<_>>())
        .filter(|f| f.len() > 1 && f[1].parse::<u64>().is_ok())
        .collect();
    assert_eq!(rows.len(), 2, "{printed}");
    let dir = tempdir();
    for (row, scene) in rows.iter().zip(&scenes) {
        // scene, blocks, pov s, komplex s, pov prim/s, komplex prim/s, komplex all/s, ratio, pov rays, komplex rays
        assert_eq!(row.len(), 10, "{printed}");
        assert_eq!(row[0], scene.file_stem().unwrap().to_str().unwrap());
        let num = |i: usize| -> f64 { row[i].parse().unwrap_or_else(|_| panic!("column {i} of {row:?}")) };
        let (pov, ours, ratio) = (num(2), num(3), num(7));
        // Seconds are printed to the millisecond, the ratio from the unrounded times.
        let (lo, hi) = ((pov - 5e-4) / (ours + 5e-4), (pov + 5e-4) / (ours - 5e-4).max(1e-9));
        assert!(lo - 0.005 <= ratio && ratio <= hi + 0.005, "ratio {ratio} outside [{lo}, {hi}]: {row:?}");
        assert!((num(4) - 160.0 * 120.0 / pov).abs() <= 0.01 * num(4) + 1.0, "{row:?}");
        let bench = komplex_ok(
            dir.path(),
            &["bench", scene.to_str().unwrap(), "--width", "160", "--height", "120", "--threads", "1"],
        );
        let bench = String::from_utf8(bench.stdout).unwrap();
        let all_rays = bench.lines().nth(1).unwrap().split_whitespace().nth(6).unwrap();
        assert_eq!(row[9], all_rays, "komplex rays are bench's all rays: {bench}");
        let (theirs, ours) = (num(8), num(9));
        assert!(ours >= 160.0 * 120.0, "{row:?}");
        assert!(theirs >= 0.5 * ours && theirs <= 2.0 * ours, "POV-Ray traced {theirs} rays, komplex {ours}: {row:?}");
    }
}
