// techniques: any
// Shadow filter: Poisson-disk percentage-closer filtering, 16 taps of a fixed
// Poisson disk scaled to params.z texels, each a hardware 2x2 compare (the
// overview's "PCF with a Poisson disk").
// Interface: see filter_hard.wgsl.

const POISSON_DISK: array<vec2<f32>, 16> = array<vec2<f32>, 16>(
    vec2<f32>(-0.94201624, -0.39906216), vec2<f32>(0.94558609, -0.76890725),
    vec2<f32>(-0.09418410, -0.92938870), vec2<f32>(0.34495938, 0.29387760),
    vec2<f32>(-0.91588581, 0.45771432), vec2<f32>(-0.81544232, -0.87912464),
    vec2<f32>(-0.38277543, 0.27676845), vec2<f32>(0.97484398, 0.75648379),
    vec2<f32>(0.44323325, -0.97511554), vec2<f32>(0.53742981, -0.47373420),
    vec2<f32>(-0.26496911, -0.41893023), vec2<f32>(0.79197514, 0.19090188),
    vec2<f32>(-0.24188840, 0.99706507), vec2<f32>(-0.81409955, 0.91437590),
    vec2<f32>(0.19984126, 0.78641367), vec2<f32>(0.14383161, -0.14100790),
);

fn shadow_filter(
    depth_map: texture_depth_2d_array,
    compare: sampler_comparison,
    moments: texture_2d_array<f32>,
    coord: vec4<f32>,
    reference: f32,
    size: vec4<f32>,
    params: vec4<f32>,
) -> f32 {
    let scale = max(params.z, 0.0) / size.xy;
    var sum = 0.0;
    for (var i = 0; i < 16; i++) {
        sum += textureSampleCompareLevel(depth_map, compare, coord.xy + POISSON_DISK[i] * scale, i32(coord.w), reference);
    }
    return sum / 16.0;
}
