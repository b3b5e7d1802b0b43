// techniques: rtw
// Depth pass of rectilinear texture warping: the base projection, then each texture
// axis warped through its table (one layer per base: a single map, or each kept face
// of a cube map in its layer's top-left corner). The tables are filtered by hand
// with the exact texel-centre linear, clamp-to-edge semantics of
// `shadowmap_rtw::forward_warp` (the sampler of rtw_sample.wgsl, composed in), so the
// CPU and the GPU agree. Casters must be subdivided: the warp is piecewise linear
// between table texel centres.
//
// The warped position is snapped to the rasterizer's 1/256-pixel grid here. Where the
// warp compresses (low importance), triangles become slivers with a depth slope of
// 0.1-1 per texel; a rasterizer that snaps for coverage but builds the depth plane
// from the unsnapped position (Mesa's llvmpipe does) then stores depths up to
// slope/512 away from one that uses the snapped position (the reference rasterizer,
// most hardware). Snapping first makes both agree; where the rasterizer already
// snaps to 1/256 it changes nothing.

struct RtwShadow {
    clip_from_world: mat4x4<f32>,
    uv_from_world: mat4x4<f32>,
    // x: u-table texels, y: v-table texels, z: reversed-Z, w: map texels per side
    // (0: no snapping).
    sizes: vec4<u32>,
    // x, y: where the u and the v table start in `rtw_tables`.
    table_offsets: vec4<u32>,
    // x, y: scale of the warped uv into the layer's top-left corner (1: the map
    // fills the layer; cube faces of different sizes); z: the near plane's w where
    // the casters were cut to a window (unused here).
    layer: vec4<f32>,
}

// Subpixel steps per pixel of the rasterizer's fixed-point grid.
const SUBPIXEL_STEPS: f32 = 256.0;

@group(0) @binding(0) var<uniform> rtw: RtwShadow;
// The u table, then the v table.
@group(0) @binding(1) var<storage, read> rtw_tables: array<f32>;

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    let clip = rtw.clip_from_world * vec4<f32>(position, 1.0);
    // The base is orthographic (w = 1); a perspective base is divided first.
    let ndc = clip.xyz / clip.w;
    let uv = vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    let warped = vec2<f32>(
        uv.x + rtw_sample(rtw.table_offsets.x, rtw.sizes.x, uv.x),
        uv.y + rtw_sample(rtw.table_offsets.y, rtw.sizes.y, uv.y),
    ) * rtw.layer.xy;
    var snapped = warped;
    if rtw.sizes.w > 0u {
        // Pixels times the 2^8 subpixel steps of Vulkan/D3D rasterizers; the result
        // converts back exactly for power-of-two resolutions, within an ulp otherwise.
        let steps = f32(rtw.sizes.w) * SUBPIXEL_STEPS;
        snapped = round(warped * steps) / steps;
    }
    return vec4<f32>(2.0 * snapped.x - 1.0, 1.0 - 2.0 * snapped.y, ndc.z, 1.0);
}
