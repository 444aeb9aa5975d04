//! Assembled complexes (instances and lattices of definitions) answer every
//! query as their explicit expansion does: the same blocks, ids, owners
//! and events, the distances and points to within rounding. The oracle is
//! the flat complex of the expanded blocks, built by `Complex::new`.

use std::sync::Arc;

use complex::{
    Block, BlockId, Complex, ComplexError, ComplexOptions, Hit, MaterialKey, Member, Opacity, Partition, Placement,
};
use quadric::nalgebra::{Point3, Vector3};
use quadric::{Quadric, Ray, Solid, Transform};

use crate::common::{cuboid, moved};

/// A scene as a tree: the assembled complex and the expansion are both
/// built from it.
#[derive(Clone)]
enum Spec {
    Block(Block),
    Place { members: Vec<Spec>, transform: Transform, pitch: Vector3<f64>, count: [u32; 3] },
}

fn assemble(specs: &[Spec]) -> Complex {
    let members = specs
        .iter()
        .map(|s| match s {
            Spec::Block(b) => Member::Block(b.clone()),
            Spec::Place { members, transform, pitch, count } => Member::Placed(Placement {
                definition: Arc::new(assemble(members)),
                transform: *transform,
                pitch: *pitch,
                count: *count,
            }),
        })
        .collect();
    Complex::assemble(members, ComplexOptions { epsilon: Some(1e-9), ..Default::default() }).expect("valid test input")
}

fn expand(specs: &[Spec], m: &Transform, out: &mut Vec<Block>) {
    for s in specs {
        match s {
            Spec::Block(b) => out
                .push(Block::new(b.name(), moved(b.solids(), m), b.opacity(), b.material()).expect("valid test input")),
            Spec::Place { members, transform, pitch, count } => {
                for k in 0..count[2] {
                    for j in 0..count[1] {
                        for i in 0..count[0] {
                            let offset =
                                Vector3::new(f64::from(i) * pitch.x, f64::from(j) * pitch.y, f64::from(k) * pitch.z);
                            let element =
                                Transform::translate(offset).expect("valid test input").then(transform).then(m);
                            expand(members, &element, out);
                        }
                    }
                }
            }
        }
    }
}

fn flat(specs: &[Spec]) -> Complex {
    let mut blocks = Vec::new();
    expand(specs, &Transform::identity(), &mut blocks);
    Complex::new(blocks, ComplexOptions { epsilon: Some(1e-9), ..Default::default() }).expect("valid test input")
}

fn block(name: &str, solids: Vec<Solid>, opacity: Opacity, material: u32) -> Spec {
    Spec::Block(Block::new(name, solids, opacity, MaterialKey(material)).expect("valid test input"))
}

fn ball(c: [f64; 3], r: f64) -> Vec<Solid> {
    vec![complex::shapes::sphere(Point3::from(c), r).expect("valid test input")]
}

fn lattice(members: Vec<Spec>, transform: Transform, pitch: [f64; 3], count: [u32; 3]) -> Spec {
    Spec::Place { members, transform, pitch: Vector3::from(pitch), count }
}

/// A pin cell: a ball in a box-shaped transparent coolant cell.
fn pin(opacity: Opacity) -> Vec<Spec> {
    vec![
        block("pin", ball([0.5, 0.5, 0.5], 0.3), Opacity::Opaque, 1),
        block("cell", cuboid([0.05, 0.05, 0.05], [0.95, 0.95, 0.95]), opacity, 2),
    ]
}

/// The scenes: a flat one placed once, lattices (one, two and three
/// axes), a rotated and scaled instance, nested lattices, with opaque and
/// transparent blocks interleaved with own blocks.
fn scenes() -> Vec<(&'static str, Vec<Spec>)> {
    let rotate = Transform::rotate_y_degrees(30.0)
        .expect("valid test input")
        .then(&Transform::translate(Vector3::new(1.0, 0.5, 0.0)).expect("valid test input"));
    let scaled = Transform::scale(1.5)
        .expect("valid test input")
        .then(&Transform::rotate_z_degrees(-20.0).expect("valid test input"));
    let inner = lattice(pin(Opacity::Opaque), Transform::identity(), [1.0, 1.0, 1.0], [3, 3, 1]);
    vec![
        ("instance", vec![lattice(pin(Opacity::Transparent), Transform::identity(), [0.0; 3], [1, 1, 1])]),
        (
            "row",
            vec![
                block("ground", vec![crate::common::hs(0.0, -1.0, 0.0, -0.1)], Opacity::Opaque, 3),
                lattice(pin(Opacity::Opaque), Transform::identity(), [1.0, 0.0, 0.0], [5, 1, 1]),
                block("post", ball([2.0, 1.5, 0.5], 0.6), Opacity::Opaque, 4),
            ],
        ),
        ("grid", vec![lattice(pin(Opacity::Transparent), rotate, [1.0, 1.0, 1.0], [4, 3, 2])]),
        (
            "overlapping",
            vec![
                block("glass", ball([1.5, 1.5, 0.5], 1.2), Opacity::Transparent, 5),
                lattice(pin(Opacity::Transparent), Transform::identity(), [0.7, 0.7, 1.0], [4, 4, 1]),
            ],
        ),
        ("scaled", vec![lattice(pin(Opacity::Transparent), scaled, [1.0, 1.0, 1.0], [2, 2, 2])]),
        ("nested", vec![lattice(vec![inner.clone()], rotate, [3.0, 0.0, 3.0], [3, 1, 2]), inner]),
    ]
}

