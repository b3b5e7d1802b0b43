//! Views the unit tests of this crate share.

use alloc::vec::Vec;
use glam::Vec3;
use shadowmap_frustum::{Aabb, Camera, Projection, SceneBounds, ShadowTransform};
use shadowmap_rtw::EyeSample;
use shadowmap_warp::{UniformOptions, uniform_focused};

/// A camera 10 m over a ground plane looking down at 45°, the sun straight down,
/// and the uniform fit of the ground it sees.
pub(crate) fn looking_down_at_the_ground() -> (Camera, Vec3, ShadowTransform) {
    let camera = Camera::look_to(
        Vec3::new(0.0, 10.0, 0.0),
        Vec3::new(0.0, -1.0, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.5, 100.0),
    )
    .unwrap();
    let light = Vec3::NEG_Y;
    let floor = Aabb::new(Vec3::new(-40.0, -1.0, -60.0), Vec3::new(40.0, 0.0, 0.0));
    let base = uniform_focused(
        &camera,
        light,
        &SceneBounds::whole(floor),
        &UniformOptions::default(),
    )
    .unwrap();
    (camera, light, base)
}

/// The unit directions of a grid of the camera's rays, `columns` x `rows` through
/// the centres of the cells of its near plane, row by row.
pub(crate) fn pixel_rays(
    camera: &Camera,
    columns: usize,
    rows: usize,
) -> impl Iterator<Item = Vec3> {
    let c = camera.frustum().unwrap().corners;
    let eye = camera.eye();
    (0..rows).flat_map(move |row| {
        (0..columns).map(move |column| {
            let (x, y) = (
                (column as f32 + 0.5) / columns as f32,
                (row as f32 + 0.5) / rows as f32,
            );
            (c[0].lerp(c[1], x).lerp(c[3].lerp(c[2], x), y) - eye).normalize()
        })
    })
}

/// A uniform number in `[0, 1)` from an xorshift `state` (reproducible views).
pub(crate) fn unit_random(state: &mut u64) -> f32 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f32 / (1u64 << 53) as f32
}

/// Where a grid of the camera's rays meets the ground plane `y = 0`, and a wall
/// `z = wall` facing `+z` above it (the end of a street).
pub(crate) fn street_samples(
    camera: &Camera,
    columns: usize,
    rows: usize,
    wall: f32,
) -> Vec<EyeSample> {
    let eye = camera.eye();
    let mut out = Vec::new();
    for d in pixel_rays(camera, columns, rows) {
        let t_ground = if d.y < -1e-3 {
            -eye.y / d.y
        } else {
            f32::INFINITY
        };
        let t_wall = if d.z < -1e-3 {
            (wall - eye.z) / d.z
        } else {
            f32::INFINITY
        };
        let (t, normal) = if t_ground < t_wall {
            (t_ground, Vec3::Y)
        } else {
            (t_wall, Vec3::Z)
        };
        if t.is_finite() && (eye + d * t).y < 12.0 {
            out.push(EyeSample {
                position: eye + d * t,
                normal,
                eye_distance: t,
            });
        }
    }
    out
}

/// Where a grid of the camera's rays (`columns` x `rows`) leaves the box `room`
/// from inside: its floor, walls and ceiling, each sample with the inward normal of
/// the face it meets.
pub(crate) fn room_samples(
    camera: &Camera,
    room: &Aabb,
    columns: usize,
    rows: usize,
) -> Vec<EyeSample> {
    let eye = camera.eye();
    let mut out = Vec::new();
    for d in pixel_rays(camera, columns, rows) {
        let mut exit = (f32::INFINITY, Vec3::ZERO);
        for axis in 0..3 {
            let (wall, normal) = if d[axis] > 0.0 {
                (room.max[axis], -Vec3::AXES[axis])
            } else if d[axis] < 0.0 {
                (room.min[axis], Vec3::AXES[axis])
            } else {
                continue;
            };
            let t = (wall - eye[axis]) / d[axis];
            if t < exit.0 {
                exit = (t, normal);
            }
        }
        if exit.0.is_finite() && exit.0 > 0.0 {
            out.push(EyeSample {
                position: eye + d * exit.0,
                normal: exit.1,
                eye_distance: exit.0,
            });
        }
    }
    out
}
