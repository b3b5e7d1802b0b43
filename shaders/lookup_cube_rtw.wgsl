// techniques: rtw
// Shadow lookup of rectilinear texture warping over the kept faces of a cube map
// (Rosen's RTW on each face's perspective base): the first face whose window holds
// the point (the windows are disjoint up to rounding; the cube lookup of
// lookup_cascades.wgsl selects the same way), its uv warped through the face's
// tables with the exact semantics of `shadowmap_rtw::forward_warp` (the sampler of
// rtw_sample.wgsl, composed in) and scaled into the face's corner of its layer;
// depth from the base. Same interface as lookup_matrix.wgsl; the layer is the face's.

struct RtwShadow {
    clip_from_world: mat4x4<f32>,
    uv_from_world: mat4x4<f32>,
    // x: u-table texels, y: v-table texels, z: reversed-Z.
    sizes: vec4<u32>,
    // x, y: where the u and the v table start in `rtw_tables`.
    table_offsets: vec4<u32>,
    // x, y: scale of the warped uv into the layer's top-left corner.
    layer: vec4<f32>,
}

struct WarpedCube {
    faces: array<RtwShadow, 6>,
    // x: kept faces.
    count: vec4<u32>,
}

@group(1) @binding(0) var<uniform> shadow: WarpedCube;
// Every face's u table, then its v table.
@group(1) @binding(1) var<storage, read> rtw_tables: array<f32>;

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let n = min(shadow.count.x, 6u);
    for (var i = 0u; i < n; i++) {
        let face = shadow.faces[i];
        let h = face.uv_from_world * vec4<f32>(world, 1.0);
        if !(h.w > 0.0) {
            continue;
        }
        let s = h.xyz / h.w;
        let inside = all(s.xy >= vec2<f32>(0.0)) && all(s.xy <= vec2<f32>(1.0))
            && s.z >= 0.0 && s.z <= 1.0;
        if inside {
            let warped = vec2<f32>(
                s.x + rtw_sample(face.table_offsets.x, face.sizes.x, s.x),
                s.y + rtw_sample(face.table_offsets.y, face.sizes.y, s.y),
            );
            return vec4<f32>(warped * face.layer.xy, s.z, f32(i));
        }
    }
    return vec4<f32>(0.0, 0.0, 0.0, -1.0);
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
