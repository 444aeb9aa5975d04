//! Shading against analytic values (docs/model.md §5.2, §5.3): ambient plus Lambert, and
//! shadows from opaque and transparent blockers.

use crate::geom::{add, dot, mul, prod, sub, unit, Cam, V};
use crate::support::{render_frame, rendered, tempdir, world, write_scene, Exr};

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

const NO_LIGHT_WALLS: &str = r#""settings": { "ambient": [1, 1, 1], "max_depth": 5 },
    "materials": { "glass": { "transmit": [1, 1, 1], "ior": 1.5 },
                   "red": { "ambient": [1, 0, 0] }, "blue": { "ambient": [0, 0, 1] }, "green": { "ambient": [0, 1, 0] } }"#;

/// Refracts unit `d` at a surface with unit normal `n` facing against `d`.
fn snell(d: V, n: V, eta: f64) -> V {
    let cos_i = -dot(d, n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    assert!(k > 0.0);
    add(mul(eta, d), mul(eta * cos_i - k.sqrt(), n))
}

#[test]
fn a_tilted_slab_shifts_the_view_by_snells_law() {
    // Eye at the origin looking down -z at a wall at z = -10: red for x < 0,
    // blue for x > 0. Between them a glass slab (ior 1.5) tilted by 40°
    // about y, 2 units thick. Which colour a pixel shows is decided by
    // where the twice-refracted ray meets the wall.
    let cam = Cam { e: [0.0; 3], d: [0.0, 0.0, -1.0], u: [0.0, 1.0, 0.0], w: 64, h: 8, angle: 40.0 };
    let (s, c) = 40f64.to_radians().sin_cos();
    let nrm = [s, 0.0, c];
    let json = format!(
        r#"{{ {}, {NO_LIGHT_WALLS},
             "blocks": [ {{ "name": "slab", "material": "glass", "transparent": true,
                            "objects": [ {{ "halfspace": [{s:?}, 0, {c:?}, 1] }}, {{ "halfspace": [{:?}, 0, {:?}, -3] }} ] }},
                         {{ "name": "left", "material": "red", "objects": [ {{ "halfspace": [0, 0, 1, 10] }}, {{ "halfspace": [1, 0, 0, 0] }} ] }},
                         {{ "name": "right", "material": "blue", "objects": [ {{ "halfspace": [0, 0, 1, 10] }}, {{ "halfspace": [-1, 0, 0, 0] }} ] }} ] }}"#,
        cam.json(),
        -s,
        -c
    );
    let dir = tempdir();
    let img = rendered(dir.path(), &write_scene(dir.path(), "slab.json", &json));
    let (mut red, mut blue) = (0, 0);
    let mut straight_would_differ = 0;
    for i in 0..cam.h {
        for j in 0..cam.w {
            let d = cam.ray(i, j);
            // Into the slab through the plane nrm·x = -1, out through nrm·x = -3.
            let p1 = mul(-1.0 / dot(nrm, d), d);
            let d1 = snell(d, nrm, 1.0 / 1.5);
            let p2 = add(p1, mul((-3.0 - dot(nrm, p1)) / dot(nrm, d1), d1));
            let d2 = snell(d1, nrm, 1.5);
            let x = p2[0] + (-10.0 - p2[2]) / d2[2] * d2[0];
            let x_straight = d[0] * (-10.0 / d[2]);
            if x.abs() < 0.05 {
                continue;
            }
            let want = if x < 0.0 { [1.0, 0.0, 0.0] } else { [0.0, 0.0, 1.0] };
            if x < 0.0 {
                red += 1;
            } else {
                blue += 1;
            }
            if (x < 0.0) != (x_straight < 0.0) {
                straight_would_differ += 1;
            }
            close(rgb(&img, i as usize, j as usize), want, &format!("pixel ({i},{j}), wall x = {x}"));
        }
    }
    assert!(
        red > 20 && blue > 20 && straight_would_differ >= 8,
        "{red} red, {blue} blue, {straight_would_differ} shifted"
    );
}