/// A deterministic stream of numbers in `[0, 1)` (SplitMix64).
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn point(&mut self, b: &complex::Aabb) -> Point3<f64> {
        let (lo, hi) = (b.min.map(|c| c.max(-20.0)), b.max.map(|c| c.min(20.0)));
        let pad = 0.1 * (hi - lo);
        let (lo, hi) = (lo - pad, hi + pad);
        Point3::new(
            lo.x + self.next() * (hi.x - lo.x),
            lo.y + self.next() * (hi.y - lo.y),
            lo.z + self.next() * (hi.z - lo.z),
        )
    }

    /// A ray from near the scene towards a point of it.
    fn ray(&mut self, b: &complex::Aabb) -> Ray {
        let from = self.point(b) + Vector3::new(self.next() - 0.5, 2.0, -6.0);
        let to = self.point(b);
        Ray::new(from, to - from).expect("valid test input")
    }
}

fn close(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

fn same_hit(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.block == b.block
                && a.solid == b.solid
                && a.entering == b.entering
                && close(a.t, b.t)
                && (a.point - b.point).norm() <= 1e-9
                && (a.normal - b.normal).norm() <= 1e-9
        }
        _ => false,
    }
}

fn same_partition(a: &Partition, b: &Partition) -> bool {
    a.segments.len() == b.segments.len()
        && a.segments
            .iter()
            .zip(&b.segments)
            .all(|(s, t)| s.owner == t.owner && close(s.start, t.start) && close(s.end, t.end))
}

const RAYS: usize = 400;

#[test]
fn ids_and_names_follow_the_expansion() {
    for (name, specs) in scenes() {
        let (a, f) = (assemble(&specs), flat(&specs));
        assert_eq!(a.len(), f.len(), "{name}");
        for i in 0..f.len() as u32 {
            let (x, y) = (a.block(BlockId(i)), f.block(BlockId(i)));
            assert_eq!(
                (x.name(), x.opacity(), x.material()),
                (y.name(), y.opacity(), y.material()),
                "{name} block {i}"
            );
            // The resolved block, moved to the world, is the expanded one.
            let r = a.resolve(BlockId(i));
            let m = r.to_world.unwrap_or_else(Transform::identity);
            let p = f.block_aabb(BlockId(i)).center().unwrap_or_else(Point3::origin);
            let local = m.inverse().apply_point(&p);
            assert_eq!(r.block.contains_point(&local), y.contains_point(&p), "{name} block {i}");
            let (ba, bf) = (a.block_aabb(BlockId(i)), f.block_aabb(BlockId(i)));
            // Both boxes are conservative, each padded its own way.
            if bf.is_bounded() {
                assert!(ba.min.iter().zip(bf.min.iter()).all(|(x, y)| *x <= *y + 1e-6), "{name} {i}: {ba:?} ⊉ {bf:?}");
                assert!(ba.max.iter().zip(bf.max.iter()).all(|(x, y)| *x >= *y - 1e-6), "{name} {i}: {ba:?} ⊉ {bf:?}");
            }
        }
    }
}

