//! `Complex::volumes` and `Complex::overlaps` against analytic volumes; the
//! standard error is honest over many seeds; touching and disjoint blocks
//! do not overlap.

use std::f64::consts::PI;

use complex::{Aabb, Block, BlockId, Complex, ComplexError, Estimate, VolumeOptions};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{Quadric, Solid, Transform};

use crate::common::{block, complex, cuboid, hs, translate, O, T};

fn scaled(sx: f64, sy: f64, sz: f64) -> Transform {
    Transform::scale_xyz(Vector3::new(sx, sy, sz)).expect("finite")
}

fn ball(x: f64, r: f64) -> Solid {
    Solid::from(Quadric::sphere().transformed(&scaled(r, r, r).then(&translate(x, 0.0, 0.0))))
}

fn one(solids: Vec<Solid>) -> Complex {
    complex(vec![block("shape", solids, O, 0)])
}

/// The analytic shapes: a name, the block's solids, the exact volume.
fn shapes() -> Vec<(&'static str, Vec<Solid>, f64)> {
    let rotation = Transform::rotate_x_degrees(30.0)
        .expect("finite")
        .then(&Transform::rotate_z_degrees(50.0).expect("finite"))
        .then(&translate(0.3, -0.2, 0.1));
    vec![
        ("sphere", vec![ball(0.0, 1.0)], 4.0 / 3.0 * PI),
        // Semi-axes 2, 1, 1/2, turned and moved: (4/3)π·2·1·½.
        (
            "rotated ellipsoid",
            vec![Solid::from(Quadric::sphere().transformed(&scaled(2.0, 1.0, 0.5).then(&rotation)))],
            4.0 / 3.0 * PI,
        ),
        // Radius 1, height 2.
        (
            "capped cylinder",
            vec![Solid::from(Quadric::tube_z()), hs(0.0, 0.0, -1.0, -1.0), hs(0.0, 0.0, 1.0, -1.0)],
            2.0 * PI,
        ),
        // x² + z² <= y², 1 <= y <= 2: πh(R₁² + R₁R₂ + R₂²)/3.
        (
            "cone frustum",
            vec![Solid::from(Quadric::cone()), hs(0.0, -1.0, 0.0, 1.0), hs(0.0, 1.0, 0.0, -2.0)],
            7.0 / 3.0 * PI,
        ),
        // x² + z² <= y <= 1: πh²/2.
        ("paraboloid cap", vec![Solid::from(Quadric::paraboloid()), hs(0.0, 1.0, 0.0, -1.0)], PI / 2.0),
        // x² + z² <= 1 + y², |y| <= 1: ∫π(1 + y²) dy.
        (
            "hyperboloid segment",
            vec![Solid::from(Quadric::hyperboloid_one_sheet()), hs(0.0, -1.0, 0.0, -1.0), hs(0.0, 1.0, 0.0, -1.0)],
            8.0 / 3.0 * PI,
        ),
        // Radius 1 less radius 1/2.
        (
            "hollow ball",
            vec![ball(0.0, 1.0), Solid::from(Quadric::sphere().transformed(&scaled(0.5, 0.5, 0.5)).complement())],
            7.0 / 6.0 * PI,
        ),
        // The cube [-1, 1]³ less a hole of radius 1/2 through it along z.
        (
            "drilled box",
            {
                let mut s = cuboid([-1.0; 3], [1.0; 3]);
                s.push(Solid::from(Quadric::tube_z().transformed(&scaled(0.5, 0.5, 1.0)).complement()));
                s
            },
            8.0 - PI / 2.0,
        ),
        // Two unit balls with centres 1 apart share two caps of height ½.
        ("lens", vec![ball(0.0, 1.0), ball(1.0, 1.0)], 5.0 / 12.0 * PI),
    ]
}

fn options(tolerance: f64, seed: u64) -> VolumeOptions {
    VolumeOptions { tolerance, seed, ..VolumeOptions::default() }
}

