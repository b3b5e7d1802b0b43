// techniques: rtw
// RTW warp tables from the collapsed importance, one workgroup per axis (workgroup 0:
// u from the column maxima, workgroup 1: v from the row maxima), exactly the steps of
// shadowmap_rtw::WarpMaps::build:
//
//   blurred_i = sum_k w_|k| * m_clamp(i + k)         Gaussian, clamp-to-edge
//   current_i = blurred_i / max(blurred)              (1 everywhere if max is 0: identity)
//   density_i = clamp(a * density_i + (1 - a) * current_i, floor, 1)
//                                                     a = temporal weight after a first build
//   T_0 = T_{N-1} = 0,  T_k = c_0 + scale * sum_{j<k} (d_j + d_{j+1}) / 2 - c_k
//   c_k = (k + 0.5) / N,  scale = ((N - 1) / N) / sum_{j<N-1} (d_j + d_{j+1}) / 2
//
// (T = 0 everywhere when the density is constant.) The cumulative sum is a
// workgroup scan: each invocation sums a contiguous chunk, then a Hillis-Steele scan
// over the 256 chunk sums; rounding error grows with log2 of the length, not with it.

struct WarpParams {
    // x: map width (u-table texels), y: map height (v-table texels), z: blur radius.
    sizes: vec4<u32>,
    // x: floor, y: temporal weight.
    knobs: vec4<f32>,
    // Normalized Gaussian weights w_0..w_radius, four per vector.
    weights: array<vec4<f32>, 17>,
}

const GROUP: u32 = 256u;

@group(0) @binding(0) var<uniform> params: WarpParams;
// Column maxima (width), then row maxima (height).
@group(0) @binding(1) var<storage, read> maxima: array<f32>;
// Scratch: the blurred maxima, then the cumulative sums.
@group(0) @binding(2) var<storage, read_write> scratch: array<f32>;
// The density of the last build, kept for temporal smoothing.
@group(0) @binding(3) var<storage, read_write> density: array<f32>;
// The u table (width texels), then the v table (height texels).
@group(0) @binding(4) var<storage, read_write> tables: array<f32>;
// 0, 1: whether axis u, v has been built before (temporal history);
// 2, 3: whether axis u, v fell back to the identity.
@group(0) @binding(5) var<storage, read_write> state: array<u32, 4>;

var<workgroup> input_max: atomic<u32>;
var<workgroup> blurred_max: atomic<u32>;
var<workgroup> density_min: atomic<u32>;
var<workgroup> density_max: atomic<u32>;
var<workgroup> constant_density: u32;
var<workgroup> scan: array<f32, GROUP>;

fn weight(k: u32) -> f32 {
    return params.weights[k / 4u][k % 4u];
}

// 2^k for -126 <= k <= 127, built from its bits (exact on every GPU).
fn power_of_two(k: i32) -> f32 {
    return bitcast<f32>(u32(k + 127) << 23u);
}

// Two factors whose product is 2^-(e + 1) for a peak of exponent e (so peak times both
// lies in [0.5, 1)); each factor is a normal f32 even for peaks near f32::MAX or
// subnormal peaks, and multiplying by a power of two is exact. (1, 1) for a zero peak.
fn inverse_power_of_two_scale(peak_bits: u32) -> vec2<f32> {
    if peak_bits == 0u {
        return vec2<f32>(1.0);
    }
    let e = i32((peak_bits >> 23u) & 0xffu) - 127;
    let total = e + 1;
    let first = total / 2;
    return vec2<f32>(power_of_two(-first), power_of_two(first - total));
}

