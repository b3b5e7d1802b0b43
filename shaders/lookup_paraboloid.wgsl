// techniques: paraboloid
// Shadow lookup of a paraboloid map, mirroring `ParaboloidMap::lookup`: the side
// (front where -q.z >= 0 or the map is single), the disc (paraboloid_side.wgsl,
// composed in), the cut, the depth as distance. A single map does not cover points
// whose uv leaves [0, 1]^2. With warp tables for the side (RTW over the paraboloid,
// `point_rtw`), the uv then goes through them as `WarpMaps::warp_sample` does.
// Same interface as lookup_matrix.wgsl; layer 0 front, 1 back.

struct Paraboloid {
    rotation: mat4x4<f32>,
    position_near: vec4<f32>,
    // far, zoom, reversed-Z (0/1), dual (0/1)
    far_zoom_reversed_dual: vec4<f32>,
}

struct ParaboloidLookup {
    map: Paraboloid,
    // Per side (front, back): the warp tables in `rtw_tables` as u offset, u texels,
    // v offset, v texels (0 texels: no warp).
    warp: array<vec4<u32>, 2>,
}

@group(1) @binding(0) var<uniform> shadow: ParaboloidLookup;
// The warp tables of both sides (one zero when neither is warped).
@group(1) @binding(1) var<storage, read> rtw_tables: array<f32>;

// @compose paraboloid_side begin
// Placeholder: the projection of paraboloid_side.wgsl is composed in here.
fn paraboloid_side(q: vec3<f32>, back: bool) -> vec4<f32> {
    return vec4<f32>(0.0, 0.0, 1.0, 1.0);
}
// @compose paraboloid_side end

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let m = shadow.map;
    let q = (m.rotation * vec4<f32>(world - m.position_near.xyz, 0.0)).xyz;
    let dual = m.far_zoom_reversed_dual.w > 0.5;
    let back = dual && -q.z < 0.0;
    let distance = length(q);
    let p = paraboloid_side(q, back);
    if !(distance > 0.0) || !(p.z > 1e-30) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let ndc = p.xy / p.z / m.far_zoom_reversed_dual.y;
    var uv = vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    if !dual && !(all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0))) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let warp = shadow.warp[select(0u, 1u, back)];
    if warp.y + warp.w > 0u {
        uv += vec2<f32>(rtw_sample(warp.x, warp.y, uv.x), rtw_sample(warp.z, warp.w, uv.y));
    }
    let near = m.position_near.w;
    let far = m.far_zoom_reversed_dual.x;
    var depth = (distance - near) / (far - near);
    if m.far_zoom_reversed_dual.z > 0.5 {
        depth = 1.0 - depth;
    }
    return vec4<f32>(uv, depth, select(0.0, 1.0, back));
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
