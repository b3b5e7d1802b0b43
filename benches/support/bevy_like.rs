//! Our transcription of Bevy's per-frame directional cascade math
//! (`calculate_cascade` and the per-view loop of `build_directional_light_cascades` in
//! `bevy_light`), shared by the benches that compare against it.
//!
//! Bevy's default cascade configuration (`CascadeShadowConfigBuilder::default`):
//! 4 cascades, minimum distance 0.1, first far bound 10, maximum distance 150,
//! overlap proportion 0.2, and its default 2048² directional shadow map.

use glam::{Mat4, Quat, Vec3A, Vec4};

pub(crate) const CASCADES: usize = 4;
pub(crate) const MIN_DISTANCE: f32 = 0.1;
pub(crate) const FIRST_FAR: f32 = 10.0;
pub(crate) const MAX_DISTANCE: f32 = 150.0;
pub(crate) const OVERLAP: f32 = 0.2;
pub(crate) const MAP_SIZE: f32 = 2048.0;

/// Far bound of each cascade: exponential from `FIRST_FAR` to `MAX_DISTANCE`
/// (Bevy's `calculate_cascade_bounds`, computed once at configuration time).
pub(crate) fn far_bounds() -> [f32; CASCADES] {
    let base = (MAX_DISTANCE / FIRST_FAR).powf(1.0 / (CASCADES - 1) as f32);
    core::array::from_fn(|i| FIRST_FAR * base.powi(i as i32))
}

/// Our transcription of one cascade's per-frame output.
#[derive(Clone, Copy, Default)]
pub(crate) struct BevyCascade {
    pub(crate) world_from_cascade: Mat4,
    pub(crate) clip_from_cascade: Mat4,
    pub(crate) clip_from_world: Mat4,
    pub(crate) texel_size: f32,
}

/// Slice corners in view space for a symmetric perspective projection, near
/// face then far face, each bottom-right, top-right, top-left, bottom-left.
fn corners(fov_y: f32, aspect: f32, z_near: f32, z_far: f32) -> [Vec3A; 8] {
    let t = (fov_y * 0.5).tan();
    let (a, b) = (z_near.abs() * t, z_far.abs() * t);
    [
        Vec3A::new(a * aspect, -a, z_near),
        Vec3A::new(a * aspect, a, z_near),
        Vec3A::new(-a * aspect, a, z_near),
        Vec3A::new(-a * aspect, -a, z_near),
        Vec3A::new(b * aspect, -b, z_far),
        Vec3A::new(b * aspect, b, z_far),
        Vec3A::new(-b * aspect, b, z_far),
        Vec3A::new(-b * aspect, -b, z_far),
    ]
}

/// One cascade: light-space box of the corners, a rotation-invariant diameter
/// (body or far-face diagonal, rounded up), texel-snapped centre, reversed-Z
/// orthographic projection.
fn cascade(
    corners: [Vec3A; 8],
    map_size: f32,
    world_from_light: Mat4,
    light_from_camera: Mat4,
) -> BevyCascade {
    let mut min = Vec3A::splat(f32::MAX);
    let mut max = Vec3A::splat(f32::MIN);
    for c in corners {
        let p = light_from_camera.transform_point3a(c);
        min = min.min(p);
        max = max.max(p);
    }
    let body = (corners[0] - corners[6]).length_squared();
    let far_face = (corners[4] - corners[6]).length_squared();
    let diameter = body.max(far_face).sqrt().ceil();
    let texel = diameter / map_size;
    let center = Vec3A::new(
        (0.5 * (min.x + max.x) / texel).floor() * texel,
        (0.5 * (min.y + max.y) / texel).floor() * texel,
        max.z,
    );
    let light_from_world = world_from_light.transpose();
    let cascade_from_world = Mat4::from_cols(
        light_from_world.x_axis,
        light_from_world.y_axis,
        light_from_world.z_axis,
        (-center).extend(1.0),
    );
    let world_from_cascade = Mat4::from_cols(
        world_from_light.x_axis,
        world_from_light.y_axis,
        world_from_light.z_axis,
        world_from_light * center.extend(1.0),
    );
    let r = (max.z - min.z).recip();
    let clip_from_cascade = Mat4::from_cols(
        Vec4::new(2.0 / diameter, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 2.0 / diameter, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, 0.0),
        Vec4::new(0.0, 0.0, 1.0, 1.0),
    );
    BevyCascade {
        world_from_cascade,
        clip_from_cascade,
        clip_from_world: clip_from_cascade * cascade_from_world,
        texel_size: texel,
    }
}

/// The per-frame part for one view and one light: the light frame from its
/// rotation, then one cascade per bound. (Bevy collects into a `Vec`; a fixed
/// array here makes the reference only faster.)
pub(crate) fn cascades(
    light_rotation: Quat,
    world_from_view: Mat4,
    fov_y: f32,
    aspect: f32,
    far_bounds: &[f32; CASCADES],
) -> [BevyCascade; CASCADES] {
    let world_from_light = Mat4::from_quat(light_rotation);
    let light_from_world = world_from_light.transpose();
    let light_from_camera = light_from_world * world_from_view;
    let keep = 1.0 - OVERLAP;
    core::array::from_fn(|i| {
        let near = if i == 0 {
            MIN_DISTANCE
        } else {
            keep * far_bounds[i - 1]
        };
        cascade(
            corners(fov_y, aspect, -near, -far_bounds[i]),
            MAP_SIZE,
            world_from_light,
            light_from_camera,
        )
    })
}
