//! Writes the seed corpora `fuzz/seeds/<target>/` (deterministic, so running
//! it again changes nothing): solids and scenes like the ones Komplex renders,
//! rays that hit, graze and miss them, and the bad inputs that must be
//! rejected. Each seed is checked to decode back to itself.
//!
//! `cargo run --manifest-path fuzz/Cargo.toml --example seeds`

use std::fs;
use std::path::Path;

use komplex_fuzz::Num::{self, Dec, Frac, Int, Near, Special};
use komplex_fuzz::{
    decode, encode, Base, BlockSpec, CastSpec, Chain, ComplexInput, PointSpec, QuadricInput, RaySpec, SolidSpec, Step,
    Wire,
};

fn n(x: i8) -> Num {
    Int(x)
}

fn v(x: i8, y: i8, z: i8) -> [Num; 3] {
    [n(x), n(y), n(z)]
}

fn solid(base: Base, steps: Vec<Step>) -> SolidSpec {
    SolidSpec { base, complement: false, chain: Chain(steps) }
}

fn elementary(i: u8, steps: Vec<Step>) -> SolidSpec {
    solid(Base::Elementary(i), steps)
}

/// `a x + b y + c z + d <= 0`.
fn hs(a: i8, b: i8, c: i8, d: i8) -> SolidSpec {
    solid(Base::HalfSpace([n(a), n(b), n(c), n(d)]), vec![])
}

fn through(o: [Num; 3], t: [Num; 3]) -> RaySpec {
    RaySpec::Through(o, t)
}

fn free(o: [Num; 3], d: [Num; 3]) -> RaySpec {
    RaySpec::Free(o, d)
}

/// Rays that hit the unit solid at the origin, graze it and miss it.
fn rays() -> Vec<RaySpec> {
    vec![
        through(v(-5, 0, 0), v(0, 0, 0)),
        free(v(-5, 1, 0), v(1, 0, 0)), // tangent to the unit sphere
        through(v(3, 4, 5), [Frac(16), Frac(-8), n(0)]),
        free(v(0, 0, 0), v(0, 1, 0)), // from inside, along the axis of the y solids
    ]
}

fn far_rays() -> Vec<RaySpec> {
    vec![
        through([Dec(1, 9), n(0), n(0)], [Dec(1, 9), n(0), Dec(1, 9)]),
        free([Dec(-1, 9), n(0), Near(1, 3)], v(1, 0, 0)),
    ]
}

fn points() -> Vec<PointSpec> {
    vec![PointSpec(v(0, 0, 0)), PointSpec([Frac(64), n(0), n(0)]), PointSpec(v(0, 1, 0))]
}

fn quadric_seeds() -> Vec<(String, QuadricInput)> {
    let mut out = Vec::new();
    let names = ["sphere", "tube_x", "tube_y", "tube_z", "cone", "paraboloid", "hyperboloid1", "hyperboloid2"];
    for (i, name) in names.iter().enumerate() {
        let q = |steps, complement| QuadricInput {
            solid: SolidSpec { base: Base::Elementary(i as u8), complement, chain: Chain(steps) },
            rays: rays(),
            points: points(),
        };
        out.push((name.to_string(), q(vec![], false)));
        out.push((format!("{name}_outside"), q(vec![], true)));
        out.push((
            format!("{name}_placed"),
            q(vec![Step::ScaleXyz([n(2), Frac(32), n(1)]), Step::RotateZ(n(30)), Step::Translate(v(1, -2, 3))], false),
        ));
        out.push((
            format!("{name}_far"),
            QuadricInput {
                solid: elementary(i as u8, vec![Step::Translate([Dec(1, 9), n(0), Dec(1, 9)])]),
                rays: far_rays(),
                points: vec![PointSpec([Dec(1, 9), n(0), Dec(1, 9)])],
            },
        ));
    }
    // x² + 4y² + 9z² - 9 <= 0 from coefficients, and a symmetric matrix.
    let ellipsoid = [n(1), n(4), n(9), n(0), n(0), n(0), n(0), n(0), n(0), n(-9)];
    out.push((
        "ellipsoid".into(),
        QuadricInput { solid: solid(Base::Coefficients(ellipsoid), vec![]), rays: rays(), points: points() },
    ));
    #[rustfmt::skip]
    let matrix = [n(1), n(0), n(0), n(0),  n(0), n(1), n(0), n(0),  n(0), n(0), n(0), n(-1),  n(0), n(0), n(-1), n(0)];
    out.push((
        "matrix_paraboloid".into(),
        QuadricInput { solid: solid(Base::Matrix(matrix), vec![]), rays: rays(), points: points() },
    ));
    out.push(("half_space".into(), QuadricInput { solid: hs(1, 1, 0, -1), rays: rays(), points: points() }));
    #[rustfmt::skip]
    let shear = [n(1), n(1), n(0), n(2),  n(0), n(1), n(0), n(0),  n(0), n(0), n(1), n(-1)];
    out.push((
        "sheared_sphere".into(),
        QuadricInput {
            solid: elementary(0, vec![Step::Matrix(shear), Step::RotateX(Frac(1000))]),
            rays: rays(),
            points: points(),
        },
    ));
    // Bad input that must be rejected.
    #[rustfmt::skip]
    let singular = [n(1), n(2), n(0), n(0),  n(2), n(4), n(0), n(0),  n(0), n(0), n(1), n(0)];
    let bad = [
        ("scale_zero", vec![Step::Scale(n(0))]),
        ("scale_subnormal", vec![Step::Scale(Special(6))]),
        ("scale_huge_chain", vec![Step::Scale(Dec(1, 127)), Step::Scale(Dec(1, 127)), Step::Scale(Dec(1, 127))]),
        ("singular_matrix", vec![Step::Matrix(singular)]),
        ("translate_inf", vec![Step::Translate([Special(14), n(0), n(0)])]),
        ("rotate_nan", vec![Step::RotateY(Special(16))]),
    ];
    for (name, steps) in bad {
        out.push((name.into(), QuadricInput { solid: elementary(0, steps), rays: rays(), points: vec![] }));
    }
    out.push((
        "bad_rays".into(),
        QuadricInput {
            solid: elementary(0, vec![]),
            rays: vec![
                free(v(0, 0, 0), v(0, 0, 0)),
                through(v(1, 2, 3), v(1, 2, 3)),
                free([Special(16), n(0), n(0)], v(1, 0, 0)),
            ],
            points: vec![PointSpec([Special(12), Special(13), n(0)])],
        },
    ));
    out
}

