//! POV-Ray cross-check (issue 6): `komplex export-pov --mask` rendered by
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
        let ours: Vec<u32> =
            render_frame(&world(&scene, Some((WIDTH, HEIGHT)))).pixels.iter().map(|p| p.block).collect();
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
