// techniques: rtw
// Shadow lookup of rectilinear texture warping: the base projection's uv, each axis
// warped through its table with the exact semantics of `shadowmap_rtw::forward_warp`
// (hand-filtered by the sampler of rtw_sample.wgsl, composed in), depth from the base.
// Same interface as lookup_matrix.wgsl.

struct RtwShadow {
    clip_from_world: mat4x4<f32>,
    uv_from_world: mat4x4<f32>,
    // x: u-table texels, y: v-table texels, z: reversed-Z.
    sizes: vec4<u32>,
    // x, y: where the u and the v table start in `rtw_tables`.
    table_offsets: vec4<u32>,
    // x, y: scale of the warped uv into the layer's top-left corner (1 here).
    layer: vec4<f32>,
}

@group(1) @binding(0) var<uniform> shadow: RtwShadow;
// The u table, then the v table.
@group(1) @binding(1) var<storage, read> rtw_tables: array<f32>;

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let h = shadow.uv_from_world * vec4<f32>(world, 1.0);
    if !(h.w > 0.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let uv = h.xy / h.w;
    let warped = vec2<f32>(
        uv.x + rtw_sample(shadow.table_offsets.x, shadow.sizes.x, uv.x),
        uv.y + rtw_sample(shadow.table_offsets.y, shadow.sizes.y, uv.y),
    );
    return vec4<f32>(warped * shadow.layer.xy, h.z / h.w, 0.0);
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