#[test]
fn a_prism_reflects_totally_inside() {
    // A right-angled glass prism: rays entering its front face head-on meet
    // the hypotenuse at 45°, beyond the critical angle asin(1/1.5) = 41.8°,
    // reflect totally towards -x and leave through the side face onto the
    // green wall. The red wall straight behind is not seen.
    let cam = Cam { e: [0.0, 0.0, 3.0], d: [0.0, 0.0, -1.0], u: [0.0, 1.0, 0.0], w: 41, h: 41, angle: 30.0 };
    let json = format!(
        r#"{{ {}, {NO_LIGHT_WALLS},
             "blocks": [ {{ "name": "prism", "material": "glass", "transparent": true,
                            "objects": [ {{ "halfspace": [0, 0, 1, 2] }}, {{ "halfspace": [1, 0, -1, -3] }}, {{ "halfspace": [-1, 0, 0, -1] }},
                                         {{ "halfspace": [0, 1, 0, -1] }}, {{ "halfspace": [0, -1, 0, -1] }} ] }},
                         {{ "name": "back", "material": "red", "objects": [ {{ "halfspace": [0, 0, 1, 10] }} ] }},
                         {{ "name": "side", "material": "green", "objects": [ {{ "halfspace": [1, 0, 0, 5] }} ] }} ] }}"#,
        cam.json()
    );
    let dir = tempdir();
    let img = rendered(dir.path(), &write_scene(dir.path(), "prism.json", &json));
    let mut checked = 0;
    for i in 0..cam.h {
        for j in 0..cam.w {
            // Rays within 3° of the axis: the hypotenuse angle stays within 45° ± 2°.
            if dot(cam.ray(i, j), cam.d).acos().to_degrees() > 3.0 {
                continue;
            }
            checked += 1;
            close(rgb(&img, i as usize, j as usize), [0.0, 1.0, 0.0], &format!("pixel ({i},{j})"));
        }
    }
    assert!(checked > 50, "{checked}");
}

#[test]
fn index_one_glass_is_invisible() {
    // A transparent block with ior 1, transmit 1 and no surface terms bends
    // nothing and dims nothing: colours equal the scene without it.
    let base = |extra: &str| {
        format!(
            r#"{{ "camera": {{ "eye": [0, 2, 6], "direction": [0, -2, -6], "width": 32, "height": 24 }},
                 "lights": [ {{ "position": [2, 5, 3] }} ],
                 "materials": {{ "air": {{ "transmit": [1, 1, 1] }}, "m": {{ "ambient": [0.2, 0.2, 0.2], "diffuse": [0.7, 0.5, 0.3], "specular": [0.5, 0.5, 0.5] }} }},
                 "blocks": [ {extra}
                   {{ "name": "ball", "material": "m", "objects": [ {{ "sphere": {{ "radius": 0.8, "center": [0, 0.8, 0] }} }} ] }},
                   {{ "name": "floor", "material": "m", "objects": [ {{ "halfspace": [0, 1, 0, 0] }}, {{ "halfspace": [0, -1, 0, -1] }} ] }} ] }}"#
        )
    };
    let dir = tempdir();
    let plain = rendered(dir.path(), &write_scene(dir.path(), "plain.json", &base("")));
    let with = rendered(
        dir.path(),
        &write_scene(
            dir.path(),
            "with.json",
            &base(
                r#"{ "name": "air", "material": "air", "transparent": true, "objects": [ { "sphere": { "radius": 1.5, "center": [0.5, 1, 1] } } ] },"#,
            ),
        ),
    );
    let mut through = 0;
    for i in 0..24 {
        for j in 0..32 {
            through += usize::from(with.at("id.block", i, j) == 1.0);
            close(rgb(&with, i, j), rgb(&plain, i, j), &format!("pixel ({i},{j})"));
        }
    }
    assert!(through > 50, "only {through} pixels look through the invisible block");
}

