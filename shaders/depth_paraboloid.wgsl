// techniques: paraboloid
// Depth pass of a paraboloid map, one side per layer. Each vertex is projected onto
// the paraboloid exactly as `ParaboloidMap::project` does (the projection of
// paraboloid_side.wgsl, composed in); casters must be subdivided (on the GPU by the
// refinement of refine.wgsl, or by `shadowmap_paraboloid::subdivide_triangles`) since
// the image of an edge is curved. The hemisphere is clipped in the fragment stage:
// `hemisphere` is the cosine of the angle from the side's axis, linearly
// interpolated, and fragments where it is negative are discarded.
//
// A layer with warp tables (RTW over the paraboloid side, `point_rtw`) then sends its
// texture coordinates through them, as `shadowmap_rtw::WarpMaps::warp_sample` does;
// tables of 0 texels leave them unchanged.
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
    // The layer's warp tables in `rtw_tables`: u offset, u texels, v offset, v texels
    // (0 texels: no warp).
    warp: vec4<u32>,
}

// Subpixel steps per pixel of the rasterizer's fixed-point grid.
const SUBPIXEL_STEPS: f32 = 256.0;

@group(0) @binding(0) var<uniform> layer: ParaboloidLayer;
// The warp tables of every layer (one zero when no layer is warped).
@group(0) @binding(1) var<storage, read> rtw_tables: array<f32>;

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

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) hemisphere: f32,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOut {
    let m = layer.map;
    let q = (m.rotation * vec4<f32>(position - m.position_near.xyz, 0.0)).xyz;
    let p = paraboloid_side(q, layer.side.x > 0.5);
    let disc = p.xy / max(p.z, 1e-20);
    var ndc = disc / m.far_zoom_reversed_dual.y;
    if layer.warp.y + layer.warp.w > 0u {
        let u = 0.5 + 0.5 * ndc.x;
        let v = 0.5 - 0.5 * ndc.y;
        let warped_u = u + rtw_sample(layer.warp.x, layer.warp.y, u);
        let warped_v = v + rtw_sample(layer.warp.z, layer.warp.w, v);
        ndc = vec2<f32>(2.0 * warped_u - 1.0, 1.0 - 2.0 * warped_v);
    }
    let near = m.position_near.w;
    let far = m.far_zoom_reversed_dual.x;
    var depth = (length(q) - near) / (far - near);
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
    out.hemisphere = p.w;
    return out;
}

@fragment
fn fs_main(in: VertexOut) {
    if in.hemisphere < 0.0 {
        discard;
    }
}
