// techniques: cascades, paraboloid
// Min/max reduction of a depth buffer (SDSM depth bounds; IPSM's truncated frustum).
//
// Two levels: `reduce_tiles` reduces each 32x32 tile (a 16x16 workgroup, 2x2 texels per
// invocation) to one partial (min, max); `reduce_partials` reduces the partials to the
// result. Background texels (the clear value: depth >= 1, or <= 0 with reversed-Z) are
// skipped, as are NaNs. Depths are non-negative, so their bit patterns order like the
// floats and u32 min/max is float min/max (-0.0 is folded into +0.0 first).
// An empty reduction leaves min = 0xffffffff > max = 0 (the "no sample" marker).

override REVERSED_Z: bool = false;

const EMPTY_MIN: u32 = 0xffffffffu;
const EMPTY_MAX: u32 = 0u;

@group(0) @binding(0) var depth_texture: texture_depth_2d;
// Pairs (min bits, max bits), one per tile.
@group(0) @binding(1) var<storage, read_write> partials: array<vec2<u32>>;
// (min bits, max bits) of the whole buffer.
@group(0) @binding(2) var<storage, read_write> result: vec2<u32>;

var<workgroup> group_min: atomic<u32>;
var<workgroup> group_max: atomic<u32>;

// Bits of a visible depth (0xffffffff for background or NaN, which min ignores).
fn visible_bits(d: f32) -> u32 {
    var visible: bool;
    if REVERSED_Z {
        visible = d > 0.0 && d <= 1.0;
    } else {
        visible = d >= 0.0 && d < 1.0;
    }
    if !visible {
        return EMPTY_MIN;
    }
    return select(bitcast<u32>(d), 0u, d == 0.0);
}

@compute @workgroup_size(16, 16, 1)
fn reduce_tiles(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if local_index == 0u {
        atomicStore(&group_min, EMPTY_MIN);
        atomicStore(&group_max, EMPTY_MAX);
    }
    workgroupBarrier();

    let size = textureDimensions(depth_texture);
    var lo = EMPTY_MIN;
    var hi = EMPTY_MAX;
    for (var k = 0u; k < 4u; k++) {
        let texel = gid.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
        if all(texel < size) {
            let bits = visible_bits(textureLoad(depth_texture, texel, 0));
            if bits != EMPTY_MIN {
                lo = min(lo, bits);
                hi = max(hi, bits);
            }
        }
    }
    if lo != EMPTY_MIN {
        atomicMin(&group_min, lo);
        atomicMax(&group_max, hi);
    }
    workgroupBarrier();

    if local_index == 0u {
        let tile = group.y * groups.x + group.x;
        partials[tile] = vec2<u32>(atomicLoad(&group_min), atomicLoad(&group_max));
    }
}

@compute @workgroup_size(256, 1, 1)
fn reduce_partials(@builtin(local_invocation_index) local_index: u32) {
    if local_index == 0u {
        atomicStore(&group_min, EMPTY_MIN);
        atomicStore(&group_max, EMPTY_MAX);
    }
    workgroupBarrier();

    // The partials binding is sized to the tile count of the buffer being reduced.
    let count = arrayLength(&partials);
    var lo = EMPTY_MIN;
    var hi = EMPTY_MAX;
    for (var i = local_index; i < count; i += 256u) {
        let p = partials[i];
        lo = min(lo, p.x);
        hi = max(hi, p.y);
    }
    atomicMin(&group_min, lo);
    atomicMax(&group_max, hi);
    workgroupBarrier();

    if local_index == 0u {
        result = vec2<u32>(atomicLoad(&group_min), atomicLoad(&group_max));
    }
}
