//! `komplex generate` and `komplex bench`. No timings are
//! asserted: only that the figures are there and consistent.

use crate::support::{bench_scenes, komplex, komplex_ok, scene, tempdir};

#[test]
fn committed_bench_scenes_are_what_the_generators_write() {
    let dir = tempdir();
    let check = |args: &[&str], committed: &str| {
        let out = dir.path().join("out.json");
        let mut all = vec!["generate"];
        all.extend_from_slice(args);
        all.extend_from_slice(&["-o", out.to_str().unwrap()]);
        komplex_ok(dir.path(), &all);
        let want = std::fs::read_to_string(crate::support::root().join("scenes/bench").join(committed)).unwrap();
        assert!(std::fs::read_to_string(&out).unwrap() == want, "{committed} differs from `komplex generate {args:?}`");
    };
    check(&["sphereflake", "--level", "3"], "sphereflake-3.json");
    check(&["grid", "--count", "1000"], "grid-1000.json");
    assert_eq!(bench_scenes().len(), 2, "a new bench scene needs a line above");
}

#[test]
fn generated_scenes_have_the_requested_block_counts() {
    let dir = tempdir();
    // (arguments, blocks in the loaded scene): level L has 1 + 9 + … + 9^L spheres, plus the ground.
    for (args, blocks) in [
        (&["sphereflake", "--level", "0"][..], 2),
        (&["sphereflake", "--level", "2"], 92),
        (&["grid", "--count", "10"], 10),
        (&["grid", "--count", "27", "--seed", "9"], 27),
    ] {
        let mut all = vec!["generate"];
        all.extend_from_slice(args);
        let out = komplex_ok(dir.path(), &all);
        std::fs::write(dir.path().join("g.json"), &out.stdout).unwrap();
        let check = komplex_ok(dir.path(), &["check", "g.json"]);
        let summary = String::from_utf8_lossy(&check.stdout).to_string();
        assert!(summary.contains(&format!("{blocks} block")), "{args:?}: {summary}");
    }
}

