// techniques: any
// Shadow filter: N x N percentage-closer filtering (N = size.w taps per side, 1 to
// 9), each tap a hardware 2x2 compare, taps spaced params.z / (N - 1) * 2 texels
// apart across a square of radius params.z texels.
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
    let n = clamp(i32(size.w), 1, 9);
    let texel = 1.0 / size.xy;
    let radius = max(params.z, 0.0);
    let step = select(0.0, 2.0 * radius / f32(n - 1), n > 1);
    var sum = 0.0;
    for (var j = 0; j < n; j++) {
        for (var i = 0; i < n; i++) {
            let offset = (vec2<f32>(f32(i), f32(j)) * step - radius) * texel;
            sum += textureSampleCompareLevel(depth_map, compare, coord.xy + offset, i32(coord.w), reference);
        }
    }
    return sum / f32(n * n);
}
