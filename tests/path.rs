//! The path integrator against analytic answers (docs/model.md §5.10):
//! furnaces, a point light and a sphere light over a plane, a glass ball
//! in a uniform sky; the same expectations with and without Russian
//! roulette and next-event estimation; adaptive sampling's stopping rule;
//! images independent of the thread count.

use render::frame::{Frame, Options};
use render::path::PathOptions;

fn world(json: &str) -> render::world::World {
    render::format::SceneFile::from_json(json).unwrap().to_world().unwrap()
}

fn render_with(json: &str, path: PathOptions, threads: Option<usize>) -> Frame {
    let options = Options { threads, path, ..Options::default() };
    render::frame::render(&world(json), options, &|| {}).unwrap().0
}

fn render(json: &str) -> Frame {
    render_with(json, PathOptions::default(), None)
}

/// The mean of the red channel over the pixels `keep` selects and its
/// standard error, the pixels taken as independent estimates (each has its
/// own random numbers).
fn mean_and_error(frame: &Frame, keep: impl Fn(usize) -> bool) -> (f64, f64) {
    let v: Vec<f64> = (0..frame.len()).filter(|&k| keep(k)).map(|k| f64::from(frame.rgb[0][k])).collect();
    assert!(v.len() > 10, "too few pixels: {}", v.len());
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// `got` within 4.5 standard errors of `want` (a correct integrator fails
/// with probability below 10⁻⁵; the seeds are fixed, so a failure repeats).
fn assert_agrees((mean, se): (f64, f64), want: f64, what: &str) {
    assert!((mean - want).abs() <= 4.5 * se + 1e-6 * want.abs(), "{what}: {mean} ± {se}, want {want}");
}

/// A convex diffuse ball of albedo ρ under a sky of radiance `L`: every
/// path bounces once and escapes, so every sample of a covered pixel is
/// exactly `ρ L`, and a partly covered pixel is `L (1 − A (1 − ρ))`.
#[test]
fn a_diffuse_ball_under_a_constant_sky_is_albedo_times_sky() {
    let frame = render(
        r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 40, "height": 30 },
             "settings": { "integrator": "path", "spp": 8, "background": [2, 1, 0.5] },
             "materials": { "m": { "diffuse": [0.25, 0.5, 0.75] } },
             "blocks": [ { "material": "m", "objects": [ { "sphere": {} } ] } ] }"#,
    );
    let sky = [2.0f32, 1.0, 0.5];
    let albedo = [0.25f32, 0.5, 0.75];
    let mut covered = 0;
    for p in frame.pixels() {
        covered += usize::from(p.alpha == 1.0);
        for c in 0..3 {
            let want = sky[c] * (1.0 - p.alpha * (1.0 - albedo[c]));
            assert!((p.rgb[c] - want).abs() <= 1e-6 * sky[c], "{p:?}: channel {c} want {want}");
        }
    }
    assert!(covered > 100);
}

/// Inside a closed diffuse shell of albedo ρ that emits `E`, the radiance
/// everywhere is `E/(1 − ρ)`; Russian roulette and next-event estimation
/// change the noise, not that expectation (`max_depth` 64 leaves out
/// `ρ⁶⁶ ≈ 10⁻²⁰` of it).
#[test]
fn a_closed_furnace_converges_to_emission_over_one_minus_albedo() {
    let scene = r#"{ "camera": { "eye": [0, 0, 0], "direction": [0, 0, -1], "width": 16, "height": 12 },
        "settings": { "integrator": "path", "spp": 32, "max_depth": 64 },
        "materials": { "wall": { "diffuse": [0.5, 0.5, 0.5], "emission": [1.5, 1.5, 1.5] } },
        "blocks": [ { "material": "wall",
                      "objects": [ { "quadric": [-1, -1, -1, 0, 0, 0, 0, 0, 0, 100] }, { "sphere": { "radius": 12 } } ] } ] }"#;
    for (next_event, roulette) in [(true, true), (false, true), (true, false), (false, false)] {
        let frame = render_with(scene, PathOptions { next_event, roulette }, None);
        assert_agrees(mean_and_error(&frame, |_| true), 3.0, &format!("nee {next_event}, roulette {roulette}"));
    }
}

/// A lossless glass ball inside the closed furnace changes nothing: the
/// radiance is `E/(1 − ρ)` on the wall seen directly and through the ball,
/// along paths that alternate between the diffuse wall (light samples,
/// blocked by the glass, and BSDF samples weighed against them) and the
/// glass (refraction, Fresnel reflection inside and out).
#[test]
fn a_glass_ball_in_the_closed_furnace_changes_nothing() {
    let frame = render(
        r#"{ "camera": { "eye": [0, 0, 6], "direction": [0, 0, -1], "width": 24, "height": 18, "aperture": 80 },
             "settings": { "integrator": "path", "spp": 32, "max_depth": 64 },
             "materials": { "wall": { "diffuse": [0.5, 0.5, 0.5], "emission": [1.5, 1.5, 1.5] },
                            "glass": { "transmit": [1, 1, 1], "ior": 1.5 } },
             "blocks": [ { "material": "glass", "transparent": true, "objects": [ { "sphere": { "radius": 2 } } ] },
                         { "material": "wall",
                           "objects": [ { "quadric": [-1, -1, -1, 0, 0, 0, 0, 0, 0, 100] }, { "sphere": { "radius": 12 } } ] } ] }"#,
    );
    assert_agrees(mean_and_error(&frame, |k| frame.block[k] == 1), 3.0, "through the ball");
    assert_agrees(mean_and_error(&frame, |k| frame.block[k] == 2), 3.0, "the wall");
}

