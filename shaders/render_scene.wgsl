// techniques: any
// The headless renderer's scene pass: Lambert shading with the shadow of one
// technique, and a per-pixel shadow mask (1 lit, 2 shadowed, 3 not covered by the
// map; 0, the clear value, is background) from the plain nearest-texel depth test.
//
// The regions between the `@compose` markers are placeholders: at pipeline creation
// the renderer replaces them with a lookup_*.wgsl and a filter_*.wgsl source (see
// `render::compose_scene_shader`), so this file also validates on its own.

struct Frame {
    clip_from_world: mat4x4<f32>,
    view_from_world: mat4x4<f32>,
    // Directional: direction the light travels, w = 0; point: position, w = 1.
    light: vec4<f32>,
    // x: depth bias (stored-depth units), y: world bias (XPSM), z: filter radius
    // (texels), w: reversed-Z of the shadow map.
    bias: vec4<f32>,
    // width, height, layers, taps.
    shadow_size: vec4<f32>,
    // Camera position (xyz).
    eye: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(2) @binding(0) var shadow_depth: texture_depth_2d_array;
@group(2) @binding(1) var shadow_compare: sampler_comparison;
@group(2) @binding(2) var shadow_moments: texture_2d_array<f32>;

// @compose lookup begin
fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    return vec4<f32>(0.0, 0.0, 0.0, -1.0);
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
// @compose lookup end

// @compose filter begin
fn shadow_filter(
    depth_map: texture_depth_2d_array,
    compare: sampler_comparison,
    moments: texture_2d_array<f32>,
    coord: vec4<f32>,
    reference: f32,
    size: vec4<f32>,
    params: vec4<f32>,
) -> f32 {
    return 1.0;
}
// @compose filter end

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) view_depth: f32,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.clip_from_world * vec4<f32>(position, 1.0);
    out.world = position;
    out.view_depth = -(frame.view_from_world * vec4<f32>(position, 1.0)).z;
    return out;
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) mask: u32,
}

fn covered(coord: vec4<f32>) -> bool {
    return coord.w >= 0.0 && coord.w < frame.shadow_size.z && all(coord.xy >= vec2<f32>(0.0))
        && all(coord.xy <= vec2<f32>(1.0)) && coord.z == coord.z;
}

// The sample's depth moved toward the light by the bias, clamped like the depth pass.
fn biased(coord: vec4<f32>) -> f32 {
    let b = frame.bias.x;
    return clamp(select(coord.z - b, coord.z + b, frame.bias.w > 0.5), 0.0, 1.0);
}

// Plain nearest-texel test (`DepthMap::is_lit`): 1 lit, 0 shadowed.
fn hard_test(coord: vec4<f32>) -> f32 {
    let dims = vec2<u32>(frame.shadow_size.xy);
    let texel = min(vec2<u32>(coord.xy * frame.shadow_size.xy), dims - vec2<u32>(1u));
    let stored = textureLoad(shadow_depth, texel, u32(coord.w), 0);
    let reference = biased(coord);
    return select(f32(reference <= stored), f32(reference >= stored), frame.bias.w > 0.5);
}

fn filtered(coord: vec4<f32>) -> f32 {
    if !covered(coord) {
        return 1.0;
    }
    return shadow_filter(shadow_depth, shadow_compare, shadow_moments, coord, biased(coord),
        frame.shadow_size, frame.bias);
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let face = cross(dpdx(in.world), dpdy(in.world));
    var n = normalize(face);
    if dot(n, frame.eye.xyz - in.world) < 0.0 {
        n = -n;
    }
    var to_light = -normalize(frame.light.xyz);
    if frame.light.w > 0.5 {
        to_light = normalize(frame.light.xyz - in.world);
    }
    let lambert = max(dot(n, to_light), 0.0);

    let coord = shadow_lookup(in.world, in.view_depth, frame.bias.y, false);
    var out: FragmentOut;
    if covered(coord) {
        out.mask = select(2u, 1u, hard_test(coord) > 0.5);
    } else {
        out.mask = 3u;
    }
    var visibility = filtered(coord);
    let blend = shadow_blend_weight(in.world, in.view_depth);
    if blend > 0.0 {
        let next = shadow_lookup(in.world, in.view_depth, frame.bias.y, true);
        visibility = mix(visibility, filtered(next), blend);
    }
    // Albedo varies a little with the normal so that faces stay apart.
    let albedo = vec3<f32>(0.75, 0.72, 0.68) + 0.12 * n;
    let shade = 0.25 + 0.75 * lambert * visibility;
    out.color = vec4<f32>(albedo * shade, 1.0);
    return out;
}
