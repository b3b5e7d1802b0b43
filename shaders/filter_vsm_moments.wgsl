// techniques: any
// Variance shadow maps, the moments pass and the separable blur, as fragment passes
// over a full-screen triangle, one layer at a time:
//   fs_moments: (d, d^2) of the depth map, d = 1 - depth with reversed-Z;
//   fs_blur:    Gaussian blur of the moments along `direction`, radius texels
//               (sigma = radius / 2), clamped to the edge.

struct VsmParams {
    // Layer to read.
    layer: u32,
    // Blur radius in texels (0: copy).
    radius: u32,
    // 1 with reversed-Z.
    reversed_z: u32,
    pad: u32,
    // (1, 0) horizontal, (0, 1) vertical.
    direction: vec2<i32>,
    pad2: vec2<i32>,
}

@group(0) @binding(0) var depth_map: texture_depth_2d_array;
@group(0) @binding(1) var moments_in: texture_2d_array<f32>;
@group(0) @binding(2) var<uniform> vsm: VsmParams;

@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_moments(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let stored = textureLoad(depth_map, vec2<i32>(frag.xy), i32(vsm.layer), 0);
    let d = select(stored, 1.0 - stored, vsm.reversed_z != 0u);
    return vec4<f32>(d, d * d, 0.0, 1.0);
}

@fragment
fn fs_blur(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let dims = vec2<i32>(textureDimensions(moments_in));
    let centre = vec2<i32>(frag.xy);
    let r = i32(min(vsm.radius, 32u));
    let sigma = max(f32(r) * 0.5, 0.5);
    var sum = vec4<f32>(0.0);
    var total = 0.0;
    for (var k = -r; k <= r; k++) {
        let w = exp(-0.5 * f32(k * k) / (sigma * sigma));
        let p = clamp(centre + vsm.direction * k, vec2<i32>(0), dims - vec2<i32>(1));
        sum += w * textureLoad(moments_in, p, i32(vsm.layer), 0);
        total += w;
    }
    return sum / total;
}