/// `e` is within `rel` of `exact`, and its error is at most `tolerance` relative.
fn assert_close(what: &str, e: Estimate, exact: f64, rel: f64, tolerance: f64) {
    assert!((e.value - exact).abs() <= rel * exact, "{what}: {} vs {exact} (error {})", e.value, e.error);
    assert!(e.error <= tolerance * exact * 1.01, "{what}: error {} above {tolerance} of {exact}", e.error);
}

#[test]
fn analytic_volumes_to_one_part_in_ten_thousand() {
    for (name, solids, exact) in shapes() {
        let v = one(solids).volumes(&options(1e-5, 7)).expect("valid options");
        assert!(v.converged, "{name}");
        let b = v.blocks[0];
        assert_close(name, b.own.expect("bounded"), exact, 1e-4, 1e-5);
        assert_close(name, b.owned.expect("bounded"), exact, 1e-4, 1e-5);
        assert_close(name, v.union.expect("bounded"), exact, 1e-4, 1e-5);
    }
}

#[test]
fn the_priority_rule_splits_two_overlapping_transparent_balls() {
    let ball_v = 4.0 / 3.0 * PI;
    let lens = 5.0 / 12.0 * PI;
    // Transparent both: the first owns itself, the second the rest. An
    // opaque second block takes the lens from a transparent first.
    for (opacity, first, second) in [(T, ball_v, ball_v - lens), (O, ball_v - lens, ball_v)] {
        let c = complex(vec![block("a", vec![ball(0.0, 1.0)], T, 0), block("b", vec![ball(1.0, 1.0)], opacity, 1)]);
        let v = c.volumes(&options(1e-5, 3)).expect("valid options");
        assert_close("first owned", v.blocks[0].owned.expect("bounded"), first, 1e-4, 1e-5);
        assert_close("second owned", v.blocks[1].owned.expect("bounded"), second, 1e-4, 1e-5);
        assert_close("first own", v.blocks[0].own.expect("bounded"), ball_v, 1e-4, 1e-5);
        assert_close("second own", v.blocks[1].own.expect("bounded"), ball_v, 1e-4, 1e-5);
        assert_close("union", v.union.expect("bounded"), 2.0 * ball_v - lens, 1e-4, 1e-5);
    }
}

#[test]
fn three_standard_errors_cover_the_truth_in_99_percent_of_runs() {
    // A coarse tolerance: one round of the default 8,192 lines per seed.
    let shapes = shapes();
    let mut misses = 0;
    let runs = 240;
    for seed in 0..runs {
        let (_, solids, exact) = &shapes[seed as usize % shapes.len()];
        let v = one(solids.clone()).volumes(&options(3e-2, seed)).expect("valid options");
        let e = v.blocks[0].owned.expect("bounded");
        if (e.value - exact).abs() > 3.0 * e.error {
            misses += 1;
        }
    }
    assert!(misses * 100 <= runs, "{misses} of {runs} runs missed by more than 3 standard errors");
}

