// techniques: rtw
// RTW backward analysis on the GPU: every G-buffer sample raises its cell of the
// importance map to its importance (shadowmap_rtw::ImportanceMap::accumulate_backward),
// then each row and column of the map collapses to its maximum (WarpMaps::build).
//
//   importance = (reference_distance / max(d, min_distance))^distance_exponent
//              * w                                              (the base's footprint:
//                                   1 for an orthographic base, the light depth for a
//                                   perspective one)
//              * (1 + orientation_weight * (1 - |n . l|))      (normal given)
//              * edge_weight                                    (sample on a shadow edge)
//
// Importance is finite and >= 0, so its bit pattern orders like the float: atomicMax
// on u32 bits is the float maximum.

struct ImportanceParams {
    uv_from_world: mat4x4<f32>,
    // xyz: direction the light travels (w = 0) or light position (w = 1).
    light: vec4<f32>,
    // reference_distance, min_distance, distance_exponent, orientation_weight.
    distance: vec4<f32>,
    // x: edge_weight.
    edge: vec4<f32>,
    // x: map width, y: map height.
    map_size: vec4<u32>,
}

const F32_MAX: f32 = 3.40282347e38;
const ACCEPTED: u32 = 0u;
const SKIPPED: u32 = 1u;
const NO_SAMPLE: u32 = 2u;

@group(0) @binding(0) var<uniform> params: ImportanceParams;
// xyz: world position, w: eye distance.
@group(0) @binding(1) var gbuffer_position: texture_2d<f32>;
// xyz: normal (zero: unknown), w: 0 no sample, 1 sample, 2 sample on a shadow edge.
@group(0) @binding(2) var gbuffer_normal: texture_2d<f32>;
// The importance map, row-major, f32 bits.
@group(0) @binding(3) var<storage, read_write> cells: array<atomic<u32>>;
// Column maxima (map width), then row maxima (map height), f32 bits.
@group(0) @binding(4) var<storage, read_write> maxima: array<atomic<u32>>;
// Accepted and skipped sample counts.
@group(0) @binding(5) var<storage, read_write> counts: array<atomic<u32>, 2>;

var<workgroup> row_max: atomic<u32>;
var<workgroup> group_counts: array<atomic<u32>, 2>;

fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn all_finite(v: vec4<f32>) -> bool {
    return is_finite(v.x) && is_finite(v.y) && is_finite(v.z) && is_finite(v.w);
}

// glam's normalize_or_zero, scaled first so tiny vectors do not underflow.
fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let m = max(abs(v.x), max(abs(v.y), abs(v.z)));
    if !(m > 0.0) {
        return vec3<f32>(0.0);
    }
    let s = v / m;
    return s / length(s);
}

fn toward_light(p: vec3<f32>) -> vec3<f32> {
    if params.light.w == 0.0 {
        return -normalize_or_zero(params.light.xyz);
    }
    return normalize_or_zero(params.light.xyz - p);
}

// Splats the sample of one G-buffer texel; returns NO_SAMPLE, ACCEPTED or SKIPPED.
fn splat_texel(texel: vec2<u32>) -> u32 {
    let size = textureDimensions(gbuffer_position);
    if any(texel >= size) {
        return NO_SAMPLE;
    }
    let position_distance = textureLoad(gbuffer_position, texel, 0);
    let normal_flags = textureLoad(gbuffer_normal, texel, 0);
    if !(normal_flags.w >= 0.5) {
        return NO_SAMPLE; // background
    }
    let h = params.uv_from_world * vec4<f32>(position_distance.xyz, 1.0);
    if !all_finite(position_distance) || !all_finite(normal_flags) || !all_finite(h) || !(h.w > 0.0) {
        return SKIPPED;
    }
    let uv = h.xy / h.w;
    if !(uv.x >= 0.0 && uv.x < 1.0 && uv.y >= 0.0 && uv.y < 1.0) {
        return SKIPPED;
    }

    let ratio = params.distance.x / max(position_distance.w, params.distance.y);
    var importance = ratio;
    if params.distance.z != 1.0 {
        importance = pow(ratio, params.distance.z);
    }
    importance *= h.w;
    let n = normalize_or_zero(normal_flags.xyz);
    if any(n != vec3<f32>(0.0)) {
        let cos_light = min(abs(dot(n, toward_light(position_distance.xyz))), 1.0);
        importance *= 1.0 + params.distance.w * (1.0 - cos_light);
    }
    if normal_flags.w >= 1.5 {
        importance *= params.edge.x;
    }
    importance = min(importance, F32_MAX);

    let width = params.map_size.x;
    let height = params.map_size.y;
    let x = min(u32(uv.x * f32(width)), width - 1u);
    let y = min(u32(uv.y * f32(height)), height - 1u);
    atomicMax(&cells[y * width + x], bitcast<u32>(importance));
    return ACCEPTED;
}

// One invocation per G-buffer texel; counts go through workgroup memory so the
// global counters see one atomic per workgroup, not one per sample.
@compute @workgroup_size(16, 16, 1)
fn splat(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    if local_index < 2u {
        atomicStore(&group_counts[local_index], 0u);
    }
    workgroupBarrier();
    let status = splat_texel(gid.xy);
    if status != NO_SAMPLE {
        atomicAdd(&group_counts[status], 1u);
    }
    workgroupBarrier();
    if local_index < 2u {
        let count = atomicLoad(&group_counts[local_index]);
        if count != 0u {
            atomicAdd(&counts[local_index], count);
        }
    }
}

// One workgroup per row: the row's maximum, and every cell raises its column's.
@compute @workgroup_size(64, 1, 1)
fn collapse(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    let width = params.map_size.x;
    let y = group.x;
    if local_index == 0u {
        atomicStore(&row_max, 0u);
    }
    workgroupBarrier();
    var m = 0u;
    for (var x = local_index; x < width; x += 64u) {
        let bits = atomicLoad(&cells[y * width + x]);
        m = max(m, bits);
        atomicMax(&maxima[x], bits);
    }
    atomicMax(&row_max, m);
    workgroupBarrier();
    if local_index == 0u {
        atomicStore(&maxima[width + y], atomicLoad(&row_max));
    }
}
