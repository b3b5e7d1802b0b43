//! Every `#[repr(C)]` uniform block has the size and member offsets naga computes for
//! the WGSL struct of the same role, so no vec3 padding or array stride differs.

use core::mem::{offset_of, size_of};

use glam::{Mat4, Vec3};
use shadowmap::frustum::{
    Aabb, Camera, Light, LightDirection, Projection, SceneBounds, ShadowTransform,
};
use shadowmap::paraboloid::{ParaboloidMap, ParaboloidUniform};
use shadowmap::warp::LispsmOptions;
use shadowmap::{CascadePlan, DpsmOptions, FitInput, Fitted, Technique, fit};
use shadowmap_wgpu::shaders;
use shadowmap_wgpu::uniforms::{
    CascadeShadowRaw, FrameRaw, MatrixShadowRaw, ParaboloidLayerRaw, ParaboloidLookupRaw,
    RtwLookupRaw, RtwShadowRaw, ToRaw, cascade_layers, paraboloid_layers, warped_cascade_layers,
};

/// (struct span, member offsets) of `name` in `source`, by naga's layouter.
fn wgsl_layout(source: &str, name: &str) -> (u32, Vec<(String, u32)>) {
    let module = naga::front::wgsl::parse_str(source).expect("parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name) {
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let offsets = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                    .collect();
                return (*span, offsets);
            }
        }
    }
    panic!("struct {name} not found");
}

fn check(source: &str, name: &str, size: usize, offsets: &[(&str, usize)]) {
    let (span, members) = wgsl_layout(source, name);
    assert_eq!(span as usize, size, "{name}: size");
    assert_eq!(members.len(), offsets.len(), "{name}: member count");
    for ((wgsl_name, wgsl_offset), (rust_name, rust_offset)) in members.iter().zip(offsets) {
        assert_eq!(wgsl_name, rust_name, "{name}: member order");
        assert_eq!(
            *wgsl_offset as usize, *rust_offset,
            "{name}.{rust_name}: offset"
        );
    }
}

#[test]
fn matrix_block_matches_every_shader_that_reads_it() {
    let offsets = [
        (
            "clip_from_world",
            offset_of!(MatrixShadowRaw, clip_from_world),
        ),
        ("uv_from_world", offset_of!(MatrixShadowRaw, uv_from_world)),
        ("params", offset_of!(MatrixShadowRaw, params)),
    ];
    for source in [shaders::DEPTH_MATRIX, shaders::LOOKUP_MATRIX] {
        check(
            source,
            "MatrixShadow",
            size_of::<MatrixShadowRaw>(),
            &offsets,
        );
    }
}

#[test]
fn cascade_block_matches() {
    check(
        shaders::LOOKUP_CASCADES,
        "CascadeShadow",
        size_of::<CascadeShadowRaw>(),
        &[
            ("uv_from_world", offset_of!(CascadeShadowRaw, uv_from_world)),
            ("view_z_row", offset_of!(CascadeShadowRaw, view_z_row)),
            ("split_far", offset_of!(CascadeShadowRaw, split_far)),
            ("band_width", offset_of!(CascadeShadowRaw, band_width)),
            (
                "layer_uv_scale",
                offset_of!(CascadeShadowRaw, layer_uv_scale),
            ),
            ("count", offset_of!(CascadeShadowRaw, count)),
            ("reversed_z", offset_of!(CascadeShadowRaw, reversed_z)),
            (
                "select_by_projection",
                offset_of!(CascadeShadowRaw, select_by_projection),
            ),
            ("margin_uv", offset_of!(CascadeShadowRaw, margin_uv)),
        ],
    );
}

#[test]
fn paraboloid_blocks_match() {
    let map_offsets = [
        ("rotation", offset_of!(ParaboloidUniform, rotation)),
        (
            "position_near",
            offset_of!(ParaboloidUniform, position_near),
        ),
        (
            "far_zoom_reversed_dual",
            offset_of!(ParaboloidUniform, far_zoom_reversed_dual),
        ),
    ];
    for source in [
        shaders::DEPTH_PARABOLOID,
        shaders::LOOKUP_PARABOLOID,
        shaders::REFINE,
    ] {
        check(
            source,
            "Paraboloid",
            size_of::<ParaboloidUniform>(),
            &map_offsets,
        );
    }
    check(
        shaders::DEPTH_PARABOLOID,
        "ParaboloidLayer",
        size_of::<ParaboloidLayerRaw>(),
        &[
            ("map", offset_of!(ParaboloidLayerRaw, map)),
            ("side", offset_of!(ParaboloidLayerRaw, side)),
            ("warp", offset_of!(ParaboloidLayerRaw, warp)),
        ],
    );
    check(
        shaders::LOOKUP_PARABOLOID,
        "ParaboloidLookup",
        size_of::<ParaboloidLookupRaw>(),
        &[
            ("map", offset_of!(ParaboloidLookupRaw, map)),
            ("warp", offset_of!(ParaboloidLookupRaw, warp)),
        ],
    );
}