#[test]
fn the_result_does_not_depend_on_the_thread_count() {
    let c = complex(vec![block("a", vec![ball(0.0, 1.0)], T, 0), block("b", vec![ball(1.0, 1.0)], O, 1)]);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
        pool.install(|| (c.volumes(&options(1e-3, 5)), c.overlaps(&options(1e-3, 5))))
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn unbounded_blocks_have_no_volume_unless_clipped() {
    let c =
        complex(vec![block("ball", vec![ball(0.0, 1.0)], O, 0), block("floor", vec![hs(0.0, 1.0, 0.0, 0.0)], O, 1)]);
    let v = c.volumes(&options(1e-3, 1)).expect("valid options");
    assert_eq!((v.blocks[1].own, v.blocks[1].owned, v.union), (None, None, None));
    // The ball owns itself (it comes first); the box is the ball's.
    let e = v.blocks[0].owned.expect("bounded");
    assert!((e.value - 4.0 / 3.0 * PI).abs() <= 4.0 * e.error);
    // Clipped to [-2, 2]³: the floor is the lower half of the box.
    let bounds = Aabb { min: Point3::new(-2.0, -2.0, -2.0), max: Point3::new(2.0, 2.0, 2.0) };
    let v = c.volumes(&VolumeOptions { bounds: Some(bounds), ..options(1e-3, 1) }).expect("valid options");
    let checks =
        [(v.blocks[1].own, 32.0), (v.blocks[1].owned, 32.0 - 2.0 / 3.0 * PI), (v.union, 32.0 + 2.0 / 3.0 * PI)];
    for (e, exact) in checks {
        let e = e.expect("clipped");
        assert!((e.value - exact).abs() <= 4.0 * e.error, "{} vs {exact}", e.value);
    }
}

#[test]
fn empty_blocks_and_empty_scenes_have_volume_zero() {
    let empty = block("nothing", vec![ball(0.0, 1.0), ball(3.0, 1.0)], O, 0);
    let v = complex(vec![empty]).volumes(&VolumeOptions::default()).expect("valid options");
    assert_eq!(v.blocks[0].own.map(|e| e.value), Some(0.0));
    assert_eq!(v.union.map(|e| e.value), Some(0.0));
    let none = complex(vec![]).volumes(&VolumeOptions::default()).expect("valid options");
    assert_eq!((none.blocks.len(), none.union.map(|e| e.value)), (0, Some(0.0)));
}

#[test]
fn bad_options_are_errors() {
    let c = one(vec![ball(0.0, 1.0)]);
    for tolerance in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        let got = c.volumes(&options(tolerance, 0));
        assert!(matches!(got, Err(ComplexError::BadVolumeOption { option: "tolerance", .. })), "{tolerance}: {got:?}");
    }
    let few = VolumeOptions { replicates: 4, ..VolumeOptions::default() };
    assert!(matches!(c.overlaps(&few), Err(ComplexError::BadVolumeOption { option: "replicates", .. })));
    let inverted = Aabb { min: Point3::new(1.0, 0.0, 0.0), max: Point3::new(0.0, 1.0, 1.0) };
    let clip = VolumeOptions { bounds: Some(inverted), ..VolumeOptions::default() };
    assert_eq!(c.volumes(&clip), Err(ComplexError::BadVolumeBounds));
}

/// The overlapping pairs as `(a, b, exact volume)` checks.
fn check_overlaps(blocks: Vec<Block>, expected: &[(u32, u32, f64)]) {
    let c = complex(blocks);
    let found = c.overlaps(&options(1e-3, 11)).expect("valid options");
    let pairs: Vec<(u32, u32)> = found.pairs.iter().map(|p| (p.a.0, p.b.0)).collect();
    let want: Vec<(u32, u32)> = expected.iter().map(|&(a, b, _)| (a, b)).collect();
    assert_eq!(pairs, want);
    for (p, &(_, _, exact)) in found.pairs.iter().zip(expected) {
        assert!((p.volume.value - exact).abs() <= 4.0 * p.volume.error.max(1e-12), "{} vs {exact}", p.volume.value);
        assert!(p.volume.error <= 1e-3 * exact * 1.01);
        for id in [p.a, p.b] {
            assert!(c.block(id).contains_point(&p.point), "witness {:?} outside block {}", p.point, id.0);
        }
    }
}

#[test]
fn overlapping_pairs_are_found_with_their_volume() {
    let lens = 5.0 / 12.0 * PI;
    // A lens, and a ball inside a cube (the ball's volume).
    check_overlaps(
        vec![
            block("a", vec![ball(0.0, 1.0)], O, 0),
            block("b", vec![ball(1.0, 1.0)], T, 0),
            block("cube", cuboid([9.0, -1.0, -1.0], [11.0, 1.0, 1.0]), O, 0),
            block("inner", vec![ball(10.0, 0.5)], O, 0),
        ],
        &[(0, 1, lens), (2, 3, PI / 6.0)],
    );
    // Two cubes sharing a slab of 2 × 2 × 0.5.
    check_overlaps(
        vec![block("p", cuboid([0.0; 3], [2.0; 3]), O, 0), block("q", cuboid([1.5, 0.0, 0.0], [3.5, 2.0, 2.0]), O, 0)],
        &[(0, 1, 2.0)],
    );
}