/// A plane of albedo ρ seen under a point light of intensity `I` at height
/// `h` straight above the point the camera looks at: `L = ρ/π · I/h²`
/// (the light's radiant intensity, W/sr, falls off with `h²`). Nothing else
/// lights the plane, and a sample carries no randomness but the pixel's
/// position, so the centre pixel is within the variation of the falloff
/// across one small pixel.
#[test]
fn a_point_light_is_an_intensity_falling_off_with_the_squared_distance() {
    let frame = render(
        r#"{ "camera": { "eye": [0, 3, 4], "direction": [0, -3, -4], "width": 9, "height": 9, "aperture": 0.1 },
             "settings": { "integrator": "path", "spp": 4 },
             "lights": [ { "position": [0, 2, 0], "color": [8, 8, 8] } ],
             "materials": { "m": { "diffuse": [0.6, 0.6, 0.6] } },
             "blocks": [ { "material": "m", "objects": [ { "halfspace": [0, 1, 0, 0] } ] } ] }"#,
    );
    let want = 0.6 / std::f64::consts::PI * 8.0 / 4.0;
    let got = f64::from(frame.at(4, 4).rgb[0]);
    assert!((got - want).abs() < 1e-3 * want, "{got} against {want}");
}

/// A diffuse plane of albedo ρ under a sphere of radius `r` and radiance
/// `Le` whose centre is `d` above the point seen: the irradiance is
/// `π Le (r/d)²`, so `L = ρ Le (r/d)²`. With next-event estimation the
/// light is sampled by its exact solid angle; without it, only BSDF
/// samples find it: both must agree with the formula, and also with a
/// `max_depth` of 0 (direct light only: the plane cannot see itself, and the
/// black lamp reflects nothing).
#[test]
fn a_sphere_light_gives_the_irradiance_of_its_solid_angle() {
    let scene = |spp: u32| {
        format!(
            r#"{{ "camera": {{ "eye": [0, 3, 4], "direction": [0, -3, -4], "width": 12, "height": 12, "aperture": 0.2 }},
                 "settings": {{ "integrator": "path", "spp": {spp}, "max_depth": 0 }},
                 "materials": {{ "m": {{ "diffuse": [0.6, 0.6, 0.6] }}, "lamp": {{ "emission": [10, 10, 10] }} }},
                 "blocks": [ {{ "material": "lamp", "objects": [ {{ "sphere": {{ "radius": 0.3, "center": [0, 2, 0] }} }} ] }},
                             {{ "material": "m", "objects": [ {{ "halfspace": [0, 1, 0, 0] }} ] }} ] }}"#
        )
    };
    // Over the pixels, the irradiance varies by under 10⁻³ relative.
    let want = 0.6 * 10.0 * (0.3f64 / 2.0).powi(2);
    let with = render_with(&scene(16), PathOptions::default(), None);
    assert_agrees(mean_and_error(&with, |_| true), want, "light samples");
    let (_, se) = mean_and_error(&with, |_| true);
    assert!(se < 0.01 * want, "light samples of an exact solid angle are nearly noiseless: ± {se}");
    let without = render_with(&scene(256), PathOptions { next_event: false, roulette: true }, None);
    assert_agrees(mean_and_error(&without, |_| true), want, "BSDF samples only");
}

/// The error falls at least as fast as `spp^-½`, Monte Carlo's rate (the
/// sampler's stratified pairs make it faster; a bias would make it level
/// off): the RMSE of the pixels against the analytic radiance of the
/// sphere-lit plane (found by BSDF samples only, so that there is noise to
/// measure), at 4 to 256 samples per pixel. The least-squares slope of log
/// RMSE against log spp is below −0.45 (−½ less the scatter of an RMSE over
/// 400 pixels).
#[test]
fn the_error_falls_as_one_over_the_root_of_the_samples() {
    let want = 0.6 * 10.0 * (0.3f64 / 2.0).powi(2);
    let points: Vec<(f64, f64)> = [4u32, 16, 64, 256]
        .iter()
        .map(|&spp| {
            let scene = format!(
                r#"{{ "camera": {{ "eye": [0, 3, 4], "direction": [0, -3, -4], "width": 20, "height": 20, "aperture": 0.2 }},
                     "settings": {{ "integrator": "path", "spp": {spp}, "max_depth": 0, "seed": {spp} }},
                     "materials": {{ "m": {{ "diffuse": [0.6, 0.6, 0.6] }}, "lamp": {{ "emission": [10, 10, 10] }} }},
                     "blocks": [ {{ "material": "lamp", "objects": [ {{ "sphere": {{ "radius": 0.3, "center": [0, 2, 0] }} }} ] }},
                                 {{ "material": "m", "objects": [ {{ "halfspace": [0, 1, 0, 0] }} ] }} ] }}"#
            );
            let frame = render_with(&scene, PathOptions { next_event: false, roulette: true }, None);
            let mse = frame.rgb[0].iter().map(|&r| (f64::from(r) - want).powi(2)).sum::<f64>() / frame.len() as f64;
            (f64::from(spp).ln(), mse.sqrt().ln())
        })
        .collect();
    let n = points.len() as f64;
    let (mx, my) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let slope = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / points.iter().map(|(x, _)| (x - mx).powi(2)).sum::<f64>();
    assert!(slope < -0.45, "slope {slope}: {points:?}");
}

