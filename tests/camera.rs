//! The camera of docs/model.md §4, end to end: spheres land on the pixels the
//! formulas predict, and `Z` is the analytic distance along the ray.

use crate::geom::{add, dot, mul, sub, Cam, V};
use crate::support::{rendered, tempdir, write_scene};

/// First hit of the ray `e + t d` with the sphere `|x - c| = r`, classified:
/// `Some(Some(t))` a clear hit, `Some(None)` a clear miss, `None` too close to
/// tangent to call.
fn sphere_hit(e: V, d: V, c: V, r: f64) -> Option<Option<f64>> {
    let oc = sub(e, c);
    let b = dot(d, oc);
    let disc = b * b - (dot(oc, oc) - r * r);
    if disc.abs() < 1e-6 * r * r {
        return None;
    }
    Some((disc > 0.0).then(|| -b - disc.sqrt()))
}

fn check(cam: Cam, centre: V, radius: f64) {
    let dir = tempdir();
    let json = format!(
        r#"{{ {}, "settings": {{ "ambient": [1, 1, 1] }},
             "materials": {{ "m": {{ "ambient": [0.5, 0.5, 0.5] }} }},
             "blocks": [ {{ "name": "ball", "material": "m", "objects": [ {{ "sphere": {{ "radius": {radius:?}, "center": {centre:?} }} }} ] }} ] }}"#,
        cam.json()
    );
    let scene = write_scene(dir.path(), "ball.json", &json);
    let img = rendered(dir.path(), &scene);
    let (mut hits, mut misses) = (0, 0);
    for i in 0..cam.h {
        for j in 0..cam.w {
            let (iu, ju) = (i as usize, j as usize);
            let Some(want) = sphere_hit(cam.e, cam.ray(i, j), centre, radius) else { continue };
            match want {
                Some(t) => {
                    hits += 1;
                    assert_eq!(img.at("id.block", iu, ju), 1.0, "pixel ({i},{j}) should see the ball");
                    let z = img.at("Z", iu, ju);
                    assert!((z - t).abs() <= 1e-6 * t, "pixel ({i},{j}): Z {z} vs analytic {t}");
                    // The normal faces the camera: (x - c)/r at the hit point.
                    let x = add(cam.e, mul(t, cam.ray(i, j)));
                    let n = mul(1.0 / radius, sub(x, centre));
                    for (k, ch) in ["N.X", "N.Y", "N.Z"].iter().enumerate() {
                        assert!((img.at(ch, iu, ju) - n[k]).abs() < 1e-5, "{ch} at ({i},{j})");
                    }
                }
                None => {
                    misses += 1;
                    assert_eq!(img.at("id.block", iu, ju), 0.0, "pixel ({i},{j}) should miss");
                    assert_eq!(img.at("Z", iu, ju), f64::INFINITY);
                }
            }
        }
    }
    assert!(hits > 20 && misses > 20, "a test that can fail needs both: {hits} hits, {misses} misses");
}

#[test]
fn sphere_straight_ahead() {
    check(
        Cam { e: [0.0, 0.0, 0.0], d: [0.0, 0.0, -1.0], u: [0.0, 1.0, 0.0], w: 40, h: 30, angle: 50.0 },
        [0.0, 0.0, -5.0],
        1.0,
    );
}

#[test]
fn sphere_off_axis_oblique_camera() {
    check(
        Cam { e: [0.3, -0.2, 4.0], d: [0.2, 0.1, -1.0], u: [0.1, 1.0, 0.3], w: 37, h: 23, angle: 70.0 },
        [1.0, 0.5, -2.0],
        0.9,
    );
}

#[test]
fn sphere_centred_on_a_chosen_pixel() {
    // A small ball placed on the ray through pixel (5, 30) by the formulas
    // covers that pixel, with Z = distance - radius there.
    let cam = Cam { e: [1.0, 2.0, 3.0], d: [-1.0, -0.5, -2.0], u: [0.0, 0.0, 1.0], w: 48, h: 32, angle: 40.0 };
    let (i, j) = (5u32, 30u32);
    let centre = add(cam.e, mul(10.0, cam.ray(i, j)));
    let r = 0.05;
    let dir = tempdir();
    let json = format!(
        r#"{{ {}, "blocks": [ {{ "objects": [ {{ "sphere": {{ "radius": {r:?}, "center": {centre:?} }} }} ] }} ] }}"#,
        cam.json()
    );
    let img = rendered(dir.path(), &write_scene(dir.path(), "dot.json", &json));
    let (iu, ju) = (i as usize, j as usize);
    assert_eq!(img.at("id.block", iu, ju), 1.0);
    let z = img.at("Z", iu, ju);
    assert!((z - (10.0 - r)).abs() < 1e-5, "Z {z}");
    let covered: usize = img.channels["id.block"].samples.iter().filter(|b| **b == 1.0).count();
    // Angular radius 0.005 rad; one pixel spans about 0.7/57.7 = 0.012 rad: only the pixel itself.
    assert_eq!(covered, 1, "the dot covers {covered} pixels");
}

/// Renders a scene given as JSON text in-process.
fn render_text(json: &str) -> render::frame::Frame {
    let world = render::format::SceneFile::load_str(json).unwrap();
    crate::support::render_frame(&world)
}