fn block(solids: Vec<SolidSpec>, steps: Vec<Step>, transparent: bool, material: u8) -> BlockSpec {
    BlockSpec { solids, chain: Chain(steps), transparent, material }
}

/// The tube x² + z² <= 1 between y = 0 and y = 2.
fn capped_tube() -> Vec<SolidSpec> {
    vec![elementary(2, vec![]), hs(0, 1, 0, -2), hs(0, -1, 0, 0)]
}

fn cube() -> Vec<SolidSpec> {
    vec![hs(1, 0, 0, -1), hs(-1, 0, 0, -1), hs(0, 1, 0, -1), hs(0, -1, 0, -1), hs(0, 0, 1, -1), hs(0, 0, -1, -1)]
}

fn casts() -> Vec<CastSpec> {
    let max_ts = [Special(14), n(4), Frac(1)];
    rays().into_iter().zip(max_ts.into_iter().cycle()).map(|(ray, max_t)| CastSpec { ray, max_t }).collect()
}

fn complex_seeds() -> Vec<(String, ComplexInput)> {
    let scene = |blocks, epsilon| ComplexInput { blocks, epsilon, casts: casts(), points: points() };
    let at = |x: i8| vec![Step::Translate(v(x, 0, 0))];
    vec![
        ("one_sphere".into(), scene(vec![block(vec![elementary(0, vec![])], vec![], false, 0)], None)),
        ("capped_tube".into(), scene(vec![block(capped_tube(), vec![Step::RotateX(n(90))], false, 0)], None)),
        (
            "glass_of_water".into(),
            scene(
                vec![
                    block(capped_tube(), vec![Step::Scale(Frac(60))], true, 1),
                    block(capped_tube(), vec![], true, 2),
                    block(cube(), vec![Step::Translate(v(0, -2, 0))], false, 0),
                ],
                None,
            ),
        ),
        (
            "overlapping_balls".into(),
            scene(
                vec![
                    block(vec![elementary(0, vec![])], at(0), true, 1),
                    block(vec![elementary(0, vec![])], at(1), false, 0),
                    block(vec![elementary(0, vec![])], at(-1), true, 1),
                ],
                Some(Dec(1, -6)),
            ),
        ),
        (
            "lens_and_cone".into(),
            scene(
                vec![
                    block(vec![elementary(0, at(1)), elementary(0, at(-1))], vec![], true, 3),
                    block(vec![elementary(4, vec![]), hs(0, 1, 0, -1), hs(0, -1, 0, 0)], at(3), false, 0),
                    block(
                        vec![
                            SolidSpec { complement: true, ..elementary(0, vec![]) },
                            elementary(0, vec![Step::Scale(n(2))]),
                        ],
                        vec![],
                        false,
                        0,
                    ),
                ],
                Some(n(0)),
            ),
        ),
        (
            "bad_blocks".into(),
            scene(
                vec![
                    block(vec![], vec![], false, 0),
                    block(
                        vec![elementary(
                            0,
                            vec![Step::Scale(Dec(1, 127)), Step::Scale(Dec(1, 127)), Step::Scale(Dec(1, 127))],
                        )],
                        vec![],
                        false,
                        0,
                    ),
                    block(cube(), vec![Step::Translate([Dec(1, 9), n(0), n(0)])], false, 0),
                ],
                None,
            ),
        ),
        ("bad_epsilon".into(), scene(vec![block(cube(), vec![], false, 0)], Some(n(-1)))),
    ]
}

fn write<T: Wire + PartialEq + std::fmt::Debug + for<'a> arbitrary::Arbitrary<'a>>(
    dir: &Path,
    seeds: Vec<(String, T)>,
) {
    fs::create_dir_all(dir).expect("create the seed directory");
    for (name, seed) in seeds {
        let bytes = encode(&seed);
        let back: T = decode(&bytes).expect("decodes");
        assert_eq!(back, seed, "seed {name} does not round-trip");
        fs::write(dir.join(&name), bytes).expect("write a seed");
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds");
    write(&root.join("quadric_intervals"), quadric_seeds());
    write(&root.join("complex_queries"), complex_seeds());
    println!("wrote {}", root.display());
}
