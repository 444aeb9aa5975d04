//! Procedural textures end to end (docs/model.md §5.9): a checkered floor
//! seen from above shows the analytic checker of its own frame.

use crate::geom::{add, mul, Cam};
use crate::support::{render_frame, tempdir, world, write_scene};

/// A floor `y ≤ 0` moved by `[0.5, 0, 0.25]` with an ambient checker of
/// side 0.75, under a camera looking straight down: every pixel whose ray
/// meets the floor clearly inside a cell has that cell's colour, the cell
/// found by intersecting the ray with `y = 0` by hand and flooring in the
/// block's frame (the world point minus the translation).
#[test]
fn checkered_floor_matches_the_analytic_checker() {
    let cam = Cam { e: [0.2, 6.0, -0.1], d: [0.0, -1.0, 0.0], u: [0.0, 0.0, -1.0], w: 48, h: 36, angle: 60.0 };
    let (red, blue) = ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0]);
    let (scale, shift) = (0.75, [0.5, 0.0, 0.25]);
    let json = format!(
        r#"{{ {},
             "settings": {{ "ambient": [1, 1, 1] }},
             "materials": {{ "floor": {{ "ambient": {{ "checker": {{ "scale": {scale}, "colors": [{red:?}, {blue:?}] }} }} }} }},
             "blocks": [ {{ "name": "floor", "material": "floor", "transform": [ {{ "translate": {shift:?} }} ],
                           "objects": [ {{ "halfspace": [0, 1, 0, 0] }} ] }} ] }}"#,
        cam.json()
    );
    let dir = tempdir();
    let frame = render_frame(&world(&write_scene(dir.path(), "checker.json", &json), None));
    let (mut seen, mut cells) = (0, [0, 0]);
    for i in 0..cam.h {
        for j in 0..cam.w {
            let d = cam.ray(i, j);
            let x = add(cam.e, mul(-cam.e[1] / d[1], d));
            let (u, w) = ((x[0] - shift[0]) / scale, (x[2] - shift[2]) / scale);
            let px = frame.at(i, j);
            assert_eq!(px.block, 1, "pixel ({i},{j}) sees the floor");
            if (u - u.round()).abs() < 0.05 || (w - w.round()).abs() < 0.05 {
                continue;
            }
            let parity = (u.floor() + w.floor()).rem_euclid(2.0) as usize;
            let want = if parity == 0 { red } else { blue };
            let got = px.rgb.map(f64::from);
            assert_eq!(got, want, "pixel ({i},{j}) at x = {x:?}");
            seen += 1;
            cells[parity] += 1;
        }
    }
    assert!(seen > 1000 && cells[0] > 300 && cells[1] > 300, "{seen} pixels, {cells:?}");
}