/// A thin disc of radius `r` facing the camera at distance `z0` (its front
/// face at `z = -z0`, 0.01 deep), seen from the origin along `-z` through a
/// lens of radius `lens` focused at `focus`, `n × n` samples a pixel.
fn disc_scene(r: f64, z0: f64, lens: f64, focus: f64, n: u32) -> String {
    format!(
        r#"{{ "camera": {{ "eye": [0, 0, 0], "direction": [0, 0, -1], "width": 48, "height": 48,
                          "lens_radius": {lens:?}, "focus_distance": {focus:?} }},
             "settings": {{ "samples": {n} }},
             "blocks": [ {{ "objects": [ {{ "cylinder": {{ "radius": {r:?}, "axis": "z" }} }},
                                        {{ "halfspace": [0, 0, 1, {z0:?}] }},
                                        {{ "halfspace": [0, 0, -1, {back:?}] }} ] }} ] }}"#,
        back = -(z0 + 0.01)
    )
}

/// The thin lens of docs/model.md §4.5 against its geometry: a sub-pixel ray
/// from lens offset `s` meets the plane at distance `z0` `|s| |1 - z0/f|`
/// from where the pinhole ray does, which is at most `b` pixels there. So a
/// pixel whose centre is farther than `b + √2/2` pixels from the disc's
/// pinhole silhouette (a circle of `ρ` pixels) is wholly in or out, and
/// only the pixels near it are partly covered. Returns the frame and the
/// number of partly covered pixels.
fn check_disc(z0: f64, lens: f64, focus: f64) -> (render::frame::Frame, usize) {
    let (size, n) = (48.0f64, 4);
    let focal = (2.0 * size * size).sqrt() / (2.0 * 25f64.to_radians().tan());
    let rho = 12.0;
    let r = rho * z0 / focal;
    let b = lens * (1.0 - z0 / focus).abs() * focal / z0;
    let frame = render_text(&disc_scene(r, z0, lens, focus, n));
    let mut partial = 0;
    for i in 0..48u32 {
        for j in 0..48u32 {
            let c = (size - 1.0) / 2.0;
            let delta = (f64::from(i) - c).hypot(f64::from(j) - c);
            let alpha = frame.at(i, j).alpha;
            partial += usize::from(alpha > 0.0 && alpha < 1.0);
            if (delta - rho).abs() > b + 0.5f64.sqrt() + 0.05 {
                let want = if delta < rho { 1.0 } else { 0.0 };
                assert_eq!(alpha, want, "pixel ({i},{j}) at {delta:.2} px from the centre (ρ {rho}, blur {b:.2})");
            }
        }
    }
    (frame, partial)
}

#[test]
fn the_focus_plane_is_sharp_and_the_rest_blurred() {
    let (pinhole, _) = check_disc(5.0, 0.0, 5.0);
    // On the focus plane: every lens ray of a sub-pixel meets the disc where
    // its pinhole ray does, so coverage is the pinhole's.
    let (sharp, sharp_partial) = check_disc(5.0, 0.3, 5.0);
    let differ = pinhole.pixels().zip(sharp.pixels()).filter(|(a, b)| a.alpha != b.alpha).count();
    assert!(differ <= 2, "{differ} pixels differ from the pinhole's on the focus plane");
    // Three times as far: a blur of about 2.9 pixels, a wide band of partly covered pixels.
    let (blurred, blurred_partial) = check_disc(15.0, 0.3, 5.0);
    assert!(blurred_partial > 3 * sharp_partial, "{blurred_partial} vs {sharp_partial} partly covered pixels");
    // The AOVs come from the pinhole ray through the pixel centre (§4.3).
    let (far_pinhole, _) = check_disc(15.0, 0.0, 5.0);
    assert!(far_pinhole.pixels().zip(blurred.pixels()).all(|(a, b)| a.block == b.block && a.depth == b.depth));
}

#[test]
fn orthographic_spheres_keep_their_size() {
    // Parallel rays: a sphere of radius 1 spans 2 / pixel pixels wherever it is.
    let (w, h, diagonal) = (60u32, 40u32, 6.0f64);
    let p = diagonal / f64::from(w * w + h * h).sqrt();
    let (cx, cy, radius) = (0.3, -0.2, 1.0);
    for z in [0.0, -40.0] {
        let json = format!(
            r#"{{ "camera": {{ "eye": [0, 0, 10], "direction": [0, 0, -1], "width": {w}, "height": {h},
                              "projection": "orthographic", "diagonal": {diagonal:?} }},
                 "blocks": [ {{ "objects": [ {{ "sphere": {{ "radius": {radius:?}, "center": [{cx:?}, {cy:?}, {z:?}] }} }} ] }} ] }}"#
        );
        let frame = render_text(&json);
        let mut widest = 0;
        for i in 0..h {
            let mut row = 0;
            for j in 0..w {
                // The pixel's point on the image plane, from §4.5's formulas.
                let x = (f64::from(j) - f64::from(w - 1) / 2.0) * p - cx;
                let y = (f64::from(h - 1) / 2.0 - f64::from(i)) * p - cy;
                let d2 = x * x + y * y;
                let px = frame.at(i, j);
                row += usize::from(px.block == 1);
                if (d2 - radius * radius).abs() < 1e-9 {
                    continue;
                }
                assert_eq!(px.block == 1, d2 < radius * radius, "pixel ({i},{j}), z {z}");
                if d2 < radius * radius {
                    let t = 10.0 - z - (radius * radius - d2).sqrt();
                    assert!((f64::from(px.depth) - t).abs() < 1e-5 * t, "Z {} vs {t}", px.depth);
                }
            }
            widest = widest.max(row);
        }
        assert!((widest as f64 - 2.0 * radius / p).abs() <= 1.0, "{widest} pixels vs {}", 2.0 * radius / p);
    }
}