#[test]
fn rays_meet_what_the_expansion_meets() {
    for (name, specs) in scenes() {
        let (a, f) = (assemble(&specs), flat(&specs));
        let mut numbers = Numbers(7);
        let scene = f.aabb();
        let (mut pa, mut pf) = (Partition::default(), Partition::default());
        let mut hits = 0;
        for n in 0..RAYS {
            let ray = numbers.ray(&scene);
            let (ha, hf) = (a.cast_ray(&ray, f64::INFINITY), f.cast_ray(&ray, f64::INFINITY));
            assert!(same_hit(&ha, &hf), "{name} ray {n} {ray:?}:\n{ha:?}\n{hf:?}");
            hits += usize::from(hf.is_some());
            let reach = numbers.next() * 20.0;
            assert_eq!(a.occluded(&ray, reach), f.occluded(&ray, reach), "{name} ray {n}");
            a.segments_into(&ray, &mut pa);
            f.segments_into(&ray, &mut pf);
            assert!(same_partition(&pa, &pf), "{name} ray {n}:\n{:?}\n{:?}", pa.segments, pf.segments);
            let (ea, ef) = (a.first_interface(&ray, &mut pa), f.first_interface(&ray, &mut pf));
            assert_eq!(ea.map(|e| (e.before, e.after)), ef.map(|e| (e.before, e.after)), "{name} ray {n}");
            let (ia, ifl) = (a.intervals(&ray), f.intervals(&ray));
            assert_eq!(
                ia.iter().map(|x| x.0).collect::<Vec<_>>(),
                ifl.iter().map(|x| x.0).collect::<Vec<_>>(),
                "{name} ray {n}"
            );
            for (id, set) in &ifl {
                let mine = a.block_intervals(*id, &ray);
                assert_eq!(mine.len(), set.len(), "{name} ray {n} block {id:?}");
            }
            // Secondary rays leave the surface on the side they go to.
            if let Some(h) = hf {
                let back = -ray.direction();
                let (ra, rf) = (a.spawn_ray(h.surface(), &h.point, &back), f.spawn_ray(h.surface(), &h.point, &back));
                let (ra, rf) = (ra.expect("valid test input"), rf.expect("valid test input"));
                assert!((ra.origin() - rf.origin()).norm() <= 1e-9, "{name} ray {n}");
            }
        }
        assert!(hits > RAYS / 10, "{name}: only {hits} of {RAYS} rays hit anything");
        let rays: Vec<Ray> = (0..8).map(|_| numbers.ray(&scene)).collect();
        let four = [rays[0], rays[1], rays[2], rays[3]];
        let (fa, ff) = (a.cast_rays(&four, f64::INFINITY), f.cast_rays(&four, f64::INFINITY));
        assert!(fa.iter().zip(&ff).all(|(x, y)| same_hit(x, y)), "{name}");
    }
}

#[test]
fn points_are_owned_as_in_the_expansion() {
    for (name, specs) in scenes() {
        let (a, f) = (assemble(&specs), flat(&specs));
        let mut numbers = Numbers(11);
        let scene = f.aabb();
        let (mut ia, mut ifl) = (Vec::new(), Vec::new());
        let mut owned = 0;
        for n in 0..2000 {
            let p = numbers.point(&scene);
            assert_eq!(a.contains_point(&p), f.contains_point(&p), "{name} point {n} {p:?}");
            owned += usize::from(f.contains_point(&p).is_some());
            a.blocks_containing(&p, &mut ia);
            f.blocks_containing(&p, &mut ifl);
            assert_eq!(ia, ifl, "{name} point {n}");
        }
        assert!(owned > 100, "{name}: only {owned} points owned");
    }
}

#[test]
fn volumes_agree_with_the_expansion() {
    let specs = &scenes()[1].1[1..2];
    let (a, f) = (assemble(specs), flat(specs));
    let options = complex::VolumeOptions { tolerance: 0.02, ..Default::default() };
    let (va, vf) = (a.volumes(&options).expect("valid test input"), f.volumes(&options).expect("valid test input"));
    let ball = 4.0 / 3.0 * std::f64::consts::PI * 0.3f64.powi(3);
    for (x, y) in va.blocks.iter().zip(&vf.blocks) {
        let (x, y) = (x.owned.expect("valid test input"), y.owned.expect("valid test input"));
        assert!((x.value - y.value).abs() <= 4.0 * (x.error + y.error), "{x:?} {y:?}");
    }
    let pins = va.blocks.iter().step_by(2).map(|b| b.owned.expect("valid test input"));
    for v in pins {
        assert!((v.value - ball).abs() <= 4.0 * v.error, "{v:?} against {ball}");
    }
}

