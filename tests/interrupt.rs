//! Ctrl-C during a render: exit status 130, the earlier output untouched,
//! no temporary file left behind.

use std::process::{Command, Stdio};
use std::time::Duration;

use crate::support::{scene, tempdir};

#[test]
fn sigint_stops_the_render_and_writes_nothing() {
    let dir = tempdir();
    let d = dir.path();
    std::fs::write(d.join("out.exr"), b"an earlier render").unwrap();
    std::fs::write(d.join("out.png"), b"an earlier preview").unwrap();
    let before: Vec<_> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name()).collect();
    // Tens of millions of rays: far more than a second of work, so the signal
    // arrives mid-render; rows stay short, so it stops soon after.
    let glass = scene("glass.json");
    let args =
        ["render", glass.to_str().unwrap(), "-o", "out.exr", "--png", "out.png", "--width", "4000", "--samples", "2"];
    let child =
        Command::new(env!("CARGO_BIN_EXE_komplex")).args(args).current_dir(d).stderr(Stdio::piped()).spawn().unwrap();
    // Long enough for the handler to be installed (the first thing `render` does).
    std::thread::sleep(Duration::from_millis(1500));
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "killed before the handler was installed? stderr:\n{err}");
    assert_eq!(err.trim_end(), "error: interrupted; no output was written");
    assert_eq!(std::fs::read(d.join("out.exr")).unwrap(), b"an earlier render");
    assert_eq!(std::fs::read(d.join("out.png")).unwrap(), b"an earlier preview");
    let after: Vec<_> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(before.len(), after.len(), "stray files: {after:?}");
}

#[test]
fn a_set_flag_stops_the_render_loop() {
    use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
    let world = crate::support::world(&scene("csg.json"), Some((16, 200)));
    let run = |flag: &AtomicBool, rows: &AtomicU32| {
        render::frame::render_until(
            &world,
            render::frame::Options { threads: Some(2), ..Default::default() },
            &|| {
                // Ctrl-C arrives once the third row is done.
                if rows.fetch_add(1, Ordering::SeqCst) == 2 {
                    flag.store(true, Ordering::SeqCst);
                }
            },
            flag,
        )
    };
    let (flag, rows) = (AtomicBool::new(false), AtomicU32::new(0));
    assert!(matches!(run(&flag, &rows), Err(render::Error::Interrupted)));
    // Workers check the flag before each task, a band of sixteen rows, and
    // report its rows when it is done. After the third row's report, the
    // reporting worker reports its band's other 13 rows, and the other
    // worker may finish the band it had started: at most 3 + 13 + 16 rows.
    // (Without the check all 200 would be rendered.)
    assert!(rows.load(Ordering::SeqCst) <= 32, "{} rows rendered after the flag", rows.load(Ordering::SeqCst));
    // Without the flag the same loop finishes.
    let (flag, rows) = (AtomicBool::new(false), AtomicU32::new(1000));
    assert_eq!(run(&flag, &rows).unwrap().0.len(), 16 * 200);
}
