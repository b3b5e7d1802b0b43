// techniques: paraboloid
// Depth pass of a paraboloid map, one side per layer. Each vertex is projected onto
// the paraboloid exactly as `ParaboloidMap::project` does; casters must be subdivided
// on the CPU (`shadowmap_paraboloid::subdivide_triangles`) since the image of an edge
// is curved. The hemisphere is clipped in the fragment stage: `hemisphere` is the
// cosine of the angle from the side's axis, linearly interpolated, and fragments
// where it is negative are discarded.
//
// The projected position is snapped to the rasterizer's 1/256-pixel grid (as in
// depth_rtw.wgsl): near the rim the map compresses, depth slopes grow, and a
// rasterizer that builds the depth plane from unsnapped positions (llvmpipe) would
// otherwise store depths up to slope/512 away from one using the snapped positions.

struct Paraboloid {
    rotation: mat4x4<f32>,
    position_near: vec4<f32>,
    // far, zoom, reversed-Z (0/1), dual (0/1)
    far_zoom_reversed_dual: vec4<f32>,
}

struct ParaboloidLayer {
    map: Paraboloid,
    // x: 0 front (faces light-space -Z), 1 back; y: map texels per side (0: no
    // snapping).
    side: vec4<f32>,
}

// Subpixel steps per pixel of the rasterizer's fixed-point grid.
const SUBPIXEL_STEPS: f32 = 256.0;

@group(0) @binding(0) var<uniform> layer: ParaboloidLayer;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) hemisphere: f32,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOut {
    let m = layer.map;
    let q = (m.rotation * vec4<f32>(position - m.position_near.xyz, 0.0)).xyz;
    let distance = length(q);
    let d = q / max(distance, 1e-30);
    var x = d.x;
    var s = -d.z;
    if layer.side.x > 0.5 {
        x = -d.x;
        s = d.z;
    }
    // 1 + s, accurate near the pole too: (1 + s)(1 - s) = x^2 + y^2.
    let denom = select((x * x + d.y * d.y) / (1.0 - s), 1.0 + s, s >= 0.0);
    let disc = vec2<f32>(x, d.y) / max(denom, 1e-20);
    let ndc = disc / m.far_zoom_reversed_dual.y;
    let near = m.position_near.w;
    let far = m.far_zoom_reversed_dual.x;
    var depth = (distance - near) / (far - near);
    if m.far_zoom_reversed_dual.z > 0.5 {
        depth = 1.0 - depth;
    }
    var snapped = ndc;
    if layer.side.y > 0.0 {
        // ndc spans 2 map widths: half the resolution's subpixel steps per unit.
        let steps = 0.5 * layer.side.y * SUBPIXEL_STEPS;
        snapped = round(ndc * steps) / steps;
    }
    var out: VertexOut;
    out.clip = vec4<f32>(snapped, depth, 1.0);
    out.hemisphere = s;
    return out;
}

@fragment
fn fs_main(in: VertexOut) {
    if in.hemisphere < 0.0 {
        discard;
    }
}