@compute @workgroup_size(256, 1, 1)
fn build_axis(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let axis = min(group.x, 1u);
    let n = select(params.sizes.x, params.sizes.y, axis == 1u);
    let offset = select(0u, params.sizes.x, axis == 1u);
    let radius = params.sizes.z;
    let last = i32(n) - 1;
    if lid == 0u {
        atomicStore(&input_max, 0u);
        atomicStore(&blurred_max, 0u);
        atomicStore(&density_min, 0xffffffffu);
        atomicStore(&density_max, 0u);
    }
    workgroupBarrier();

    // The input's peak: the blur runs on m * 2^-e (peak * 2^-e in [0.5, 1)), which
    // cannot overflow where importance saturates near f32::MAX (the CPU blurs in f64).
    // The ratio blurred / max(blurred) is unchanged. No division: WGSL guarantees x / y
    // only for |y| in [2^-126, 2^126], and GPUs that divide as x * (1 / y) flush the
    // subnormal 1 / y of a larger peak to zero, which zeroed the whole axis.
    var local_peak = 0u;
    for (var i = lid; i < n; i += GROUP) {
        local_peak = max(local_peak, bitcast<u32>(maxima[offset + i]));
    }
    atomicMax(&input_max, local_peak);
    workgroupBarrier();
    let input_scale = inverse_power_of_two_scale(atomicLoad(&input_max));

    // Blur and its maximum.
    var local_max = 0.0;
    for (var i = lid; i < n; i += GROUP) {
        var acc = weight(0u) * (maxima[offset + i] * input_scale.x * input_scale.y);
        for (var k = 1u; k <= radius; k++) {
            let lo = u32(clamp(i32(i) - i32(k), 0, last));
            let hi = u32(clamp(i32(i + k), 0, last));
            acc += weight(k) * (maxima[offset + lo] * input_scale.x * input_scale.y)
                + weight(k) * (maxima[offset + hi] * input_scale.x * input_scale.y);
        }
        scratch[offset + i] = acc;
        local_max = max(local_max, acc);
    }
    atomicMax(&blurred_max, bitcast<u32>(local_max));
    workgroupBarrier();

    // Normalize, temporal smoothing, floor.
    let max_bits = atomicLoad(&blurred_max);
    let fallback = max_bits == 0u || max_bits >= 0x7f800000u;
    let peak = bitcast<f32>(max_bits);
    let alpha = select(0.0, params.knobs.y, state[axis] != 0u);
    let floor_density = params.knobs.x;
    var d_min = 0xffffffffu;
    var d_max = 0u;
    for (var i = lid; i < n; i += GROUP) {
        let current = select(scratch[offset + i] / peak, 1.0, fallback);
        // The history is read only when there is one: a fresh or reset buffer may
        // hold anything (0 * NaN is NaN).
        var mixed = current;
        if alpha > 0.0 {
            mixed = alpha * density[offset + i] + (1.0 - alpha) * current;
        }
        let d = min(max(mixed, floor_density), 1.0);
        density[offset + i] = d;
        d_min = min(d_min, bitcast<u32>(d));
        d_max = max(d_max, bitcast<u32>(d));
    }
    atomicMin(&density_min, d_min);
    atomicMax(&density_max, d_max);
    storageBarrier();
    workgroupBarrier();
    if lid == 0u {
        let flat = atomicLoad(&density_min) >= atomicLoad(&density_max);
        constant_density = select(0u, 1u, flat || n < 2u);
        state[axis] = 1u;
        state[2u + axis] = select(0u, 1u, fallback);
    }
    if workgroupUniformLoad(&constant_density) != 0u {
        for (var i = lid; i < n; i += GROUP) {
            tables[offset + i] = 0.0;
        }
        return;
    }

    // Trapezoid terms e_j = (d_j + d_{j+1}) / 2, j < n - 1: chunk sums, then a scan.
    let terms = n - 1u;
    let chunk = (terms + GROUP - 1u) / GROUP;
    let begin = min(lid * chunk, terms);
    let end = min(begin + chunk, terms);
    var chunk_sum = 0.0;
    for (var j = begin; j < end; j++) {
        chunk_sum += 0.5 * (density[offset + j] + density[offset + j + 1u]);
    }
    scan[lid] = chunk_sum;
    workgroupBarrier();
    for (var step = 1u; step < GROUP; step <<= 1u) {
        var v = scan[lid];
        if lid >= step {
            v += scan[lid - step];
        }
        workgroupBarrier();
        scan[lid] = v;
        workgroupBarrier();
    }
    let total = scan[GROUP - 1u];
    var cumulative = 0.0;
    if lid > 0u {
        cumulative = scan[lid - 1u];
    }

    let nf = f32(n);
    let scale = ((nf - 1.0) / nf) / total;
    let c0 = 0.5 / nf;
    if lid == 0u {
        tables[offset] = 0.0;
        tables[offset + n - 1u] = 0.0;
    }
    // T_{j+1} needs the terms up to j; the last term only enters the total.
    for (var j = begin; j < end; j++) {
        cumulative += 0.5 * (density[offset + j] + density[offset + j + 1u]);
        if j + 2u < n {
            let c = (f32(j + 1u) + 0.5) / nf;
            tables[offset + j + 1u] = c0 + cumulative * scale - c;
        }
    }
}
