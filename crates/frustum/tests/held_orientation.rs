//! The stable fit's new maps (`CascadeSet::fit_with_state_ranked`): what the
//! caller's measure is asked for, that its choice is kept, and that every
//! candidate covers the visible receivers.

use std::cell::RefCell;

use glam::{DVec2, Vec3};
use shadowmap_frustum::{
    Aabb, Camera, Cascade, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, CascadeState,
    MAX_HELD_CANDIDATES, Projection, SceneBounds, ShadowMapping, SplitScheme, ValidCamera,
};

/// A 10 x 3 x 8 m room.
const ROOM: Aabb = Aabb {
    min: Vec3::new(-5.0, 0.0, -4.0),
    max: Vec3::new(5.0, 3.0, 4.0),
};

/// A camera in the room turned `yaw` degrees from `-Z`, looking slightly down.
fn camera(yaw: f32) -> ValidCamera {
    let (s, c) = yaw.to_radians().sin_cos();
    let camera = Camera::look_to(
        Vec3::new(-2.0, 1.6, 1.5),
        Vec3::new(s, -0.35, -c),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.1, 20.0),
    )
    .unwrap();
    ValidCamera::new(&camera).unwrap()
}

fn options() -> CascadeOptions {
    CascadeOptions::default()
        .with_fit(CascadeFit::Stable)
        .with_resolution(1024)
        .with_scene(Some(SceneBounds::whole(ROOM)))
}

/// A light from above, a little off the vertical.
const LIGHT: Vec3 = Vec3::new(0.15, -1.0, 0.1);

fn splits(count: usize) -> CascadeSplits {
    CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, count, 0.1, 20.0).unwrap()
}

/// Points of the room's floor and walls the camera's slice `[n, f]` sees: a grid of
/// rays to where they leave the room, kept where their view depth is in range.
fn seen(camera: &ValidCamera, (n, f): (f32, f32)) -> Vec<Vec3> {
    let cam = camera.camera();
    let (eye, forward) = (cam.eye(), cam.forward());
    let side = forward.cross(Vec3::Y).normalize();
    let up = side.cross(forward);
    let mut out = Vec::new();
    for i in 0..40 {
        for j in 0..24 {
            let (x, y) = (i as f32 / 39.0 - 0.5, j as f32 / 23.0 - 0.5);
            let d = (forward + side * (x * 1.0 * 16.0 / 9.0) + up * y).normalize();
            let t = (0..3)
                .filter(|&a| d[a] != 0.0)
                .map(|a| {
                    let wall = if d[a] > 0.0 { ROOM.max[a] } else { ROOM.min[a] };
                    (wall - eye[a]) / d[a]
                })
                .fold(f32::INFINITY, f32::min);
            let p = eye + d * t;
            let depth = (p - eye).dot(forward);
            if depth >= n && depth <= f {
                out.push(p);
            }
        }
    }
    out
}

/// The candidates the measure was asked for, by slice.
type Offers = RefCell<Vec<Vec<Cascade>>>;

/// The fit with a measure that finds candidate `pick` of each slice finest (1,
/// the others 2): the orientations in the order offered, then, where the turn
/// allowance widens the kept one, the tight box and the kept one without it.
fn ranked(
    camera: &ValidCamera,
    state: &mut CascadeState,
    count: usize,
    pick: usize,
    offers: &Offers,
) -> CascadeSet {
    let measure = |c: &Cascade| {
        let mut offers = offers.borrow_mut();
        match offers.last_mut() {
            Some(slice) if slice[0].view_depth == c.view_depth => slice.push(*c),
            _ => offers.push(vec![*c]),
        }
        if offers.last().unwrap().len() == pick + 1 {
            1.0
        } else {
            2.0
        }
    };
    CascadeSet::fit_with_state_ranked(camera, LIGHT, &splits(count), &options(), state, &measure)
        .unwrap()
}

#[test]
fn the_first_candidate_is_the_unranked_fit_and_the_choice_is_held() {
    let camera = camera(40.0);
    let mut plain = CascadeState::default();
    let own =
        CascadeSet::fit_with_state(&camera, LIGHT, &splits(1), &options(), &mut plain).unwrap();
    let offers = Offers::default();
    let mut state = CascadeState::default();
    let first = ranked(&camera, &mut state, 1, 0, &offers);
    assert_eq!(first, own);
    let offered = offers.borrow()[0].clone();
    assert!(
        (2..=MAX_HELD_CANDIDATES + 2).contains(&offered.len()),
        "a view diagonal to the walls is offered rivals: {}",
        offered.len()
    );
    assert_eq!(offered[0], own.cascades[0]);
    // Choosing a rival: the set holds it, and the next frames keep it without
    // asking again.
    let mut state = CascadeState::default();
    offers.borrow_mut().clear();
    let chosen = ranked(&camera, &mut state, 1, 1, &offers);
    assert_eq!(chosen.cascades[0], offered[1]);
    let again = ranked(&camera, &mut state, 1, 0, &offers);
    assert_eq!(again.cascades[0].transform, offered[1].transform);
    assert_eq!(offers.borrow().len(), 1, "a held map is not ranked again");
    // Ties keep this frame's orientation with its turn allowance, and so does a
    // measure that measures nothing.
    let mut state = CascadeState::default();
    let tied = ranked(&camera, &mut state, 1, 99, &offers);
    assert_eq!(tied, own);
    for unmeasured in [f64::NAN, f64::INFINITY] {
        let mut state = CascadeState::default();
        let measure = |_: &Cascade| unmeasured;
        let set = CascadeSet::fit_with_state_ranked(
            &camera,
            LIGHT,
            &splits(1),
            &options(),
            &mut state,
            &measure,
        )
        .unwrap();
        assert_eq!(set, own);
    }
}

#[test]
fn every_candidate_covers_what_its_slice_sees_in_less_area() {
    let mut offered = 0;
    for yaw in (0..360).step_by(15) {
        let camera = camera(yaw as f32);
        let offers = Offers::default();
        let mut state = CascadeState::default();
        ranked(&camera, &mut state, 2, 0, &offers);
        for candidates in offers.borrow().iter() {
            offered += candidates.len() - 1;
            let area = |c: &Cascade| map_area(c);
            for c in candidates {
                for p in seen(&camera, c.view_depth) {
                    let s = c.transform.map_point(p.as_dvec3()).unwrap();
                    let inside = s.uv.cmpge(DVec2::splat(-1e-6)).all()
                        && s.uv.cmple(DVec2::splat(1.0 + 1e-6)).all();
                    assert!(inside, "yaw {yaw}: {p} at {:?}", s.uv);
                }
                assert!(area(c) <= area(&candidates[0]) * (1.0 + 1e-9));
            }
        }
    }
    assert!(offered > 10, "{offered} rivals offered over the turn");
}

/// The world area across the light that a cascade's map covers.
fn map_area(c: &Cascade) -> f64 {
    let m = c.transform.uv_from_world.as_dmat4();
    // The map's u and v per world unit across the light: the rows' parts
    // perpendicular to the light; the area is the inverse of their cross product.
    let l = LIGHT.as_dvec3().normalize();
    let row = |i: usize| {
        let r = glam::DVec3::new(m.x_axis[i], m.y_axis[i], m.z_axis[i]);
        r - l * r.dot(l)
    };
    1.0 / row(0).cross(row(1)).length()
}
