// techniques: any
// Shadow filter: variance shadow maps. The moments texture holds the blurred
// (depth, depth^2), depth flipped to 1 - depth for reversed-Z so that larger is
// always farther (written by filter_vsm_moments.wgsl). Bilinear filtering by hand
// (Rgba32Float is not filterable everywhere), then Chebyshev's upper bound with a
// minimum variance and light-bleeding reduction.
// Interface: see filter_hard.wgsl.

fn vsm_load(moments: texture_2d_array<f32>, texel: vec2<i32>, layer: i32, dims: vec2<i32>) -> vec2<f32> {
    return textureLoad(moments, clamp(texel, vec2<i32>(0), dims - vec2<i32>(1)), layer, 0).xy;
}

fn shadow_filter(
    depth_map: texture_depth_2d_array,
    compare: sampler_comparison,
    moments: texture_2d_array<f32>,
    coord: vec4<f32>,
    reference: f32,
    size: vec4<f32>,
    params: vec4<f32>,
) -> f32 {
    let dims = vec2<i32>(size.xy);
    let layer = i32(coord.w);
    let x = coord.xy * size.xy - 0.5;
    let base = vec2<i32>(floor(x));
    let f = x - floor(x);
    let m00 = vsm_load(moments, base, layer, dims);
    let m10 = vsm_load(moments, base + vec2<i32>(1, 0), layer, dims);
    let m01 = vsm_load(moments, base + vec2<i32>(0, 1), layer, dims);
    let m11 = vsm_load(moments, base + vec2<i32>(1, 1), layer, dims);
    let m = mix(mix(m00, m10, f.x), mix(m01, m11, f.x), f.y);
    let d = select(reference, 1.0 - reference, params.w > 0.5);
    if d <= m.x {
        return 1.0;
    }
    let variance = max(m.y - m.x * m.x, 1e-6);
    let delta = d - m.x;
    let p = variance / (variance + delta * delta);
    // Light-bleeding reduction: cut the tail below 0.2.
    return clamp((p - 0.2) / 0.8, 0.0, 1.0);
}
