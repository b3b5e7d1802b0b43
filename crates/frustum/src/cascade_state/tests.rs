//! Tests of the held stable maps: the size band, the turn allowance, the held
//! depth range and the whole-texel snap.

use super::*;

/// `hold_side` with a known turned footprint.
fn hold(held: DVec2, needed: DVec2, turned: DVec2) -> (DVec2, bool) {
    hold_side(held, needed, || Ok(turned)).unwrap()
}

#[test]
fn size_is_kept_inside_the_band_and_renewed_outside() {
    let n = DVec2::new(10.0, 4.0);
    let turned = DVec2::new(10.2, 4.9);
    let (first, kept) = hold(DVec2::ZERO, n, turned);
    assert!(!kept);
    // The turned footprint, or the footprint with the headroom where that is
    // larger (x here), rounded up by less than 2%.
    let target = DVec2::new(n.x * STABLE_HEADROOM, turned.y);
    assert!(first.cmpge(target).all() && first.cmple(target * 1.016).all());
    // Grows within the margin: still covered, kept.
    assert_eq!(hold(first, n * 1.02, turned * 1.02), (first, true));
    assert_eq!(hold(first, DVec2::new(10.0, 4.8), turned), (first, true));
    // Grows past it: renewed from the new footprint.
    let (renewed, kept) = hold(first, n * 1.3, turned * 1.3);
    assert!(!kept && renewed.cmpge(turned * 1.3).all());
    assert!(renewed.cmpge(n * 1.3 * STABLE_HEADROOM).all());
    // Shrinks to 80%: kept; to 60%: the held map is more than 1.5 times the size
    // it would be chosen at, renewed.
    assert!(hold(first, n * 0.8, turned * 0.8).1);
    let (smaller, kept) = hold(first, n * 0.6, turned * 0.6);
    assert!(!kept && smaller.cmplt(first).all());
    // One axis too small renews both.
    let (both, kept) = hold(first, DVec2::new(9.0, 8.0), DVec2::new(10.0, 8.0));
    assert!(!kept && both.y >= 8.0 * STABLE_HEADROOM && both.x < first.x);
}

#[test]
fn the_turned_footprint_is_computed_only_where_it_decides() {
    let n = DVec2::new(10.0, 4.0);
    let turned = DVec2::new(10.2, 4.9);
    let (first, _) = hold(DVec2::ZERO, n, turned);
    // Covered and within the band over the headroom alone: not asked for, and
    // the same choice as with it.
    let unasked = || -> Result<DVec2, FrustumError> { panic!("turned footprint asked for") };
    assert_eq!(hold_side(first, n, unasked).unwrap(), (first, true));
    assert_eq!(hold(first, n, turned), (first, true));
    // Where the turn needs much more than the headroom, a footprint shrunk to
    // 70% keeps the held size only by its turned extent (held y about 6.06,
    // over 0.7 * 4 * 1.03 more than 1.5 times, over 0.7 * 6 less).
    let wide_turn = DVec2::new(10.2, 6.0);
    let (first, _) = hold(DVec2::ZERO, n, wide_turn);
    assert_eq!(hold(first, n * 0.7, wide_turn * 0.7), (first, true));
    assert!(!hold(first, n * 0.7, n * 0.7).1);
    // Its error reaches the caller where it is needed.
    let failing = || Err(FrustumError::EmptyBounds);
    assert_eq!(
        hold_side(DVec2::ZERO, n, failing),
        Err(FrustumError::EmptyBounds)
    );
}

#[test]
fn a_turned_footprint_needs_its_long_side_times_the_turn_across() {
    // A 5 x 1 rectangle in the light frame of a light straight down: turned by
    // phi, its box grows to 5 cos + sin by 5 sin + cos.
    let light = crate::projection::light_rotation(DVec3::NEG_Y, Vec3::Z);
    let world = |x: f64, y: f64| light.inverse().transform_point3(DVec3::new(x, y, 0.0));
    let corners = [
        world(0.0, 0.0),
        world(5.0, 0.0),
        world(5.0, 1.0),
        world(0.0, 1.0),
    ];
    let phi = 0.1;
    let e = turned_extent(&corners.iter().copied(), &light, phi);
    let (s, c) = (phi.sin(), phi.cos());
    assert!((e.x - (5.0 * c + s)).abs() < 1e-9, "{e}");
    assert!((e.y - (5.0 * s + c)).abs() < 1e-9, "{e}");
    assert_eq!(
        turned_extent(&corners.iter().copied(), &light, 0.0),
        DVec2::new(5.0, 1.0)
    );
}