/// A lossless glass ball (exact Fresnel, refraction, total internal
/// reflection) in a sky of uniform radiance `L` is invisible: every path
/// that escapes carries `L` (the `(ηi/ηt)²` factors of entering and
/// leaving cancel), so the image is `L` in expectation, wherever the ball
/// is. Russian roulette inside the glass only adds noise.
#[test]
fn a_glass_ball_in_a_uniform_sky_is_invisible() {
    let frame = render(
        r#"{ "camera": { "eye": [0, 0, 4], "direction": [0, 0, -1], "width": 24, "height": 18, "aperture": 30 },
             "settings": { "integrator": "path", "spp": 16, "max_depth": 64, "background": [1, 1, 1] },
             "materials": { "glass": { "transmit": [1, 1, 1], "ior": 1.5 } },
             "blocks": [ { "material": "glass", "transparent": true, "objects": [ { "sphere": {} } ] } ] }"#,
    );
    assert_agrees(mean_and_error(&frame, |k| frame.alpha[k] == 1.0), 1.0, "the ball's pixels");
}

/// Adaptive sampling: a pixel stops once its error estimate is within the
/// bound, or at `spp`; never before the minimum. Pixels of the black
/// background (no variance) stop at the minimum; the noisy lit ball takes
/// more. The estimate is checked against the spread of the samples, redone
/// here from independent renders: the error of pixels that stopped early
/// is close to the bound.
#[test]
fn adaptive_sampling_stops_each_pixel_at_its_bound() {
    let scene = r#"{ "camera": { "eye": [0, 0, 5], "direction": [0, 0, -1], "width": 16, "height": 12 },
        "settings": { "integrator": "path", "spp": 512, "noise": 0.05 },
        "materials": { "m": { "diffuse": [0.7, 0.7, 0.7] }, "lamp": { "emission": [4, 4, 4] } },
        "blocks": [ { "material": "lamp", "objects": [ { "sphere": { "radius": 0.5, "center": [2, 2, 1] } } ] },
                    { "material": "m", "objects": [ { "sphere": {} } ] } ] }"#;
    let frame = render(scene);
    assert!(frame.has_adaptive());
    let mut more = 0;
    for p in frame.pixels() {
        assert!((16..=512).contains(&p.spp), "{p:?}");
        assert!(p.spp == 512 || p.error <= 0.05, "{p:?}");
        if p.alpha == 0.0 {
            assert_eq!((p.spp, p.error), (16, 0.0), "the black background: {p:?}");
        }
        more += usize::from(p.spp > 16);
    }
    assert!(more > 20, "the lit ball needs more than the minimum: {more} pixels did");
    // Without `noise`, no adaptive planes.
    assert!(!render(&scene.replace(r#", "noise": 0.05"#, "")).has_adaptive());
}

/// The random numbers are keyed by pixel and sample: one thread or two,
/// the same image, bit for bit; another seed, another image.
#[test]
fn path_images_do_not_depend_on_threads_and_change_with_the_seed() {
    let scene = r#"{ "camera": { "eye": [0, 1, 5], "direction": [0, -1, -5], "width": 20, "height": 14, "lens_radius": 0.1 },
        "settings": { "integrator": "path", "spp": 4, "noise": 0.2 },
        "lights": [ { "position": [3, 4, 3], "color": [20, 20, 20] } ],
        "materials": { "m": { "diffuse": [0.5, 0.6, 0.7], "specular": [0.3, 0.3, 0.3], "shininess": 30 },
                       "glass": { "transmit": [1, 1, 1], "ior": 1.5 }, "lamp": { "emission": [3, 3, 3] } },
        "blocks": [ { "material": "glass", "transparent": true, "objects": [ { "sphere": { "radius": 0.5, "center": [0.6, 0.5, 1] } } ] },
                    { "material": "lamp", "objects": [ { "sphere": { "radius": 0.3, "center": [-1, 2, 0] } } ] },
                    { "material": "m", "objects": [ { "halfspace": [0, 1, 0, 0] } ] } ] }"#;
    let one = render_with(scene, PathOptions::default(), Some(1));
    let two = render_with(scene, PathOptions::default(), Some(2));
    assert_eq!(one, two);
    let other = render(&scene.replace(r#""noise": 0.2"#, r#""noise": 0.2, "seed": 7"#));
    assert_ne!(one.rgb, other.rgb);
}
