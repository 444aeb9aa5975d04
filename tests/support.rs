//! Helpers shared by the end-to-end tests.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A scene in `scenes/`.
pub fn scene(name: &str) -> PathBuf {
    root().join("scenes").join(name)
}

/// Every scene in `scenes/`.
pub fn all_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    v.sort();
    v
}

/// The committed benchmark scenes in `scenes/bench/`.
pub fn bench_scenes() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("scenes").join("bench"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    v.sort();
    v
}

/// Runs `komplex` with `args` in `cwd`.
pub fn komplex(cwd: &Path, args: &[&str]) -> Output {
    komplex_env(cwd, args, &[])
}

/// Runs `komplex` with `args` in `cwd` and the variables `env` set. The
/// scheduler's task index variables (`--tile auto/N`) are set only as `env`
/// sets them, whatever the tests run under.
pub fn komplex_env(cwd: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_komplex"));
    command.args(args).current_dir(cwd);
    for name in ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"] {
        command.env_remove(name);
    }
    command.envs(env.iter().copied()).output().expect("komplex runs")
}

/// Status, stdout and stderr as text, for failure messages.
pub fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Runs `komplex`, asserting success.
pub fn komplex_ok(cwd: &Path, args: &[&str]) -> Output {
    let o = komplex(cwd, args);
    assert!(o.status.success(), "komplex {args:?} failed:\n{}", text(&o));
    o
}

/// A fresh temporary directory.
pub fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// Writes `json` to `dir/name` and returns the path.
pub fn write_scene(dir: &Path, name: &str, json: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, json).unwrap();
    p
}

/// One channel of an EXR file as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// `f32`, `f16` or `u32`.
    pub kind: String,
    /// Every sample, row-major, as f64.
    pub samples: Vec<f64>,
}

/// An EXR file as read back by an independent reader.
#[derive(Clone, Debug, PartialEq)]
pub struct Exr {
    /// Number of parts.
    pub parts: usize,
    /// Compression name (OpenEXR's spelling, e.g. `ZIP_COMPRESSION`).
    pub compression: String,
    /// `scanlineimage` or `tiledimage`.
    pub storage: String,
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Channels by name.
    pub channels: BTreeMap<String, Channel>,
}

impl Exr {
    /// Sample of `channel` at row `i`, column `j`.
    pub fn at(&self, channel: &str, i: usize, j: usize) -> f64 {
        self.channels[channel].samples[i * self.width + j]
    }
}

fn number(v: &serde_json::Value) -> f64 {
    match v {
        serde_json::Value::String(s) if s == "inf" => f64::INFINITY,
        serde_json::Value::String(s) if s == "-inf" => f64::NEG_INFINITY,
        serde_json::Value::String(_) => f64::NAN,
        v => v.as_f64().unwrap(),
    }
}

/// Runs a Python helper script from `tests/` (exit status 2 there means a
/// package is missing). Returns `None` with a printed notice when Python or
/// the package is missing, except under CI (`CI=true`), where that fails.
pub fn python(script: &str, args: &[&Path]) -> Option<Output> {
    let script = root().join("tests").join(script);
    let out = Command::new("python3").arg(&script).args(args).output();
    let in_ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
    match out {
        Ok(o) if o.status.success() => Some(o),
        Ok(o) if o.status.code() == Some(2) || o.status.code() == Some(127) => {
            assert!(!in_ci, "CI=true but a Python package is missing: {}", String::from_utf8_lossy(&o.stderr));
            eprintln!(
                "notice: skipping a check that needs Python packages ({}); python3 -m pip install OpenEXR numpy jsonschema",
                String::from_utf8_lossy(&o.stderr).trim()
            );
            None
        }
        Ok(o) => panic!("{} failed:\n{}", script.display(), text(&o)),
        Err(e) => {
            assert!(!in_ci, "CI=true but python3 cannot run: {e}");
            eprintln!("notice: skipping a check that needs python3 ({e})");
            None
        }
    }
}

/// Reads an EXR file with the Python `OpenEXR` package (the reference
/// implementation's bindings), independent of the `exr` crate that wrote it;
/// `None` if that is not installed (see [`python`]).
pub fn read_exr(path: &Path) -> Option<Exr> {
    let out = python("read_exr.py", &[path])?;
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let channels = v["channels"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(name, c)| {
            let samples = c["samples"].as_array().unwrap().iter().map(number).collect();
            (name.clone(), Channel { kind: c["type"].as_str().unwrap().to_string(), samples })
        })
        .collect();
    Some(Exr {
        parts: v["parts"].as_u64().unwrap() as usize,
        compression: v["compression"].as_str().unwrap().to_string(),
        storage: v["storage"].as_str().unwrap().to_string(),
        width: v["width"].as_u64().unwrap() as usize,
        height: v["height"].as_u64().unwrap() as usize,
        channels,
    })
}

/// Loads a scene through the library, optionally at another size.
pub fn world(path: &Path, size: Option<(u32, u32)>) -> render::world::World {
    let mut w = render::load(path).unwrap();
    if let Some((width, height)) = size {
        w.camera = w.camera.with_size(width, height).unwrap();
    }
    w
}

/// Renders in-process.
pub fn render_frame(world: &render::world::World) -> render::frame::Frame {
    render::frame::render(world, render::frame::Options::default(), &|| {}).unwrap().0
}

/// The image a scene renders to: through the CLI and the independent
/// reader when Python's OpenEXR is available, else from the in-process
/// renderer (with a notice; never under CI, where `read_exr` fails instead).
pub fn rendered(dir: &Path, scene: &Path) -> Exr {
    let out = dir.join(format!("{}.exr", scene.file_stem().unwrap().to_string_lossy()));
    komplex_ok(dir, &["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    if let Some(exr) = read_exr(&out) {
        return exr;
    }
    let frame = render_frame(&world(scene, None));
    let f32s = |f: &dyn Fn(&render::frame::Pixel) -> f32| Channel {
        kind: "f32".into(),
        samples: frame.pixels().map(|p| f64::from(f(&p))).collect(),
    };
    let u32s = |f: &dyn Fn(&render::frame::Pixel) -> u32| Channel {
        kind: "u32".into(),
        samples: frame.pixels().map(|p| f64::from(f(&p))).collect(),
    };
    let channels = [
        ("R", f32s(&|p| p.rgb[0])),
        ("G", f32s(&|p| p.rgb[1])),
        ("B", f32s(&|p| p.rgb[2])),
        ("A", f32s(&|p| p.alpha)),
        ("Z", f32s(&|p| p.depth)),
        ("N.X", f32s(&|p| p.normal[0])),
        ("N.Y", f32s(&|p| p.normal[1])),
        ("N.Z", f32s(&|p| p.normal[2])),
        ("id.block", u32s(&|p| p.block)),
        ("id.object", u32s(&|p| p.object)),
    ]
    .into_iter()
    .map(|(n, c)| (n.to_string(), c))
    .collect();
    Exr {
        parts: 1,
        compression: "ZIP_COMPRESSION".into(),
        storage: "scanlineimage".into(),
        width: frame.width as usize,
        height: frame.height as usize,
        channels,
    }
}