#[test]
fn touching_and_disjoint_blocks_do_not_overlap() {
    let d = 2.0 / 3f64.sqrt();
    let diagonal = |s: f64| Solid::from(Quadric::sphere().transformed(&translate(s * d, s * d, s * d)));
    // Cubes sharing a face, balls touching at a point (along an axis and
    // along a diagonal, where their boxes overlap), a ball in a corner of
    // a cube it touches from outside, and disjoint balls.
    let cases: Vec<Vec<Block>> = vec![
        vec![block("p", cuboid([0.0; 3], [1.0; 3]), O, 0), block("q", cuboid([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]), O, 0)],
        vec![block("a", vec![ball(0.0, 1.0)], O, 0), block("b", vec![ball(2.0, 1.0)], O, 0)],
        vec![block("a", vec![diagonal(0.0)], O, 0), block("b", vec![diagonal(1.0)], O, 0)],
        vec![block("a", vec![ball(0.0, 1.0)], O, 0), block("b", vec![ball(5.0, 1.0)], T, 0)],
    ];
    for blocks in cases {
        check_overlaps(blocks, &[]);
    }
}

#[test]
fn unbounded_pairs_are_listed_not_measured() {
    let c = complex(vec![
        block("below", vec![hs(0.0, 1.0, 0.0, 0.0)], O, 0),
        block("left", vec![hs(1.0, 0.0, 0.0, 0.0)], O, 0),
    ]);
    let found = c.overlaps(&VolumeOptions::default()).expect("valid options");
    assert_eq!((found.pairs.len(), found.unbounded.as_slice()), (0, &[(BlockId(0), BlockId(1))][..]));
    let bounds = Aabb { min: Point3::new(-1.0, -1.0, -1.0), max: Point3::new(1.0, 1.0, 1.0) };
    let clipped = c.overlaps(&VolumeOptions { bounds: Some(bounds), ..VolumeOptions::default() }).expect("valid");
    assert_eq!(clipped.pairs.len(), 1);
    let v = clipped.pairs[0].volume;
    assert!((v.value - 2.0).abs() <= 4.0 * v.error, "{}", v.value);
}

#[test]
fn too_many_candidate_pairs_are_skipped_and_the_line_cap_is_reported() {
    let c = complex(vec![
        block("a", vec![ball(0.0, 1.0)], O, 0),
        block("b", vec![ball(1.0, 1.0)], O, 0),
        block("c", vec![ball(0.5, 0.5)], O, 0),
    ]);
    let few = VolumeOptions { max_pairs: 2, ..VolumeOptions::default() };
    let found = c.overlaps(&few).expect("valid options");
    assert!(found.skipped && found.pairs.is_empty() && found.candidates > 2, "{found:?}");
    let all = c.overlaps(&VolumeOptions { max_pairs: 3, ..VolumeOptions::default() }).expect("valid options");
    assert_eq!((all.skipped, all.candidates, all.pairs.len()), (false, 3, 3));
    // A tolerance no round within the cap reaches: the last round, flagged.
    let capped = VolumeOptions { tolerance: 1e-9, max_lines: 1 << 14, ..VolumeOptions::default() };
    let v = c.volumes(&capped).expect("valid options");
    assert!(!v.converged && v.lines <= 1 << 14 && v.rounds >= 2, "{v:?}");
    let e = v.union.expect("bounded");
    // The third ball lies in the first two's lens.
    let exact_union = 2.0 * 4.0 / 3.0 * PI - 5.0 / 12.0 * PI;
    assert!((e.value - exact_union).abs() <= 4.0 * e.error, "{} ± {}", e.value, e.error);
}
