// techniques: rtw
// Caster refinement of RTW's depth pass on the GPU: the twin of
// `shadowmap_rtw::subdivide_for_rtw` (Rosen, "Rectilinear Texture Warping for Fast
// Adaptive Shadow Mapping", I3D 2012: the warp is piecewise linear between table
// texel centres, and only vertices are warped, so long caster edges are halved until
// their straight warped images follow the warp). Same rule, same recursion, same
// pieces: an edge is halved when it spans more than `1 / pieces` of base texture
// space or its warped midpoint lies more than `1 / error_scale` from the midpoint of
// its straight warped image; a triangle with one edge halved becomes 2, two edges 3
// (the quad cut along its shorter diagonal), three edges 4, each refined again, down
// to `levels` halvings. The decision on an edge depends on its two endpoints alone
// and is symmetric in them, so two casters sharing an edge halve it identically:
// a conforming mesh stays conforming (no T-junctions, no cracks).
//
// Three entry points, one invocation per caster, over one bind group:
// - `count`: refines to `levels` and counts the pieces the caster would give at every
//   cap `c` in `0..=levels` (a piece that would be halved at depth `d` is one piece
//   at cap `d`); adds them to 64-bit totals per cap and keeps them per caster.
// - `choose` (one invocation): the finest cap whose total fits the capacity (cap 0,
//   the casters themselves, always fits); writes the indirect draw and the stats.
//   One cap for every caster keeps shared edges alike: a mesh that would overflow is
//   refined more coarsely everywhere, never truncated.
// - `emit`: refines again to the chosen cap, reserves its pieces with one atomic add
//   on the append cursor (the output order is unspecified; depth testing does not
//   care), and writes them as a triangle soup of `vec3<f32>` (9 floats a triangle).

struct RefineParams {
    uv_from_world: mat4x4<f32>,
    // x, y: pieces per unit of base u and v; z: error scale; w: unused.
    rule: vec4<f32>,
    // x: u-table texels, y: v-table texels, z: halvings (`levels`), w: casters.
    sizes: vec4<u32>,
    // x: capacity in triangles; y, z, w: unused.
    limits: vec4<u32>,
}

// Deepest refinement (`max_segments` 1024) and the stack depth it needs (a node
// pushes up to four children).
const MAX_LEVELS: u32 = 10u;
const STACK: u32 = 32u;
const CAPS: u32 = 11u;
// Words of `state`: lo/hi totals per cap, then these.
const APPEND: u32 = 22u;
const CHOSEN: u32 = 23u;
const DRAWN: u32 = 24u;
const OVERFLOW: u32 = 25u;

@group(0) @binding(0) var<uniform> params: RefineParams;
// The u table, then the v table.
@group(0) @binding(1) var<storage, read> rtw_tables: array<f32>;
// The casters: 9 floats per triangle.
@group(0) @binding(2) var<storage, read> casters: array<f32>;
@group(0) @binding(3) var<storage, read_write> state: array<atomic<u32>, 32>;
// Pieces per caster at every cap (CAPS words per caster).
@group(0) @binding(4) var<storage, read_write> piece_counts: array<u32>;
@group(0) @binding(5) var<storage, read_write> refined: array<f32>;
// vertex_count, instance_count, first_vertex, first_instance.
@group(0) @binding(6) var<storage, read_write> draw: array<u32, 4>;

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

struct Tri {
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
    depth: u32,
}

struct Mapped {
    uv: vec2<f32>,
    ok: bool,
}

fn base_uv(p: vec3<f32>) -> Mapped {
    let h = params.uv_from_world * vec4<f32>(p, 1.0);
    let uv = h.xy / h.w;
    let finite = all(abs(uv) < vec2<f32>(3.0e38));
    return Mapped(uv, h.w > 0.0 && finite);
}

fn warp(uv: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(
        uv.x + rtw_sample(0u, params.sizes.x, uv.x),
        uv.y + rtw_sample(params.sizes.x, params.sizes.y, uv.y),
    );
}

// Whether edge `a b` is halved (symmetric in `a, b`).
fn halves(a: vec3<f32>, b: vec3<f32>) -> bool {
    let ua = base_uv(a);
    let ub = base_uv(b);
    let mid = base_uv((a + b) * 0.5);
    if !(ua.ok && ub.ok) {
        return false;
    }
    let span = abs(ub.uv - ua.uv) * params.rule.xy;
    if max(span.x, span.y) > 1.0 {
        return true;
    }
    if !mid.ok {
        return false;
    }
    let chord = (warp(ua.uv) + warp(ub.uv)) * 0.5;
    let error = abs(warp(mid.uv) - chord);
    return max(error.x, error.y) * params.rule.z > 1.0;
}

fn caster(i: u32) -> Tri {
    var v: array<vec3<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        let o = 9u * i + 3u * k;
        v[k] = vec3<f32>(casters[o], casters[o + 1u], casters[o + 2u]);
    }
    return Tri(v[0], v[1], v[2], 0u);
}

fn refinable(t: Tri) -> bool {
    let finite = all(abs(t.a) < vec3<f32>(3.0e38)) && all(abs(t.b) < vec3<f32>(3.0e38))
        && all(abs(t.c) < vec3<f32>(3.0e38));
    return finite && base_uv(t.a).ok && base_uv(t.b).ok && base_uv(t.c).ok;
}

// The pieces of one refinement step of `t`, rotated so the halved edges come first
// (the winding is kept), as in `RtwSplitter::split`; `count` 1 when nothing halves.
struct Step {
    pieces: array<Tri, 4>,
    count: u32,
}

