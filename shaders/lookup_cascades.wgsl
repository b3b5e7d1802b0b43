// techniques: cascades
// Shadow lookup of cascaded shadow maps: cascade selection by view depth with a
// blend band (mirrors `CascadeSplits::select` and `blend_weight`), or by projection
// (the first cascade whose map contains the point, `CascadeSet::select_by_projection`).
// Same interface as lookup_matrix.wgsl; the layer is the cascade index.

struct CascadeShadow {
    uv_from_world: array<mat4x4<f32>, 8>,
    view_z_row: vec4<f32>,
    split_far: array<vec4<f32>, 2>,
    band_width: array<vec4<f32>, 2>,
    // Scale of layer i's uv where its map fills only the layer's top-left corner
    // (cube faces of different sizes): (x, y) of layer 2k, then of 2k + 1, in row k.
    layer_uv_scale: array<vec4<f32>, 4>,
    count: u32,
    reversed_z: u32,
    select_by_projection: u32,
    // Margin for selection by projection, in texture coordinates.
    margin_uv: f32,
}

@group(1) @binding(0) var<uniform> shadow: CascadeShadow;

fn cascade_far(i: u32) -> f32 {
    return shadow.split_far[i / 4u][i % 4u];
}

fn cascade_band(i: u32) -> f32 {
    return shadow.band_width[i / 4u][i % 4u];
}

fn layer_uv_scale(i: u32) -> vec2<f32> {
    let row = shadow.layer_uv_scale[i / 2u];
    return select(row.xy, row.zw, i % 2u == 1u);
}

fn cascade_project(i: u32, world: vec3<f32>) -> vec4<f32> {
    let h = shadow.uv_from_world[i] * vec4<f32>(world, 1.0);
    if !(h.w > 0.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    return vec4<f32>(h.xyz / h.w, f32(i));
}

// Index by view depth; -1 beyond the last cascade.
fn cascade_by_depth(view_depth: f32) -> i32 {
    let n = min(shadow.count, 8u);
    if n == 0u || !(view_depth <= cascade_far(n - 1u)) {
        return -1;
    }
    for (var i = 0u; i < n; i++) {
        if view_depth <= cascade_far(i) {
            return i32(i);
        }
    }
    return i32(n) - 1;
}

fn cascade_by_projection(world: vec3<f32>) -> i32 {
    let n = min(shadow.count, 8u);
    let m = shadow.margin_uv;
    for (var i = 0u; i < n; i++) {
        let s = cascade_project(i, world);
        let inside = s.w >= 0.0 && all(s.xy >= vec2<f32>(m)) && all(s.xy <= vec2<f32>(1.0 - m))
            && s.z >= 0.0 && s.z <= 1.0;
        if inside {
            return i32(i);
        }
    }
    return -1;
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    if shadow.select_by_projection != 0u {
        return 0.0;
    }
    let i = cascade_by_depth(view_depth);
    if i < 0 || u32(i) + 1u >= min(shadow.count, 8u) {
        return 0.0;
    }
    let band = cascade_band(u32(i));
    if !(band > 0.0) {
        return 0.0;
    }
    let end = cascade_far(u32(i));
    return clamp((view_depth - (end - band)) / band, 0.0, 1.0);
}

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    var i: i32;
    if shadow.select_by_projection != 0u {
        i = cascade_by_projection(world);
    } else {
        i = cascade_by_depth(view_depth);
    }
    if i < 0 {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    var index = u32(i);
    if second {
        index = min(index + 1u, min(shadow.count, 8u) - 1u);
    }
    let s = cascade_project(index, world);
    return vec4<f32>(s.xy * layer_uv_scale(index), s.zw);
}
