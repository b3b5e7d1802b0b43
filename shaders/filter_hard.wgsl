// techniques: any
// Shadow filter: one nearest texel, the plain depth test (what the CPU reference
// `DepthMap::is_lit` computes). 1 lit, 0 shadowed.
//
// Interface (shared by every filter_*.wgsl, composed into render_scene.wgsl):
//   coord = (u, v, depth, layer) from shadow_lookup; reference = the biased depth
//   clamped to [0, 1]; size = (width, height, layers, taps); params = (depth bias,
//   world bias, radius in texels, reversed-Z).

fn shadow_filter(
    depth_map: texture_depth_2d_array,
    compare: sampler_comparison,
    moments: texture_2d_array<f32>,
    coord: vec4<f32>,
    reference: f32,
    size: vec4<f32>,
    params: vec4<f32>,
) -> f32 {
    let dims = vec2<u32>(size.xy);
    let texel = min(vec2<u32>(coord.xy * size.xy), dims - vec2<u32>(1u));
    let stored = textureLoad(depth_map, texel, u32(coord.w), 0);
    return select(f32(reference <= stored), f32(reference >= stored), params.w > 0.5);
}