#[test]
fn bench_counts_primary_and_all_rays() {
    let dir = tempdir();
    let table = scene("table.json");
    let csg = scene("csg.json");
    let out = komplex_ok(
        dir.path(),
        &["bench", table.to_str().unwrap(), csg.to_str().unwrap(), "--width", "32", "--height", "24", "--threads", "1"],
    );
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    for (line, name) in lines[1..].iter().zip(["table", "csg"]) {
        let f: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(f[0], name);
        assert_eq!(f[3], "32x24");
        let primary: u64 = f[5].parse().unwrap();
        let all: u64 = f[6].parse().unwrap();
        assert_eq!(primary, 32 * 24);
        // Both scenes have lights and reflective surfaces: secondary rays exist.
        assert!(all > primary, "{line}");
        let (p, a): (f64, f64) = (f[7].parse().unwrap(), f[8].parse().unwrap());
        assert!(p > 0.0 && a > p, "{line}");
    }
    // One side alone keeps the scene's aspect ratio (640x480), as for `render`.
    let o = komplex(dir.path(), &["bench", table.to_str().unwrap(), "--width", "32", "--threads", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    assert_eq!(text.lines().nth(1).and_then(|l| l.split_whitespace().nth(3)), Some("32x24"), "{text}");
    // A zero side is an input error, not a silent default.
    let o = komplex(dir.path(), &["bench", table.to_str().unwrap(), "--height", "0"]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn bench_runs_keep_the_fastest_and_the_median() {
    let dir = tempdir();
    let table = scene("table.json");
    let row = |runs: &str| {
        let out = komplex_ok(
            dir.path(),
            &["bench", table.to_str().unwrap(), "--width", "24", "--height", "18", "--threads", "1", "--runs", runs],
        );
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        let header: Vec<String> = text.lines().next().unwrap().split_whitespace().map(String::from).collect();
        assert_eq!(header[header.len() - 2..], ["s", "runs"], "{text}");
        text.lines().nth(1).unwrap().split_whitespace().map(String::from).collect::<Vec<_>>()
    };
    let (one, five) = (row("1"), row("5"));
    assert_eq!((one[10].as_str(), five[10].as_str()), ("1", "5"));
    // Every run renders the same image: the same rays.
    assert_eq!((&one[5], &one[6]), (&five[5], &five[6]));
    let (fastest, median): (f64, f64) = (five[4].parse().unwrap(), five[9].parse().unwrap());
    assert!(fastest <= median, "{five:?}");
    assert_eq!(one[4], one[9], "one run: the fastest is the median");
    let o = komplex(dir.path(), &["bench", table.to_str().unwrap(), "--runs", "0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--runs must be between 1 and 1000, got 0"));
}

/// `scripts/bench-scaling.sh` end to end on two small grids: each round's
/// growth is the ratio of the two per-ray costs it printed, and the summary
/// lines are there. Bad arguments are refused with a message.
#[test]
fn scaling_script_prints_consistent_growth() {
    let script = crate::support::root().join("scripts/bench-scaling.sh");
    let run = |args: &[&str]| {
        std::process::Command::new("bash")
            .arg(&script)
            .args(args)
            .env("KOMPLEX", env!("CARGO_BIN_EXE_komplex"))
            .output()
            .expect("bash runs")
    };
    let out =
        run(&["--small", "8", "--large", "64", "--width", "24", "--height", "18", "--rounds", "2", "--runs", "1"]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(out.status.success(), "{text}{}", String::from_utf8_lossy(&out.stderr));
    let rounds: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| l.split_whitespace().map(|f| f.parse().unwrap()).collect())
        .collect();
    assert_eq!(rounds.len(), 2, "{text}");
    // Each printed figure carries the rounding of its format: seconds to
    // 1e-6 (`%.6f`), growth to 0.01 (`%.2f`); the ratio of rounded seconds
    // is off by at most the sum of their relative roundings.
    let tolerance = |want: f64, s1: f64, s2: f64| want * 1.01 * (0.5e-6 / s1 + 0.5e-6 / s2) + 0.005 + 1e-9;
    for f in &rounds {
        // round, small s, small rays, large s, large rays, growth
        let want = (f[3] / f[4]) / (f[1] / f[2]);
        assert!(f[1] > 0.0 && f[3] > 0.0, "{text}");
        assert!((f[5] - want).abs() <= tolerance(want, f[1], f[3]), "round {f:?}: growth {} but {want}", f[5]);
    }
    let summary = |prefix: &str| -> f64 {
        let line = text.lines().find(|l| l.starts_with(prefix)).unwrap_or_else(|| panic!("no '{prefix}' in {text}"));
        line[prefix.len()..].split('x').next().unwrap().parse().unwrap()
    };
    // The fastest renders of each size, wherever they fell.
    let (ts, tl) = rounds.iter().fold((f64::INFINITY, f64::INFINITY), |(a, b), f| (a.min(f[1]), b.min(f[3])));
    let want = (tl / rounds[0][4]) / (ts / rounds[0][2]);
    let fastest = summary("growth per ray, fastest renders: ");
    assert!((fastest - want).abs() <= tolerance(want, ts, tl), "fastest {fastest} but {want}: {text}");
    // The median of two rounds is their mean.
    let median = summary("growth per ray, median of 2 rounds: ");
    let want = (rounds[0][5] + rounds[1][5]) / 2.0;
    assert!((median - want).abs() <= 0.005 + 1e-9, "median {median} but {want}: {text}");

    let bad = run(&["--rounds", "0"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("'0' is not a positive whole number"));
    let bad = run(&["--frobnicate"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("unknown argument '--frobnicate'"));
}

/// `scripts/compare-builds.sh` (the keep-or-drop check of a speed change):
/// a binary against itself renders the same images, and the script says so
/// and succeeds; against a wrapper of it that writes half-float colour,
/// every render differs, each is named, and the script fails.
#[test]
fn compare_builds_tells_equal_images_from_different_ones() {
    use std::os::unix::fs::PermissionsExt;
    let root = crate::support::root();
    let bin = env!("CARGO_BIN_EXE_komplex");
    let dir = tempdir();
    let half = dir.path().join("komplex-half");
    std::fs::write(&half, format!("#!/bin/sh\nexec '{bin}' \"$@\" --half\n")).unwrap();
    std::fs::set_permissions(&half, std::fs::Permissions::from_mode(0o755)).unwrap();
    let compare = |after: &std::path::Path| {
        let out = std::process::Command::new("bash")
            .arg(root.join("scripts/compare-builds.sh"))
            .args(["--width", "40", "--height", "30", bin])
            .arg(after)
            .arg(scene("table.json"))
            .output()
            .expect("bash runs");
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).to_string(),
            String::from_utf8_lossy(&out.stderr).to_string(),
        )
    };
    let (code, stdout, stderr) = compare(std::path::Path::new(bin));
    assert_eq!(code, Some(0), "{stdout}{stderr}");
    assert!(stdout.contains("images: 0 of 3 renders differ"), "{stdout}");
    let (code, stdout, stderr) = compare(&half);
    assert_eq!(code, Some(1), "{stdout}{stderr}");
    for mode in ["plain", "--samples 2", "--precision fast"] {
        assert!(stdout.contains(&format!("differs: table ({mode})")), "{stdout}");
    }
    assert!(stdout.contains("images: 3 of 3 renders differ"), "{stdout}");
}

#[test]
fn bench_stages_add_up_to_at_most_the_load() {
    let dir = tempdir();
    let (table, csg) = (scene("table.json"), scene("csg.json"));
    let args = ["bench", table.to_str().unwrap(), csg.to_str().unwrap(), "--width", "8", "--height", "6"];
    let out = komplex_ok(dir.path(), &[&args[..], &["--threads", "1", "--stages"]].concat());
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 5, "a row and its stages per scene: {text}");
    for pair in lines[1..].chunks(2) {
        let load: f64 = pair[0].split_whitespace().nth(2).unwrap().parse().unwrap();
        let stages = pair[1].trim().strip_prefix("load stages s: ").unwrap_or_else(|| panic!("{text}"));
        let names: Vec<&str> = stages.split(", ").map(|s| s.split(' ').next().unwrap()).collect();
        assert_eq!(names, ["read", "parse", "flatten", "build"], "{text}");
        let secs: Vec<f64> = stages.split(", ").map(|s| s.split(' ').nth(1).unwrap().parse().unwrap()).collect();
        // The stages are timed inside the load; each is printed to a millisecond.
        assert!(secs.iter().all(|s| *s >= 0.0) && secs.iter().sum::<f64>() <= load + 0.002, "{text}");
    }
    // Without the flag, the table as before.
    let out = komplex_ok(dir.path(), &[&args[..], &["--threads", "1"]].concat());
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 3);
}
