// techniques: any
// Shadow filter: the hardware 2x2 compare (bilinear percentage-closer filtering by a
// linear comparison sampler, LessEqual, or GreaterEqual with reversed-Z).
// Interface: see filter_hard.wgsl.

fn shadow_filter(
    depth_map: texture_depth_2d_array,
    compare: sampler_comparison,
    moments: texture_2d_array<f32>,
    coord: vec4<f32>,
    reference: f32,
    size: vec4<f32>,
    params: vec4<f32>,
) -> f32 {
    return textureSampleCompareLevel(depth_map, compare, coord.xy, i32(coord.w), reference);
}