#[test]
fn a_billion_blocks_cost_what_their_definitions_cost() {
    // 1000 × 1000 elements of a 30 × 30 lattice of a ball: 9·10⁸ blocks.
    let ball =
        Block::new("ball", ball([0.5, 0.5, 0.5], 0.4), Opacity::Opaque, MaterialKey(0)).expect("valid test input");
    let one = Arc::new(Complex::new(vec![ball], ComplexOptions::default()).expect("valid test input"));
    let place = |definition, pitch: f64, n| Placement {
        pitch: Vector3::new(pitch, 0.0, pitch),
        count: [n, 1, n],
        ..Placement::instance(definition, Transform::identity())
    };
    let tile = Arc::new(
        Complex::assemble(vec![Member::Placed(place(one, 1.0, 30))], ComplexOptions::default())
            .expect("valid test input"),
    );
    let scene = Complex::assemble(vec![Member::Placed(place(tile, 30.0, 1000))], ComplexOptions::default())
        .expect("valid test input");
    assert_eq!(scene.len(), 900_000_000);
    // Straight down onto element (i, k) of tile (I, K): block ((K·1000 + I)·900 + k·30 + i).
    let (big, small) = ((417u32, 803u32), (12u32, 29u32));
    let x = f64::from(big.0) * 30.0 + f64::from(small.0) + 0.5;
    let z = f64::from(big.1) * 30.0 + f64::from(small.1) + 0.5;
    let hit = scene
        .cast_ray(&Ray::new(Point3::new(x, 5.0, z), -Vector3::y()).expect("valid test input"), f64::INFINITY)
        .expect("valid test input");
    assert_eq!(hit.block.0, (big.1 * 1000 + big.0) * 900 + small.1 * 30 + small.0);
    assert!((hit.t - 4.1).abs() < 1e-9 && (hit.point.y - 0.9).abs() < 1e-12, "{hit:?}");
    assert_eq!(scene.contains_point(&Point3::new(x, 0.5, z)), Some(hit.block));
    // A grazing ray along a row of balls meets the first one.
    let along = Ray::new(Point3::new(-5.0, 0.5, 0.5), Vector3::x()).expect("valid test input");
    assert_eq!(scene.cast_ray(&along, f64::INFINITY).map(|h| (h.block.0, h.t)), Some((0, 5.1)));
}

#[test]
fn bad_placements_are_errors() {
    let ball = Block::new("ball", ball([0.0; 3], 1.0), Opacity::Opaque, MaterialKey(0)).expect("valid test input");
    let one = Arc::new(Complex::new(vec![ball], ComplexOptions::default()).expect("valid test input"));
    let place = |count, pitch: f64| {
        Member::Placed(Placement {
            pitch: Vector3::repeat(pitch),
            count,
            ..Placement::instance(one.clone(), Transform::identity())
        })
    };
    let err = |m| Complex::assemble(vec![m], ComplexOptions::default()).expect_err("an error");
    assert!(matches!(err(place([0, 1, 1], 1.0)), ComplexError::BadPlacement { index: 0, .. }));
    assert!(matches!(err(place([2, 1, 1], f64::NAN)), ComplexError::BadPlacement { .. }));
    assert!(matches!(err(place([70_000, 70_000, 1], 1.0)), ComplexError::TooManyBlocks { .. }));
    let half = Block::new("half", vec![Solid::from(Quadric::sphere()).complement()], Opacity::Opaque, MaterialKey(0));
    let open = Arc::new(
        Complex::new(vec![half.expect("valid test input")], ComplexOptions::default()).expect("valid test input"),
    );
    let lattice =
        Placement { pitch: Vector3::repeat(1.0), count: [2, 1, 1], ..Placement::instance(open, Transform::identity()) };
    assert!(matches!(err(Member::Placed(lattice)), ComplexError::BadPlacement { .. }));
}

#[test]
fn empty_definitions_take_no_ids() {
    let empty = Arc::new(Complex::new(Vec::new(), ComplexOptions::default()).expect("an empty complex"));
    let ball = Block::new("ball", ball([0.0; 3], 1.0), Opacity::Opaque, MaterialKey(0)).expect("valid test input");
    let members = vec![
        Member::Placed(Placement::instance(empty.clone(), Transform::identity())),
        Member::Block(ball),
        Member::Placed(Placement {
            pitch: Vector3::repeat(1.0),
            count: [3, 1, 1],
            ..Placement::instance(empty, Transform::identity())
        }),
    ];
    let scene = Complex::assemble(members, ComplexOptions::default()).expect("valid test input");
    assert_eq!(scene.len(), 1);
    assert_eq!(scene.block(BlockId(0)).name(), "ball");
    assert_eq!(scene.contains_point(&Point3::origin()), Some(BlockId(0)));
    let ray = Ray::new(Point3::new(0.0, 0.0, -5.0), Vector3::z()).expect("valid test input");
    assert_eq!(scene.cast_ray(&ray, f64::INFINITY).map(|h| (h.block, h.t)), Some((BlockId(0), 4.0)));
}