#[test]
fn samples_average_colour_and_coverage_but_keep_centre_aovs() {
    // Flat colours: a pure-ambient ball on a background. With 4×4 samples
    // every pixel is the coverage-weighted mix of the two colours.
    let json = r#"{ "camera": { "eye": [0, 0, 4], "direction": [0, 0, -1], "width": 24, "height": 18 },
                    "settings": { "ambient": [1, 1, 1], "background": [0, 0.5, 1], "samples": 4 },
                    "materials": { "flat": { "ambient": [1, 0.25, 0] } },
                    "blocks": [ { "material": "flat", "objects": [ { "sphere": {} } ] } ] }"#;
    let dir = tempdir();
    let aa = rendered(dir.path(), &write_scene(dir.path(), "aa.json", json));
    let one =
        rendered(dir.path(), &write_scene(dir.path(), "one.json", &json.replace(r#""samples": 4"#, r#""samples": 1"#)));
    let mut partial = 0;
    for i in 0..18 {
        for j in 0..24 {
            let a = aa.at("A", i, j);
            assert_eq!(a * 16.0, (a * 16.0).round(), "coverage {a} is not k/16");
            partial += usize::from(a > 0.0 && a < 1.0);
            let want = add(mul(a, [1.0, 0.25, 0.0]), mul(1.0 - a, [0.0, 0.5, 1.0]));
            close(rgb(&aa, i, j), want, &format!("pixel ({i},{j}), coverage {a}"));
            for ch in ["Z", "N.X", "N.Y", "N.Z", "id.block", "id.object"] {
                assert_eq!(aa.at(ch, i, j), one.at(ch, i, j), "{ch} at ({i},{j})");
            }
        }
    }
    assert!(partial > 10, "{partial} edge pixels");
}

/// Along `e + t d`, 0 < t < len: the owners of the pieces inside two
/// transparent balls (the first has priority), in order, as `0` or `1`,
/// with `None` when a boundary is too close to call.
fn owners_along(e: V, d: V, len: f64, balls: &[(V, f64); 2]) -> Option<Vec<usize>> {
    let mut cuts = vec![0.0, len];
    let mut spans = [None, None];
    for (k, (c, r)) in balls.iter().enumerate() {
        if let Some((a, b)) = sphere_span(e, d, *c, *r).ok()? {
            for t in [a, b] {
                if (t - 0.0).abs() < 1e-6 || (t - len).abs() < 1e-6 {
                    return None;
                }
                if t > 0.0 && t < len {
                    cuts.push(t);
                }
            }
            spans[k] = Some((a, b));
        }
    }
    cuts.sort_by(f64::total_cmp);
    if cuts.windows(2).any(|w| w[1] - w[0] < 1e-6) {
        return None;
    }
    let mut owners: Vec<Option<usize>> = cuts
        .windows(2)
        .map(|w| {
            let m = 0.5 * (w[0] + w[1]);
            (0..2).find(|k| spans[*k].is_some_and(|(a, b)| a < m && m < b))
        })
        .collect();
    owners.dedup();
    Some(owners.into_iter().map(|o| o.map_or(9, |k| k)).collect())
}

/// Two overlapping transparent balls over a floor. A shadow ray is
/// attenuated once per passage through a medium: through two balls of the
/// same material in one go, once; through two different materials, once each.
fn two_ball_shadow(same: bool) {
    let cam = Cam { e: [0.0, 4.0, 5.0], d: [0.0, -4.0, -5.0], u: [0.0, 1.0, 0.0], w: 48, h: 36, angle: 50.0 };
    let e = cam.e;
    let light = [0.2, 6.0, 0.1];
    let balls = [([-0.35, 1.5, 0.0], 0.6), ([0.35, 1.5, 0.0], 0.6)];
    let t = [0.5, 0.5, 0.5];
    let (m1, m2) = if same { ("tint", "tint") } else { ("tint", "tint2") };
    let cam_json = cam.json();
    let json = format!(
        r#"{{ {cam_json}, "settings": {{ "ambient": [0, 0, 0] }}, "lights": [ {{ "position": {light:?} }} ],
             "materials": {{ "floor": {{ "diffuse": [1, 1, 1] }}, "tint": {{ "transmit": {t:?} }}, "tint2": {{ "transmit": {t:?} }} }},
             "blocks": [ {{ "name": "floor", "material": "floor", "objects": [ {{ "halfspace": [0, 1, 0, 0] }}, {{ "halfspace": [0, -1, 0, -1] }} ] }},
                         {{ "name": "a", "material": "{m1}", "transparent": true, "objects": [ {{ "sphere": {{ "radius": 0.6, "center": {:?} }} }} ] }},
                         {{ "name": "b", "material": "{m2}", "transparent": true, "objects": [ {{ "sphere": {{ "radius": 0.6, "center": {:?} }} }} ] }} ] }}"#,
        balls[0].0, balls[1].0
    );
    let dir = tempdir();
    let img = rendered(dir.path(), &write_scene(dir.path(), "two.json", &json));
    let mut seen = [0usize; 3];
    for i in 0..cam.h {
        for j in 0..cam.w {
            let ray = cam.ray(i, j);
            if ray[1] >= 0.0 || balls.iter().any(|(c, r)| !matches!(sphere_span(e, ray, *c, *r), Ok(None))) {
                continue;
            }
            let x = add(e, mul(-e[1] / ray[1], ray));
            let to_light = sub(light, x);
            let dist = dot(to_light, to_light).sqrt();
            let l = unit(to_light);
            let Some(owners) = owners_along(x, l, dist, &balls) else { continue };
            // Passages: maximal runs inside the balls; with one material a
            // run counts once, with two each owner change inside a run counts.
            let mut factors = 0i32;
            let mut previous: Option<usize> = None;
            for o in owners {
                if o == 9 {
                    previous = None;
                    continue;
                }
                if previous.is_none() || !same {
                    factors += 1;
                }
                previous = Some(o);
            }
            seen[factors.min(2) as usize] += 1;
            let want = mul(l[1] * 0.5f64.powi(factors), [1.0, 1.0, 1.0]);
            close(rgb(&img, i as usize, j as usize), want, &format!("floor pixel ({i},{j}), {factors} passages"));
        }
    }
    // Open floor and single passages always occur; two factors only where
    // the materials differ (the light is above the overlap, so no shadow
    // ray passes the two balls separately).
    assert!(seen[0] > 5 && seen[1] > 5 && (same || seen[2] > 5), "cases seen: {seen:?}");
}

