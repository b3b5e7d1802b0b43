// techniques: paraboloid
// Shadow lookup of a paraboloid map, mirroring `ParaboloidMap::lookup`: the side
// (front where -q.z >= 0 or the map is single), the disc, the cut, the depth as
// distance. A single map does not cover points whose uv leaves [0, 1]^2.
// Same interface as lookup_matrix.wgsl; layer 0 front, 1 back.

struct Paraboloid {
    rotation: mat4x4<f32>,
    position_near: vec4<f32>,
    // far, zoom, reversed-Z (0/1), dual (0/1)
    far_zoom_reversed_dual: vec4<f32>,
}

@group(1) @binding(0) var<uniform> shadow: Paraboloid;

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let q = (shadow.rotation * vec4<f32>(world - shadow.position_near.xyz, 0.0)).xyz;
    let distance = length(q);
    if !(distance > 0.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let d = q / distance;
    let dual = shadow.far_zoom_reversed_dual.w > 0.5;
    let back = dual && -d.z < 0.0;
    var x = d.x;
    var s = -d.z;
    if back {
        x = -d.x;
        s = d.z;
    }
    let denom = select((x * x + d.y * d.y) / (1.0 - s), 1.0 + s, s >= 0.0);
    if !(denom > 1e-30) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let ndc = vec2<f32>(x, d.y) / denom / shadow.far_zoom_reversed_dual.y;
    let uv = vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    if !dual && !(all(uv >= vec2<f32>(0.0)) && all(uv <= vec2<f32>(1.0))) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let near = shadow.position_near.w;
    let far = shadow.far_zoom_reversed_dual.x;
    var depth = (distance - near) / (far - near);
    if shadow.far_zoom_reversed_dual.z > 0.5 {
        depth = 1.0 - depth;
    }
    return vec4<f32>(uv, depth, select(0.0, 1.0, back));
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
