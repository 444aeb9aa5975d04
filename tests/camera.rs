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
