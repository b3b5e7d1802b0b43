//! The stable fit holds each cascade count's maps apart (`CascadeState`): a caller
//! that fits several counts a frame to choose among them keeps every count's maps.

use glam::Vec3;
use shadowmap_frustum::{
    Aabb, Camera, CascadeFit, CascadeOptions, CascadeSet, CascadeSplits, CascadeState, Projection,
    SceneBounds, SplitScheme, ValidCamera,
};

/// A 10 x 3 x 8 m room.
const ROOM: Aabb = Aabb {
    min: Vec3::new(-5.0, 0.0, -4.0),
    max: Vec3::new(5.0, 3.0, 4.0),
};

/// A camera in the room `walk` metres along x from its first position.
fn camera(walk: f32) -> ValidCamera {
    let camera = Camera::look_to(
        Vec3::new(-3.0 + walk, 1.6, 2.5),
        Vec3::new(0.6, -0.4, -1.0),
        Vec3::Y,
        Projection::perspective(1.0, 16.0 / 9.0, 0.1, 20.0),
    )
    .unwrap();
    ValidCamera::new(&camera).unwrap()
}

fn fit(camera: &ValidCamera, count: usize, state: &mut CascadeState) -> CascadeSet {
    let options = CascadeOptions::default()
        .with_fit(CascadeFit::Stable)
        .with_resolution(1024)
        .with_scene(Some(SceneBounds::whole(ROOM)));
    let splits =
        CascadeSplits::new(&SplitScheme::Practical { lambda: 0.5 }, count, 0.1, 20.0).unwrap();
    let light = Vec3::new(0.2, -1.0, 0.15);
    CascadeSet::fit_with_state(camera, light, &splits, &options, state).unwrap()
}

/// Two maps, then one and two again a few centimetres further: the two-map fit
/// keeps its maps (same extents, moved by whole texels) although the one-map fit
/// came between and sized a map over the whole depth range, and a fresh state
/// would have sized them anew.
#[test]
fn a_count_fitted_between_leaves_another_counts_maps_held() {
    let mut state = CascadeState::new();
    let first = fit(&camera(0.0), 2, &mut state);
    let held = [state.size(2, 0).unwrap(), state.size(2, 1).unwrap()];
    let one = fit(&camera(0.05), 1, &mut state);
    assert_eq!(one.cascades.len(), 1);
    assert!(state.size(1, 0).is_some());
    let again = fit(&camera(0.05), 2, &mut state);
    assert_eq!([state.size(2, 0), state.size(2, 1)], held.map(Some));
    let texels = |set: &CascadeSet| {
        set.cascades
            .iter()
            .map(|c| c.texel_world_size)
            .collect::<Vec<_>>()
    };
    assert_eq!(texels(&again), texels(&first));
    // Not a case where any fit would keep the sizes: fresh, the maps are sized
    // anew.
    let fresh = fit(&camera(0.05), 2, &mut CascadeState::new());
    assert_ne!(texels(&fresh), texels(&first));
}