#[test]
fn rtw_and_frame_blocks_match() {
    let rtw = [
        ("clip_from_world", offset_of!(RtwShadowRaw, clip_from_world)),
        ("uv_from_world", offset_of!(RtwShadowRaw, uv_from_world)),
        ("sizes", offset_of!(RtwShadowRaw, sizes)),
        ("table_offsets", offset_of!(RtwShadowRaw, table_offsets)),
        ("layer", offset_of!(RtwShadowRaw, layer)),
    ];
    for source in [shaders::DEPTH_RTW, shaders::LOOKUP_RTW] {
        check(source, "RtwShadow", size_of::<RtwShadowRaw>(), &rtw);
    }
    check(
        shaders::LOOKUP_RTW,
        "RtwLookup",
        size_of::<RtwLookupRaw>(),
        &[
            ("bases", offset_of!(RtwLookupRaw, bases)),
            ("count", offset_of!(RtwLookupRaw, count)),
        ],
    );
    check(
        shaders::RENDER_SCENE,
        "Frame",
        size_of::<FrameRaw>(),
        &[
            ("clip_from_world", offset_of!(FrameRaw, clip_from_world)),
            ("view_from_world", offset_of!(FrameRaw, view_from_world)),
            ("light", offset_of!(FrameRaw, light)),
            ("bias", offset_of!(FrameRaw, bias)),
            ("shadow_size", offset_of!(FrameRaw, shadow_size)),
            ("eye", offset_of!(FrameRaw, eye)),
        ],
    );
}

#[test]
fn tiled_lookup_block_matches() {
    use shadowmap_wgpu::tiles::TiledLookupRaw;
    check(
        shaders::LOOKUP_TILES,
        "TiledShadow",
        size_of::<TiledLookupRaw>(),
        &[
            ("uv_from_world", offset_of!(TiledLookupRaw, uv_from_world)),
            ("counts", offset_of!(TiledLookupRaw, counts)),
            ("params", offset_of!(TiledLookupRaw, params)),
        ],
    );
}

#[test]
fn to_raw_copies_the_math_crates_outputs() {
    let camera = Camera::look_to(
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::NEG_Z,
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.1, 100.0),
    )
    .unwrap();
    // Three cascades of 512² (the only power-of-two side the budget offers),
    // logarithmic splits with a 20% blend band, reversed-Z.
    let plan = CascadePlan::default()
        .with_max_cascades(3)
        .with_split_lambda(1.0)
        .with_overlap(0.2)
        .with_reversed_z(true);
    let light = Light::Directional {
        direction: Vec3::new(0.3, -1.0, 0.2),
    };
    let ground = Aabb::new(
        Vec3::new(-100.0, -1.0, -110.0),
        Vec3::new(100.0, 10.0, 10.0),
    );
    let input = FitInput::new(&camera, &light, SceneBounds::whole(ground), 3 * 512 * 512);
    let Fitted::Cascades(set) = fit(&Technique::StableCascades(plan), &input)
        .unwrap()
        .fitted()
        .clone()
    else {
        panic!("cascades expected");
    };
    let splits = set.splits.clone();
    let raw = set.to_raw();
    assert_eq!(raw.count, 3);
    assert_eq!(raw.reversed_z, 1);
    for i in 0..3 {
        assert_eq!(
            raw.uv_from_world[i],
            set.cascades[i].transform.uv_from_world.to_cols_array_2d()
        );
        assert_eq!(raw.split_far[0][i], splits.depths()[i + 1]);
        assert_eq!(raw.band_width[0][i], splits.band_width(i));
    }
    assert_eq!(
        raw.uv_from_world[3], [[0.0; 4]; 4],
        "unused cascades are zero"
    );
    // View depth of a point through the packed row equals the camera's.
    let p = Vec3::new(1.0, 0.5, -20.0);
    let row = glam::Vec4::from_array(raw.view_z_row);
    assert!((-row.dot(p.extend(1.0)) - camera.view_depth(p)).abs() < 1e-4);
    let by_projection = raw.with_selection_by_projection(2.0, set.resolution);
    assert_eq!(by_projection.select_by_projection, 1);
    assert!((by_projection.margin_uv - 2.0 / set.resolution as f32).abs() < 1e-9);
    assert_eq!(raw.with_selection_by_projection(f32::NAN, 0).margin_uv, 0.0);
    assert_eq!(cascade_layers(&set).len(), 3);

    let lamp = Light::Point {
        position: Vec3::new(1.0, 2.0, 3.0),
        range: 50.0,
    };
    let input = FitInput::new(&camera, &lamp, SceneBounds::whole(ground), 1 << 20);
    let dpsm = Technique::Dpsm(DpsmOptions::default().with_near(0.5));
    let shadow = fit(&dpsm, &input).unwrap();
    let map = shadow.paraboloid().unwrap();
    let p = ToRaw::to_raw(map);
    let reference = ParaboloidMap::to_raw(map);
    assert_eq!(p.rotation, reference.rotation);
    assert_eq!(p.position_near, [1.0, 2.0, 3.0, 0.5]);
    assert_eq!(p.far_zoom_reversed_dual, [50.0, 1.0, 0.0, 1.0]);
    let layers = paraboloid_layers(map);
    assert_eq!(layers.len(), 2);
    assert_eq!((layers[0].side[0], layers[1].side[0]), (0.0, 1.0));

    let t = ShadowTransform::new(
        Mat4::IDENTITY,
        Mat4::from_translation(Vec3::X),
        false,
        LightDirection::Position(Vec3::new(4.0, 5.0, 6.0)),
    );
    let m = t.to_raw();
    assert_eq!(m.clip_from_world[3], [1.0, 0.0, 0.0, 1.0]);
    assert_eq!(m.params, [0.0; 4]);
    assert_eq!(
        FrameRaw::light_vector(LightDirection::Position(Vec3::new(4.0, 5.0, 6.0))),
        [4.0, 5.0, 6.0, 1.0]
    );
}

