//! Shading against analytic values (SPEC §5): ambient plus Lambert, and
//! shadows from opaque and transparent blockers.

use crate::geom::{add, dot, mul, prod, sub, unit, Cam, V};
use crate::support::{rendered, tempdir, write_scene, Exr};

/// Parameters `t` where `e + t d` (d unit) crosses the sphere, if it does clearly;
/// `Err(())` when too close to tangent to call.
fn sphere_span(e: V, d: V, c: V, r: f64) -> Result<Option<(f64, f64)>, ()> {
    let oc = sub(e, c);
    let b = dot(d, oc);
    let disc = b * b - (dot(oc, oc) - r * r);
    if disc.abs() < 1e-4 * r * r {
        return Err(());
    }
    Ok((disc > 0.0).then(|| (-b - disc.sqrt(), -b + disc.sqrt())))
}

fn rgb(img: &Exr, i: usize, j: usize) -> V {
    [img.at("R", i, j), img.at("G", i, j), img.at("B", i, j)]
}

fn close(got: V, want: V, what: &str) {
    for k in 0..3 {
        assert!((got[k] - want[k]).abs() <= 2e-6 * (1.0 + want[k].abs()), "{what}: {got:?} vs {want:?}");
    }
}

#[test]
fn diffuse_sphere_matches_lambert() {
    let cam = Cam { e: [0.0, 0.0, 5.0], d: [0.0, 0.0, -1.0], u: [0.0, 1.0, 0.0], w: 32, h: 24, angle: 50.0 };
    let (e, w, h) = (cam.e, cam.w, cam.h);
    let (sa, ma, md, ld) = ([0.1, 0.2, 0.3], [0.2, 0.3, 0.4], [0.5, 0.6, 0.7], [0.9, 0.8, 0.7]);
    let light = [3.0, 4.0, 5.0];
    let cam_json = cam.json();
    let json = format!(
        r#"{{ {cam_json},
             "settings": {{ "ambient": {sa:?}, "background": [0.25, 0.5, 0.75] }},
             "lights": [ {{ "position": {light:?}, "diffuse": {ld:?}, "specular": [5, 5, 5] }} ],
             "materials": {{ "matte": {{ "ambient": {ma:?}, "diffuse": {md:?} }} }},
             "blocks": [ {{ "name": "ball", "material": "matte", "objects": [ {{ "sphere": {{}} }} ] }} ] }}"#
    );
    let dir = tempdir();
    let img = rendered(dir.path(), &write_scene(dir.path(), "lambert.json", &json));
    let mut lit = 0;
    for i in 0..h {
        for j in 0..w {
            let ray = cam.ray(i, j);
            let (iu, ju) = (i as usize, j as usize);
            match sphere_span(e, ray, [0.0; 3], 1.0) {
                Err(()) => {}
                Ok(None) => close(rgb(&img, iu, ju), [0.25, 0.5, 0.75], "background"),
                Ok(Some((t, _))) => {
                    let x = add(e, mul(t, ray));
                    let nl = dot(x, unit(sub(light, x))).max(0.0);
                    lit += usize::from(nl > 0.0);
                    let want = add(prod(ma, sa), mul(nl, prod(md, ld)));
                    close(rgb(&img, iu, ju), want, &format!("pixel ({i},{j})"));
                }
            }
        }
    }
    assert!(lit > 50, "{lit} lit pixels");
}

/// A floor under a ball, lit from above: floor pixels are ambient plus
/// Lambert times what the ball lets through on the way to the light.
fn shadow_case(transparent: bool, transmit: V) {
    let cam = Cam { e: [0.0, 3.0, 6.0], d: [0.0, -3.0, -6.0], u: [0.0, 1.0, 0.0], w: 40, h: 30, angle: 50.0 };
    let (e, w, h) = (cam.e, cam.w, cam.h);
    let (sa, ma, md) = ([0.1, 0.1, 0.1], [0.3, 0.3, 0.3], [0.6, 0.5, 0.4]);
    let (light, c, r) = ([0.5, 5.0, 0.3], [0.0, 1.2, 0.0], 0.7);
    let cam_json = cam.json();
    let json = format!(
        r#"{{ {cam_json},
             "settings": {{ "ambient": {sa:?} }},
             "lights": [ {{ "position": {light:?} }} ],
             "materials": {{ "floor": {{ "ambient": {ma:?}, "diffuse": {md:?} }},
                            "ball": {{ "diffuse": [0.5, 0.5, 0.5], "transmit": {transmit:?}, "ior": 1.0 }} }},
             "blocks": [ {{ "name": "floor", "material": "floor",
                            "objects": [ {{ "halfspace": [0, 1, 0, 0] }}, {{ "halfspace": [0, -1, 0, -1] }},
                                         {{ "halfspace": [1, 0, 0, -10] }}, {{ "halfspace": [-1, 0, 0, -10] }},
                                         {{ "halfspace": [0, 0, 1, -10] }}, {{ "halfspace": [0, 0, -1, -10] }} ] }},
                         {{ "name": "ball", "material": "ball", "transparent": {transparent},
                            "objects": [ {{ "sphere": {{ "radius": {r:?}, "center": {c:?} }} }} ] }} ] }}"#
    );
    let dir = tempdir();
    let img = rendered(dir.path(), &write_scene(dir.path(), "shadow.json", &json));
    let (mut shadowed, mut open) = (0, 0);
    for i in 0..h {
        for j in 0..w {
            let ray = cam.ray(i, j);
            // Only floor pixels seen directly (not through or past the ball).
            if !matches!(sphere_span(e, ray, c, r), Ok(None)) || ray[1] >= 0.0 {
                continue;
            }
            let t = -e[1] / ray[1];
            let x = add(e, mul(t, ray));
            if x[0].abs() > 9.0 || x[2].abs() > 9.0 {
                continue;
            }
            let to_light = sub(light, x);
            let l = unit(to_light);
            let pass = match sphere_span(x, l, c, r) {
                Err(()) => continue,
                Ok(Some((t0, _))) if t0 > 0.0 && t0 < dot(to_light, to_light).sqrt() => {
                    shadowed += 1;
                    transmit
                }
                Ok(_) => {
                    open += 1;
                    [1.0; 3]
                }
            };
            let want = add(prod(ma, sa), mul(l[1], prod(md, pass)));
            let (iu, ju) = (i as usize, j as usize);
            assert_eq!(img.at("id.block", iu, ju), 1.0);
            close(rgb(&img, iu, ju), want, &format!("floor pixel ({i},{j})"));
        }
    }
    assert!(shadowed > 10 && open > 100, "{shadowed} shadowed, {open} open");
}

#[test]
fn opaque_ball_casts_a_full_shadow() {
    shadow_case(false, [0.0; 3]);
}

#[test]
fn transparent_ball_attenuates_by_transmit() {
    shadow_case(true, [0.5, 0.25, 0.1]);
}
