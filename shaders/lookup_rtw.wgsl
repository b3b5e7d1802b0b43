// techniques: rtw
// Shadow lookup of rectilinear texture warping over one base (the uniform or the spot
// fit) or several (the kept faces of a cube map, Rosen's RTW on each face's
// perspective base): the base's uv, each axis warped through that base's tables
// with the exact semantics of `shadowmap_rtw::forward_warp` (hand-filtered by the
// sampler of rtw_sample.wgsl, composed in), scaled into the base's corner of its
// layer, depth from the base. With one base every point is looked up in it (the
// scene pass decides coverage from the warped uv, as `RtwShadow::map_point` maps any
// point); with several, in the first whose window holds it (the windows are disjoint
// up to rounding, as `CubeMap::map_point` selects). Same interface as
// lookup_matrix.wgsl; the layer is the base's.

struct RtwShadow {
    clip_from_world: mat4x4<f32>,
    uv_from_world: mat4x4<f32>,
    // x: u-table texels, y: v-table texels, z: reversed-Z.
    sizes: vec4<u32>,
    // x, y: where the u and the v table start in `rtw_tables`.
    table_offsets: vec4<u32>,
    // x, y: scale of the warped uv into the layer's top-left corner.
    layer: vec4<f32>,
}

struct RtwLookup {
    bases: array<RtwShadow, 6>,
    // x: bases in use.
    count: vec4<u32>,
}

@group(1) @binding(0) var<uniform> shadow: RtwLookup;
// Every base's u table, then its v table.
@group(1) @binding(1) var<storage, read> rtw_tables: array<f32>;

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let n = min(shadow.count.x, 6u);
    for (var i = 0u; i < n; i++) {
        let base = shadow.bases[i];
        let h = base.uv_from_world * vec4<f32>(world, 1.0);
        if !(h.w > 0.0) {
            continue;
        }
        let s = h.xyz / h.w;
        let inside = all(s.xy >= vec2<f32>(0.0)) && all(s.xy <= vec2<f32>(1.0));
        if inside || n == 1u {
            let warped = vec2<f32>(
                s.x + rtw_sample(base.table_offsets.x, base.sizes.x, s.x),
                s.y + rtw_sample(base.table_offsets.y, base.sizes.y, s.y),
            );
            return vec4<f32>(warped * base.layer.xy, s.z, f32(i));
        }
    }
    return vec4<f32>(0.0, 0.0, 0.0, -1.0);
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