#[test]
fn one_medium_attenuates_a_shadow_once() {
    two_ball_shadow(true);
}

#[test]
fn two_media_attenuate_a_shadow_once_each() {
    two_ball_shadow(false);
}

/// Found by fuzzing (`fuzz/fuzz_targets/scene.rs`): a light of 1e300 on a
/// diffuse reflectance of 1e300 overflows to ∞, and a zero weight times that
/// ∞ (here `reflect` in red) made a NaN pixel. A zero factor is no light.
#[test]
fn overflowing_colours_give_infinity_not_nan() {
    // The camera inside a ball of radius 10 looks along -z at its wall; the
    // light at (0, 0, 1) shines on it head on, unshadowed. Red: diffuse
    // 1e300 × 1e300 overflows; green: only the mirror (weight 1) over a wall
    // with no green; blue: nothing.
    let json = r#"{ "camera": { "eye": [0, 0, 0], "direction": [0, 0, -1], "width": 3, "height": 3 },
        "lights": [ { "position": [0, 0, 1], "color": [1e300, 1e300, 1e300] } ],
        "materials": { "m": { "diffuse": [1e300, 0, 0], "reflect": [0, 1, 0] } },
        "blocks": [ { "material": "m", "objects": [ { "sphere": { "radius": 10 } } ] } ] }"#;
    let dir = tempdir();
    let frame = render_frame(&world(&write_scene(dir.path(), "overflow.json", json), None));
    for p in frame.pixels() {
        assert!(p.rgb.iter().all(|c| !c.is_nan()), "{p:?}");
    }
    assert_eq!(frame.at(1, 1).rgb, [f32::INFINITY, 0.0, 0.0]);
}

/// A glass ball inside a mirror shell: each glass hit splits into a reflected
/// and a refracted ray and the mirror returns both, so the ray tree grows by
/// about 1.6x per bounce (1.44 M rays for this one pixel at depth 26, months
/// at the allowed 64). Branches whose weight (the product of `reflect` and
/// `transmit` along the path) falls below `MIN_PATH_WEIGHT` are not followed,
/// which keeps the count small and nearly flat in `max_depth`.
#[test]
fn mirrors_around_glass_do_not_explode_the_ray_tree() {
    let scene = |depth: u32| {
        format!(
            r#"{{ "camera": {{ "eye": [0, 0, 2.5], "direction": [0, 0.05, -1], "width": 1, "height": 1 }},
            "settings": {{ "max_depth": {depth} }},
            "lights": [ {{ "position": [0, 2, 2] }} ],
            "materials": {{
              "mirror": {{ "diffuse": [0.1, 0.1, 0.1], "reflect": [1, 1, 1] }},
              "glass": {{ "diffuse": [0, 0, 0], "reflect": [0.05, 0.05, 0.05], "transmit": [0.9, 0.9, 0.9], "ior": 1.5 }} }},
            "blocks": [
              {{ "name": "ball", "material": "glass", "transparent": true, "objects": [ {{ "sphere": {{}} }} ] }},
              {{ "name": "shell", "material": "mirror", "objects": [
                  {{ "sphere": {{ "radius": 3.2 }} }},
                  {{ "sphere": {{ "radius": 3 }}, "complement": true }} ] }} ] }}"#
        )
    };
    let dir = tempdir();
    for depth in [26, 64] {
        let w = world(&write_scene(dir.path(), &format!("deep{depth}.json"), &scene(depth)), None);
        let (frame, stats) = render::frame::render(&w, render::frame::Options::default(), &|| {}).unwrap();
        assert!(stats.rays < 50_000, "depth {depth}: {} rays for one pixel", stats.rays);
        assert!(frame.pixel(0).rgb.iter().all(|c| c.is_finite() && *c > 0.0), "{:?}", frame.pixel(0));
    }
}