#[test]
fn the_held_depth_range_rides_out_jumps_and_creep_within_the_camera_range() {
    let limits = (1.0, 1000.0);
    let mut state = CascadeState::new();
    let first = state.hold_depth_range(55.0, 160.0, limits);
    assert_eq!(first.split, (55.0, 160.0));
    assert_eq!(first.cover, (44.0, 200.0));
    // The far bound creeps by 3% a frame, the near one jumps by a fifth: the
    // same ranges for seven frames.
    for k in 1..=7 {
        let near = if k > 2 { 66.0 } else { 55.0 };
        let far = 160.0 * 1.03f32.powi(k);
        assert_eq!(state.hold_depth_range(near, far, limits), first, "{k}");
    }
    // Past the far margin: a new far end, the near end kept.
    let r = state.hold_depth_range(55.0, 210.0, limits);
    assert_eq!((r.split, r.cover), ((55.0, 210.0), (44.0, 262.5)));
    // Far too wide once the bound has come much nearer: a new far end.
    let r = state.hold_depth_range(55.0, 100.0, limits);
    assert_eq!((r.split.1, r.cover.1), (100.0, 125.0));
    // Whatever the bounds, the ranges nest inside the camera's.
    for (near, far) in [
        (f32::NAN, 5.0),
        (500.0, 20.0),
        (-3.0, f32::INFINITY),
        (2000.0, 3000.0),
        (0.5, 1e9),
    ] {
        let r = state.hold_depth_range(near, far, limits);
        let (c, s) = (r.cover, r.split);
        assert!(
            limits.0 <= c.0 && c.0 <= s.0 && s.0 <= s.1 && s.1 <= c.1 && c.1 <= limits.1,
            "{near} {far} -> {r:?}"
        );
    }
}

#[test]
fn short_mantissa_rounds_up_by_at_most_two_percent() {
    for x in [1e-3, 0.37, 1.0, 3.3, 1234.5678, 9.9e6] {
        let r = short_mantissa_above(x);
        assert!(r >= x && r <= x * (1.0 + 1.0 / 64.0), "{x} -> {r}");
        // Six mantissa bits: times 64 over its power of two is an integer.
        let scaled = r / 2f64.powi(r.log2().floor() as i32) * 64.0;
        assert_eq!(scaled, scaled.round(), "{r}");
    }
}

#[test]
fn the_turn_allowance_stops_at_the_receivers_box() {
    // A light straight down on a 10 x 4 floor seen whole: turned by 0.1 rad the
    // floor's box would grow to about 10.35 x 4.98, but no view of the floor
    // has a footprint larger than the floor.
    let res = 1024.0;
    let direction = DVec3::NEG_Y;
    let frame = crate::projection::light_rotation(direction, Vec3::Z);
    let floor = Aabb::new(Vec3::new(0.0, -1.0, 0.0), Vec3::new(10.0, 0.0, 4.0));
    let corners: [DVec3; 8] = core::array::from_fn(|i| {
        DVec3::select(
            glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
            floor.max.as_dvec3(),
            floor.min.as_dvec3(),
        )
    });
    let mut state = CascadeState::new();
    let mut slot = state.slot(1, 0).unwrap();
    let b = held_box(
        &corners.iter().copied(),
        &floor,
        direction,
        &frame,
        res,
        &mut slot,
        None,
    )
    .unwrap();
    let (turned, cap) = (
        turned_extent(&corners.iter().copied(), &frame, STABLE_TURN),
        box_extent(&floor, &frame),
    );
    assert!(turned.min_element() > 4.9 && (cap.max_element() - 10.0).abs() < 1e-9);
    // The footprint with the headroom (one texel of slack, a short mantissa).
    let side = b.hi - b.lo;
    let least = cap * STABLE_HEADROOM;
    assert!(
        side.cmpge(least).all() && side.cmple(least * 1.02).all(),
        "{side}"
    );
}

