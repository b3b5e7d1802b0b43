//! A view the unit tests of this crate share.

use glam::Vec3;
use shadowmap_frustum::{Aabb, Camera, Projection, SceneBounds, ShadowTransform};
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