#[test]
fn warped_cascade_blocks_carry_the_fits_bands_and_view_depth() {
    let camera = Camera::look_at(
        Vec3::new(0.0, 10.0, 30.0),
        Vec3::ZERO,
        Vec3::Y,
        Projection::perspective(1.0, 1.5, 0.5, 200.0),
    )
    .unwrap();
    let scene = SceneBounds::whole(Aabb::new(
        Vec3::new(-100.0, 0.0, -100.0),
        Vec3::new(100.0, 20.0, 100.0),
    ));
    let light = Light::Directional {
        direction: Vec3::new(-0.7, -0.7, 0.2),
    };
    let technique = Technique::WarpedCascades {
        plan: CascadePlan::default()
            .with_max_cascades(3)
            .with_split_lambda(0.7)
            .with_overlap(0.2),
        lispsm: LispsmOptions::default().with_reversed_z(true),
    };
    let input = FitInput::new(&camera, &light, scene, 3 * 512 * 512);
    let Fitted::WarpedCascades { cascades, .. } = fit(&technique, &input).unwrap().fitted().clone()
    else {
        panic!("warped cascades expected");
    };
    let mut set = cascades;
    let view = camera.view_from_world().unwrap();
    let raw = CascadeShadowRaw::from_warped(&set, view);
    assert_eq!(
        (raw.count, raw.reversed_z, raw.select_by_projection),
        (3, 1, 0)
    );
    for (i, c) in set.cascades.iter().enumerate() {
        assert_eq!(raw.split_far[i / 4][i % 4], c.far);
        let expected = set.cascades.get(i + 1).map_or(0.0, |n| c.far - n.near);
        assert!((raw.band_width[i / 4][i % 4] - expected).abs() < 1e-6);
        let uv = c.shadow.unwrap().transform.uv_from_world.to_cols_array_2d();
        assert_eq!(raw.uv_from_world[i], uv);
    }
    assert!(raw.band_width[0][0] > 0.0, "overlapping splits blend");
    let p = Vec3::new(2.0, 1.0, -30.0);
    let row = glam::Vec4::from_array(raw.view_z_row);
    assert!((-row.dot(p.extend(1.0)) - camera.view_depth(p)).abs() < 1e-4);

    // A cascade without a fit: a zero lookup matrix (w = 0, not covered) and a depth
    // block that puts every vertex outside the clip volume.
    set.cascades[1].shadow = None;
    let raw = CascadeShadowRaw::from_warped(&set, view);
    assert_eq!(raw.uv_from_world[1], [[0.0; 4]; 4]);
    let layers = warped_cascade_layers(&set);
    assert_eq!(layers.len(), 3);
    let clip = Mat4::from_cols_array_2d(&layers[1].clip_from_world) * p.extend(1.0);
    assert!(clip.z < 0.0 && clip.w > 0.0, "{clip}");
    assert_eq!(
        layers[0],
        set.cascades[0].shadow.unwrap().transform.to_raw()
    );
}