fn refine_step(t: Tri) -> Step {
    let d = t.depth + 1u;
    let h = vec3<bool>(halves(t.a, t.b), halves(t.b, t.c), halves(t.c, t.a));
    var s: Step;
    let n = u32(h.x) + u32(h.y) + u32(h.z);
    if n == 0u {
        s.pieces[0] = t;
        s.count = 1u;
        return s;
    }
    if n == 3u {
        let ab = (t.a + t.b) * 0.5;
        let bc = (t.b + t.c) * 0.5;
        let ca = (t.c + t.a) * 0.5;
        s.pieces[0] = Tri(t.a, ab, ca, d);
        s.pieces[1] = Tri(ab, t.b, bc, d);
        s.pieces[2] = Tri(ca, bc, t.c, d);
        s.pieces[3] = Tri(ab, bc, ca, d);
        s.count = 4u;
        return s;
    }
    // Rotate: for one halved edge, it becomes `a b`; for two, `a b` and `b c`.
    var r = t;
    if (n == 1u && h.y) || (n == 2u && h.y && h.z) {
        r = Tri(t.b, t.c, t.a, t.depth);
    } else if (n == 1u && h.z) || (n == 2u && h.z && h.x) {
        r = Tri(t.c, t.a, t.b, t.depth);
    }
    let m = (r.a + r.b) * 0.5;
    if n == 1u {
        s.pieces[0] = Tri(r.a, m, r.c, d);
        s.pieces[1] = Tri(m, r.b, r.c, d);
        s.count = 2u;
        return s;
    }
    let k = (r.b + r.c) * 0.5;
    s.pieces[0] = Tri(m, r.b, k, d);
    let an = r.a - k;
    let mc = m - r.c;
    if dot(an, an) <= dot(mc, mc) {
        s.pieces[1] = Tri(r.a, m, k, d);
        s.pieces[2] = Tri(r.a, k, r.c, d);
    } else {
        s.pieces[1] = Tri(r.a, m, r.c, d);
        s.pieces[2] = Tri(m, k, r.c, d);
    }
    s.count = 3u;
    return s;
}

// Adds `n` to the 64-bit total of cap `c` (lo word, carry into the hi word).
fn add_total(c: u32, n: u32) {
    if n == 0u {
        return;
    }
    let old = atomicAdd(&state[2u * c], n);
    if old > 0xffffffffu - n {
        atomicAdd(&state[2u * c + 1u], 1u);
    }
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.sizes.w {
        return;
    }
    let levels = min(params.sizes.z, MAX_LEVELS);
    var counts: array<u32, CAPS>;
    let root = caster(i);
    var stack: array<Tri, STACK>;
    var top = 0u;
    if refinable(root) {
        stack[0] = root;
        top = 1u;
    } else {
        for (var c = 0u; c <= levels; c++) {
            counts[c] = 1u;
        }
    }
    while top > 0u {
        top -= 1u;
        let t = stack[top];
        var s: Step;
        if t.depth < levels {
            s = refine_step(t);
        } else {
            s.count = 1u;
        }
        if s.count == 1u {
            // A leaf at every cap from its depth on.
            for (var c = t.depth; c <= levels; c++) {
                counts[c] += 1u;
            }
            continue;
        }
        counts[t.depth] += 1u;
        for (var k = 0u; k < s.count; k++) {
            stack[top] = s.pieces[k];
            top += 1u;
        }
    }
    for (var c = 0u; c <= levels; c++) {
        piece_counts[CAPS * i + c] = counts[c];
        add_total(c, counts[c]);
    }
}

@compute @workgroup_size(1)
fn choose() {
    let levels = min(params.sizes.z, MAX_LEVELS);
    var chosen = 0u;
    for (var c = levels; c > 0u; c--) {
        let lo = atomicLoad(&state[2u * c]);
        let hi = atomicLoad(&state[2u * c + 1u]);
        if hi == 0u && lo <= params.limits.x {
            chosen = c;
            break;
        }
    }
    let drawn = atomicLoad(&state[2u * chosen]);
    atomicStore(&state[CHOSEN], chosen);
    atomicStore(&state[DRAWN], drawn);
    atomicStore(&state[OVERFLOW], u32(chosen < levels));
    atomicStore(&state[APPEND], 0u);
    draw[0] = 3u * drawn;
    draw[1] = 1u;
    draw[2] = 0u;
    draw[3] = 0u;
}

fn write_piece(slot: u32, t: Tri) {
    if slot >= params.limits.x {
        return;
    }
    let o = 9u * slot;
    var v = array<vec3<f32>, 3>(t.a, t.b, t.c);
    for (var k = 0u; k < 3u; k++) {
        refined[o + 3u * k] = v[k].x;
        refined[o + 3u * k + 1u] = v[k].y;
        refined[o + 3u * k + 2u] = v[k].z;
    }
}

@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= params.sizes.w {
        return;
    }
    let cap = atomicLoad(&state[CHOSEN]);
    var slot = atomicAdd(&state[APPEND], piece_counts[CAPS * i + cap]);
    let root = caster(i);
    if !refinable(root) {
        write_piece(slot, root);
        return;
    }
    var stack: array<Tri, STACK>;
    stack[0] = root;
    var top = 1u;
    while top > 0u {
        top -= 1u;
        let t = stack[top];
        var s: Step;
        if t.depth < cap {
            s = refine_step(t);
        } else {
            s.count = 1u;
        }
        if s.count == 1u {
            write_piece(slot, t);
            slot += 1u;
            continue;
        }
        for (var k = 0u; k < s.count; k++) {
            stack[top] = s.pieces[k];
            top += 1u;
        }
    }
}