#[test]
fn the_turn_allowance_is_paid_where_the_map_measures_near_the_tight_box() {
    // A 5 x 1 floor strip under a light straight down: turned by 0.1 rad its
    // box grows about 50% across and 1% along.
    let res = 1024.0;
    let direction = DVec3::NEG_Y;
    let frame = crate::projection::light_rotation(direction, Vec3::Z);
    let strip = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(5.0, 0.0, 0.0),
        DVec3::new(5.0, 0.0, 1.0),
        DVec3::new(0.0, 0.0, 1.0),
    ];
    let receivers = Aabb::new(Vec3::splat(-100.0), Vec3::splat(100.0));
    let fit = |measure: Option<MeasureBox<'_>>| {
        let mut state = CascadeState::new();
        let mut slot = state.slot(1, 0).unwrap();
        let points = strip.iter().copied();
        let b = held_box(
            &points, &receivers, direction, &frame, res, &mut slot, measure,
        );
        (b.unwrap(), state.size(1, 0).unwrap())
    };
    let (turned, turned_side) = fit(None);
    let (x, y) = (turned_side.max_element(), turned_side.min_element());
    assert!(x < 5.0 * 1.05 && y > 1.4, "{turned_side}");
    // Measured by the larger texel side, the allowance costs nothing: kept.
    let longest = |b: &HeldBox| b.texel;
    assert_eq!(fit(Some(&longest)), (turned, turned_side));
    // Measured by the area, it costs about 45%: the headroom alone.
    let area = |b: &HeldBox| (b.hi - b.lo).x * (b.hi - b.lo).y;
    let (unturned, side) = fit(Some(&area));
    assert!(
        side.min_element() < 1.05 && side.max_element() == x,
        "{side}"
    );
    assert!(unturned.texel == turned.texel);
    // Unmeasured: kept.
    assert_eq!(fit(Some(&|_: &HeldBox| f64::NAN)), (turned, turned_side));
}

#[test]
fn held_box_moves_by_whole_texels_covers_the_footprint_and_keeps_its_frame() {
    let res = 512.0;
    let direction = DVec3::new(0.3, -1.0, 0.2).normalize();
    let frame = crate::projection::light_rotation(direction, Vec3::X);
    let other = crate::projection::light_rotation(direction, Vec3::Z);
    let footprint = [
        DVec3::new(-3.2, 0.0, 7.1),
        DVec3::new(40.3, 0.0, 19.9),
        DVec3::new(10.0, 5.0, -4.0),
        DVec3::new(22.0, 1.0, 30.0),
    ];
    let mut state = CascadeState::new();
    let receivers = Aabb::new(Vec3::splat(-200.0), Vec3::splat(200.0));
    let mut fit = |points: &[DVec3], frame: &DMat4| {
        let mut slot = state.slot(1, 0).unwrap();
        let points = points.iter().copied();
        held_box(&points, &receivers, direction, frame, res, &mut slot, None).unwrap()
    };
    let a = fit(&footprint, &frame);
    let covers = |b: &HeldBox, shift: DVec3| {
        footprint.iter().all(|p| {
            let q = b.light_from_world.transform_point3(*p + shift).truncate();
            q.cmpge(b.lo).all() && q.cmple(b.hi).all()
        })
    };
    assert!(covers(&a, DVec3::ZERO));
    // Moved: the same frame and size (even when asked for another frame), by
    // whole texels.
    let shift = DVec3::new(1.37, -0.2, -0.61);
    let moved: Vec<DVec3> = footprint.iter().map(|p| *p + shift).collect();
    let b = fit(&moved, &other);
    assert!(covers(&b, shift));
    assert_eq!(b.light_from_world, a.light_from_world);
    assert_eq!(b.hi - b.lo, a.hi - a.lo);
    let texel = (a.hi - a.lo) / res;
    let steps = (b.lo - a.lo) / texel;
    assert!(
        (steps - steps.round()).abs().max_element() < 1e-9,
        "{steps}"
    );
    // Three times larger: re-sized, in the frame asked for now.
    let big: Vec<DVec3> = footprint.iter().map(|p| *p * 3.0).collect();
    let c = fit(&big, &other);
    assert!((c.light_from_world.y_axis - other.y_axis).length() < 1e-6);
    assert!(c.texel > 2.0 * a.texel);
    assert!(state.size(1, 0).is_some() && state.size(1, 1).is_none() && state.size(2, 0).is_none());
}
