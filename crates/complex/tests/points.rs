//! `blocks_containing` lists exactly the blocks whose own solids hold the
//! point (brute force over every block's `Block::contains_point`), in
//! priority order, and its owner under the priority rule is
//! `contains_point`'s.

use complex::{BlockId, Complex};
use proptest::prelude::*;
use quadric::nalgebra::Point3;
use quadric::strategies;

use crate::oracle::{build, complex_spec, small_block};

/// Checks `blocks_containing` at each point against the brute force.
fn agrees(c: &Complex, points: &[Point3<f64>]) -> Result<(), TestCaseError> {
    let mut inside = vec![BlockId(u32::MAX)];
    for p in points {
        c.blocks_containing(p, &mut inside);
        let brute: Vec<BlockId> =
            (0..c.blocks().len() as u32).map(BlockId).filter(|&b| c.block(b).contains_point(p)).collect();
        prop_assert_eq!(&inside, &brute, "at {:?}", p);
        let owner = inside.iter().copied().find(|&b| !c.block(b).is_transparent()).or(inside.first().copied());
        prop_assert_eq!(owner, c.contains_point(p), "owner at {:?}", p);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 8).max(8)))]

    /// 3 to 8 overlapping blocks (the first three all hold the origin), some
    /// unbounded: points near the origin, where they overlap, and the origin.
    #[test]
    fn blocks_containing_is_the_brute_force_on_overlapping_blocks(
        specs in complex_spec(),
        points in proptest::collection::vec(strategies::point(2.0), 64),
    ) {
        let c = build(&specs);
        agrees(&c, &points)?;
        agrees(&c, &[Point3::origin()])?;
    }

}

proptest! {
    // A complex of some 90 blocks built each case: a
    // thirty-second of the usual count (31 cases at CI's 1,000).
    #![proptest_config(ProptestConfig::with_cases((ProptestConfig::default().cases / 32).max(4)))]

    /// 60 to 120 small blocks (a BVH several levels deep).
    #[test]
    fn blocks_containing_is_the_brute_force_on_large_scenes(
        specs in proptest::collection::vec(small_block(), 60..120),
        points in proptest::collection::vec(strategies::point(3.0), 256),
    ) {
        agrees(&build(&specs), &points)?;
    }
}

#[test]
fn blocks_containing_is_empty_at_non_finite_points() {
    let c = build(&[(crate::common::cuboid([-1.0; 3], [1.0; 3]), false, 0)]);
    let mut inside = vec![BlockId(7)];
    for p in [Point3::new(f64::NAN, 0.0, 0.0), Point3::new(0.0, f64::INFINITY, 0.0)] {
        c.blocks_containing(&p, &mut inside);
        assert!(inside.is_empty(), "{p:?}");
    }
    c.blocks_containing(&Point3::origin(), &mut inside);
    assert_eq!(inside, [BlockId(0)]);
}
