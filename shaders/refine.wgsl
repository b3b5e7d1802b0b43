// techniques: rtw, paraboloid
// Caster refinement on the GPU: the per-frame caster subdivision of the depth passes
// that project vertices non-linearly, as a compute pass that writes indirect draws.
// Two rules, each the twin of its CPU reference, evaluated in f32:
//
// - RTW (`shadowmap_rtw::subdivide_for_rtw_with`; Rosen, "Rectilinear Texture Warping
//   for Fast Adaptive Shadow Mapping", I3D 2012: the warp is piecewise linear between
//   table texel centres and only vertices are warped, so long edges are halved until
//   their straight warped images follow the warp). An edge is halved when it spans
//   more than `1 / pieces` of base texture space or its warped midpoint lies more
//   than `1 / error_scale` from the midpoint of its straight warped image; a
//   triangle with one edge halved becomes 2, two edges 3 (the quad cut along its
//   shorter diagonal), three edges 4, each refined again, down to `levels` halvings.
//   The decision on an edge depends on its two endpoints alone and is symmetric in
//   them, so a conforming mesh stays conforming (no T-junctions, no cracks).
//   Over a paraboloid side, casters are first cut at the side's plane, over a cube
//   face at the five planes of its window's frustum (near plane first, then the
//   sides; `subdivide_for_rtw_clipped`: the parts behind are left out). Pieces with
//   a vertex the base cannot map are dropped, as on the CPU.
// - Paraboloid grid (`shadowmap_paraboloid::subdivide_triangle`; Brabec et al., the
//   image of an edge on a paraboloid is curved): each edge gets the fewest equal
//   segments whose chords stay within `tolerance` texels of the curve (measured at
//   the DEVIATION_SAMPLES of every segment, refined by the 1/n^2 law), and the
//   triangle becomes the n^2 pieces of the barycentric grid, n the largest of its
//   three edges.
//
// The base is a matrix per layer (`uv_from_world`, orthographic or perspective: one
// map, or the kept faces of a cube map) or one side of a paraboloid map (the side is
// the layer). The RTW rule reads each layer's tables.
//
// Three entry points over one bind group, `count` and `emit` with one invocation per
// (caster, layer):
// - `count`: the pieces the caster would give at every cap `c` in `0..=levels` (RTW:
//   halvings up to c, a piece that would be halved at depth d is one piece at cap d;
//   grid: at most 2^c segments per edge, min(n, 2^c)^2 pieces); adds them to 64-bit
//   totals per layer and cap and keeps them per caster.
// - `choose` (one invocation): the finest cap whose total over the layers fits the
//   capacity (cap 0, the casters themselves, always fits); writes each layer's
//   indirect draw (its pieces follow the previous layer's) and the stats. One cap
//   for every caster keeps shared edges alike: a mesh that would overflow is refined
//   more coarsely everywhere, never truncated.
// - `emit`: refines again to the chosen cap, reserves its pieces with one atomic add
//   on its layer's append cursor (the order within a layer is unspecified; depth
//   testing keeps the minimum either way), and writes them as a triangle soup of
//   `vec3<f32>` (9 floats a triangle).
//
// Every RTW node visited is one iteration of one loop with no loop inside it (the
// counts per cap are summed after the walk, a node's pieces are pushed without a
// loop): llvmpipe ends a loop after 65535 iterations counted together with those of
// the loops nested in it, and its invocation then writes nothing, so a caster
// refined into more nodes than that is lost there (real GPUs have no such bound).
// Measured: with the pieces pushed by a loop, walls of the city block refined into
// 15,000 pieces over a cube face (about 40,000 iterations) were dropped.
//
// No workgroup memory and no subgroup operations: every invocation works alone and
// meets the others only through atomics on integers, so the result depends on no
// subgroup size or reduction order.

struct Paraboloid {
    rotation: mat4x4<f32>,
    position_near: vec4<f32>,
    // far, zoom, reversed-Z (0/1), dual (0/1)
    far_zoom_reversed_dual: vec4<f32>,
}

struct RefineLayer {
    // The layer's base in the matrix mode.
    uv_from_world: mat4x4<f32>,
    // The layer's tables in `rtw_tables`: u offset, u texels, v offset, v texels.
    tables: vec4<u32>,
    // RTW rule: pieces per unit of base u and v, error scale; w: the paraboloid side
    // (0 front, 1 back), or in the window mode the near plane's `w` of the base.
    rule: vec4<f32>,
}

struct RefineParams {
    // The base of the paraboloid mode (side = layer).
    paraboloid: Paraboloid,
    // Grid rule: texels per side, tolerance in texels, most segments per edge; w: unused.
    grid: vec4<f32>,
    // x: mode (bit 0: paraboloid base, bit 1: grid rule, bit 2: casters cut to each
    // layer's window), y: levels, z: casters, w: layers.
    sizes: vec4<u32>,
    // x: capacity in triangles; y, z, w: unused.
    limits: vec4<u32>,
    layers: array<RefineLayer, 6>,
}

// Deepest refinement (RTW: `max_segments` 1024; grid: 2^8 = 256 segments) and the
// stack depth the RTW recursion needs (the fan of a clipped caster, at most
// MAX_POLYGON - 2 pieces, then each level pops one node and pushes up to four:
// 6 + 3 * MAX_LEVELS).
const MAX_LEVELS: u32 = 10u;
const STACK: u32 = 36u;
const CAPS: u32 = 11u;
const MAX_LAYERS: u32 = 6u;
// Words of `state`: lo/hi totals per layer and cap (2 * MAX_LAYERS * CAPS), then these.
const APPEND: u32 = 132u;
const CHOSEN: u32 = 138u;
const DRAWN: u32 = 139u;
const OVERFLOW: u32 = 145u;
const MODE_PARABOLOID: u32 = 1u;
const MODE_GRID: u32 = 2u;
const MODE_WINDOW: u32 = 4u;
// Most vertices of a caster clipped by the planes (each adds at most one).
const MAX_POLYGON: u32 = 8u;
// Where the grid rule measures a segment's deviation from its chord
// (`shadowmap_paraboloid::DEVIATION_SAMPLES`).
const DEVIATION_SAMPLES = array<f32, 3>(0.25, 0.5, 0.75);

@group(0) @binding(0) var<uniform> params: RefineParams;
// The tables of every layer.
@group(0) @binding(1) var<storage, read> rtw_tables: array<f32>;
// The casters: 9 floats per triangle.
@group(0) @binding(2) var<storage, read> casters: array<f32>;
@group(0) @binding(3) var<storage, read_write> state: array<atomic<u32>, 146>;
// Pieces per (layer, caster) at every cap (CAPS words each).
@group(0) @binding(4) var<storage, read_write> piece_counts: array<u32>;
@group(0) @binding(5) var<storage, read_write> refined: array<f32>;
// Per layer: vertex_count, instance_count, first_vertex, first_instance.
@group(0) @binding(6) var<storage, read_write> draw: array<u32, 24>;

// @compose rtw_sample begin
// Placeholder: the sampler of rtw_sample.wgsl is composed in here.
fn rtw_sample(offset: u32, n: u32, u: f32) -> f32 {
    return 0.0;
}
// @compose rtw_sample end

// @compose paraboloid_side begin
// Placeholder: the projection of paraboloid_side.wgsl is composed in here.
fn paraboloid_side(q: vec3<f32>, back: bool) -> vec4<f32> {
    return vec4<f32>(0.0, 0.0, 1.0, 1.0);
}
// @compose paraboloid_side end

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

fn finite2(v: vec2<f32>) -> bool {
    return all(abs(v) < vec2<f32>(3.0e38));
}

fn finite3(v: vec3<f32>) -> bool {
    return all(abs(v) < vec3<f32>(3.0e38));
}

fn light_point(p: vec3<f32>) -> vec3<f32> {
    let m = params.paraboloid;
    return (m.rotation * vec4<f32>(p - m.position_near.xyz, 0.0)).xyz;
}

// `ParaboloidMap::project(p, side).uv` of a light-space point; not ok at the light,
// straight behind the side's axis, or where it overflows.
fn paraboloid_uv(q: vec3<f32>, layer: u32) -> Mapped {
    let p = paraboloid_side(q, params.layers[layer].rule.w > 0.5);
    let ndc = p.xy / p.z / params.paraboloid.far_zoom_reversed_dual.y;
    let uv = vec2<f32>(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    return Mapped(uv, length(q) > 0.0 && p.z > 0.0 && finite2(uv));
}

// The base's texture coordinates of a world point.
fn base_uv(p: vec3<f32>, layer: u32) -> Mapped {
    if (params.sizes.x & MODE_PARABOLOID) != 0u {
        return paraboloid_uv(light_point(p), layer);
    }
    let h = params.layers[layer].uv_from_world * vec4<f32>(p, 1.0);
    let uv = h.xy / h.w;
    return Mapped(uv, h.w > 0.0 && finite2(uv));
}

fn warp(uv: vec2<f32>, layer: u32) -> vec2<f32> {
    let t = params.layers[layer].tables;
    return vec2<f32>(uv.x + rtw_sample(t.x, t.y, uv.x), uv.y + rtw_sample(t.z, t.w, uv.y));
}

// RTW: whether edge `a b` is halved (symmetric in `a, b`).
fn halves(a: vec3<f32>, b: vec3<f32>, layer: u32) -> bool {
    let ua = base_uv(a, layer);
    let ub = base_uv(b, layer);
    let mid = base_uv((a + b) * 0.5, layer);
    if !(ua.ok && ub.ok) {
        return false;
    }
    let rule = params.layers[layer].rule;
    let span = abs(ub.uv - ua.uv) * rule.xy;
    if max(span.x, span.y) > 1.0 {
        return true;
    }
    if !mid.ok {
        return false;
    }
    let chord = (warp(ua.uv, layer) + warp(ub.uv, layer)) * 0.5;
    let error = abs(warp(mid.uv, layer) - chord);
    return max(error.x, error.y) * rule.z > 1.0;
}

fn caster(i: u32) -> Tri {
    var v: array<vec3<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        let o = 9u * i + 3u * k;
        v[k] = vec3<f32>(casters[o], casters[o + 1u], casters[o + 2u]);
    }
    return Tri(v[0], v[1], v[2], 0u);
}

// RTW: whether the base maps every vertex (else the caster is dropped).
fn mappable(t: Tri, layer: u32) -> bool {
    let finite = finite3(t.a) && finite3(t.b) && finite3(t.c);
    return finite && base_uv(t.a, layer).ok && base_uv(t.b, layer).ok && base_uv(t.c, layer).ok;
}

// RTW: the part of a caster in front of the planes that bound the layer's base, as
// `subdivide_for_rtw_clipped` clips it: a paraboloid side's plane
// (`ParaboloidMap::plane_distance`), or a window's five (`w - near`, then the sides
// `u w >= 0`, `u w <= w`, `v w <= w`, `v w >= 0`, in the CPU's order of its clip
// planes `w + x`, `w - x`, `w + y`, `w - y`); a matrix base without a window is not
// clipped. The result is a convex polygon (Sutherland-Hodgman, each crossing
// interpolated from its edge's end in front) whose pieces are its fan from its first
// vertex. A caster with a non-finite vertex gives nothing.
struct Polygon {
    v: array<vec3<f32>, MAX_POLYGON>,
    n: u32,
}

fn plane_count() -> u32 {
    if (params.sizes.x & MODE_PARABOLOID) != 0u {
        return 1u;
    }
    return select(0u, 5u, (params.sizes.x & MODE_WINDOW) != 0u);
}

fn plane_distance(p: vec3<f32>, layer: u32, plane: u32) -> f32 {
    let rule = params.layers[layer].rule;
    if (params.sizes.x & MODE_PARABOLOID) != 0u {
        let z = light_point(p).z;
        return select(-z, z, rule.w > 0.5);
    }
    let h = params.layers[layer].uv_from_world * vec4<f32>(p, 1.0);
    switch plane {
        case 0u: {
            return h.w - rule.w;
        }
        case 1u: {
            return h.x;
        }
        case 2u: {
            return h.w - h.x;
        }
        case 3u: {
            return h.w - h.y;
        }
        default: {
            return h.y;
        }
    }
}

// The point where edge `a b` crosses the plane, interpolated from `a` (in front).
fn crossing(a: vec3<f32>, b: vec3<f32>, da: f32, db: f32) -> vec3<f32> {
    return a + (b - a) * (da / (da - db));
}

// One Sutherland-Hodgman step: the part of `poly` in front of one plane, walking its
// edges in order and keeping the vertices in front and the crossings.
fn clip_polygon(poly: Polygon, layer: u32, plane: u32) -> Polygon {
    var d: array<f32, MAX_POLYGON>;
    for (var i = 0u; i < poly.n; i++) {
        d[i] = plane_distance(poly.v[i], layer, plane);
    }
    var out: Polygon;
    out.n = 0u;
    for (var i = 0u; i < poly.n; i++) {
        let j = select(i + 1u, 0u, i + 1u == poly.n);
        let front_i = d[i] >= 0.0;
        let front_j = d[j] >= 0.0;
        if front_i && out.n < MAX_POLYGON {
            out.v[out.n] = poly.v[i];
            out.n += 1u;
        }
        if front_i != front_j && out.n < MAX_POLYGON {
            if front_i {
                out.v[out.n] = crossing(poly.v[i], poly.v[j], d[i], d[j]);
            } else {
                out.v[out.n] = crossing(poly.v[j], poly.v[i], d[j], d[i]);
            }
            out.n += 1u;
        }
    }
    return out;
}

fn clip_to_base(t: Tri, layer: u32) -> Polygon {
    var poly: Polygon;
    poly.n = 0u;
    if !(finite3(t.a) && finite3(t.b) && finite3(t.c)) {
        return poly;
    }
    poly.v[0] = t.a;
    poly.v[1] = t.b;
    poly.v[2] = t.c;
    poly.n = 3u;
    let planes = plane_count();
    for (var plane = 0u; plane < planes; plane++) {
        poly = clip_polygon(poly, layer, plane);
    }
    return poly;
}

// The pieces of one RTW step of `t`, rotated so the halved edges come first (the
// winding is kept), as in `RtwSplitter::split`; `count` 1 when nothing halves.
struct Step {
    pieces: array<Tri, 4>,
    count: u32,
}

fn refine_step(t: Tri, layer: u32) -> Step {
    let d = t.depth + 1u;
    let h = vec3<bool>(halves(t.a, t.b, layer), halves(t.b, t.c, layer), halves(t.c, t.a, layer));
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

// Grid: the texel-space image of a light-space point on the layer's side.
fn texel(q: vec3<f32>, layer: u32) -> Mapped {
    let m = paraboloid_uv(q, layer);
    return Mapped(m.uv * params.grid.x, m.ok);
}

fn segment_distance(p: vec2<f32>, a: vec2<f32>, b: vec2<f32>) -> f32 {
    let ab = b - a;
    let len2 = dot(ab, ab);
    var t = 0.0;
    if len2 > 0.0 {
        t = clamp(dot(p - a, ab) / len2, 0.0, 1.0);
    }
    return distance(p, a + ab * t);
}

// Grid: the largest deviation (texels) of `n` equal segments of light-space edge
// `qa qb` from its image curve; negative where the curve is undefined.
fn deviation(qa: vec3<f32>, qb: vec3<f32>, n: u32, layer: u32) -> f32 {
    let step = 1.0 / f32(n);
    var prev = texel(qa, layer);
    if !prev.ok {
        return -1.0;
    }
    var worst = 0.0;
    var samples = DEVIATION_SAMPLES;
    for (var k = 0u; k < n; k++) {
        let t0 = f32(k) * step;
        let next = texel(qa + (qb - qa) * (t0 + step), layer);
        if !next.ok {
            return -1.0;
        }
        for (var j = 0u; j < 3u; j++) {
            let m = texel(qa + (qb - qa) * (t0 + samples[j] * step), layer);
            if !m.ok {
                return -1.0;
            }
            worst = max(worst, segment_distance(m.uv, prev.uv, next.uv));
        }
        prev = next;
    }
    if !(worst < 3.0e38) {
        return -1.0;
    }
    return worst;
}

// Grid: the equal segments light-space edge `qa qb` needs (`edge_subdivisions`).
fn edge_segments(qa: vec3<f32>, qb: vec3<f32>, layer: u32) -> u32 {
    let tolerance = params.grid.y;
    let most = u32(params.grid.z);
    var n = 1u;
    loop {
        let dev = deviation(qa, qb, n, layer);
        if dev < 0.0 {
            return most;
        }
        if dev <= tolerance || n >= most {
            return min(n, most);
        }
        // The deviation of a smooth curve falls as 1/n^2.
        let guess = f32(n) * sqrt(dev / tolerance);
        var capped = f32(most);
        if guess < capped {
            capped = guess;
        }
        n = min(max(u32(capped), n + 1u), most);
    }
    return most;
}

// Grid: the segments per edge of caster `t` (the largest of its edges; 1 for a
// caster with a non-finite vertex).
fn grid_segments(t: Tri, layer: u32) -> u32 {
    if !(finite3(t.a) && finite3(t.b) && finite3(t.c)) {
        return 1u;
    }
    let qa = light_point(t.a);
    let qb = light_point(t.b);
    let qc = light_point(t.c);
    return max(edge_segments(qa, qb, layer), max(edge_segments(qb, qc, layer), edge_segments(qc, qa, layer)));
}

// Adds `n` to the 64-bit total of (layer, cap) (lo word, carry into the hi word).
fn add_total(layer: u32, c: u32, n: u32) {
    if n == 0u {
        return;
    }
    let word = 2u * (layer * CAPS + c);
    let old = atomicAdd(&state[word], n);
    if old > 0xffffffffu - n {
        atomicAdd(&state[word + 1u], 1u);
    }
}

fn levels() -> u32 {
    return min(params.sizes.y, MAX_LEVELS);
}

// Marks a walk that counts instead of writing.
const COUNT_ONLY: u32 = 0xffffffffu;

// RTW: walks the refinement of the mappable pieces of `poly` (its fan) down to
// `limit` halvings. With `first` = COUNT_ONLY it counts the pieces at every cap up to
// `limit` (a piece that would be halved at depth d is one piece at cap d, a leaf one
// piece at every cap from its depth on); otherwise it writes the leaves from slot
// `first` on. Every piece of the fan starts on the stack, so one walk serves them.
fn rtw_walk(poly: Polygon, layer: u32, limit: u32, first: u32) -> array<u32, CAPS> {
    // Counting: leaves and halved nodes per depth, summed into caps at the end, so
    // every node costs one iteration (software rasterizers bound a loop's iterations:
    // llvmpipe stops a loop after 65535).
    var leaves: array<u32, CAPS>;
    var halved: array<u32, CAPS>;
    var slot = first;
    var stack: array<Tri, STACK>;
    var top = 0u;
    for (var k = 1u; k + 1u < poly.n; k++) {
        let piece = Tri(poly.v[0], poly.v[k], poly.v[k + 1u], 0u);
        if mappable(piece, layer) {
            stack[top] = piece;
            top += 1u;
        }
    }
    while top > 0u {
        top -= 1u;
        let t = stack[top];
        var s: Step;
        if t.depth < limit {
            s = refine_step(t, layer);
        } else {
            s.count = 1u;
        }
        if s.count == 1u {
            if first == COUNT_ONLY {
                leaves[t.depth] += 1u;
            } else {
                write_piece(slot, t);
                slot += 1u;
            }
            continue;
        }
        if first == COUNT_ONLY {
            halved[t.depth] += 1u;
        }
        // Pushed without an inner loop: llvmpipe's loop bound counts the
        // iterations of nested loops together with the walk's own.
        stack[top] = s.pieces[0];
        stack[top + 1u] = s.pieces[1];
        if s.count > 2u {
            stack[top + 2u] = s.pieces[2];
        }
        if s.count > 3u {
            stack[top + 3u] = s.pieces[3];
        }
        top += s.count;
    }
    var counts: array<u32, CAPS>;
    var below = 0u;
    for (var c = 0u; c <= limit; c++) {
        below += leaves[c];
        counts[c] = below + halved[c];
    }
    return counts;
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let layer = id.y;
    if i >= params.sizes.z || layer >= min(params.sizes.w, MAX_LAYERS) {
        return;
    }
    let top_level = levels();
    let root = caster(i);
    var counts: array<u32, CAPS>;
    if (params.sizes.x & MODE_GRID) != 0u {
        let n = grid_segments(root, layer);
        for (var c = 0u; c <= top_level; c++) {
            let m = min(n, 1u << c);
            counts[c] = m * m;
        }
    } else {
        counts = rtw_walk(clip_to_base(root, layer), layer, top_level, COUNT_ONLY);
    }
    let at = CAPS * (layer * params.sizes.z + i);
    for (var c = 0u; c <= top_level; c++) {
        piece_counts[at + c] = counts[c];
        add_total(layer, c, counts[c]);
    }
}

@compute @workgroup_size(1)
fn choose() {
    let top_level = levels();
    let layers = min(params.sizes.w, MAX_LAYERS);
    var chosen = 0u;
    for (var c = top_level; c > 0u; c--) {
        // The sum over the layers, kept at most the capacity while it fits.
        var fits = true;
        var sum = 0u;
        for (var l = 0u; l < layers; l++) {
            let word = 2u * (l * CAPS + c);
            let lo = atomicLoad(&state[word]);
            let hi = atomicLoad(&state[word + 1u]);
            if hi != 0u || lo > params.limits.x - sum {
                fits = false;
                break;
            }
            sum += lo;
        }
        if fits {
            chosen = c;
            break;
        }
    }
    var first = 0u;
    for (var l = 0u; l < MAX_LAYERS; l++) {
        var drawn = 0u;
        if l < layers {
            drawn = atomicLoad(&state[2u * (l * CAPS + chosen)]);
        }
        atomicStore(&state[APPEND + l], first);
        atomicStore(&state[DRAWN + l], drawn);
        draw[4u * l] = 3u * drawn;
        draw[4u * l + 1u] = 1u;
        draw[4u * l + 2u] = 3u * first;
        draw[4u * l + 3u] = 0u;
        first += drawn;
    }
    atomicStore(&state[CHOSEN], chosen);
    atomicStore(&state[OVERFLOW], u32(chosen < top_level));
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

// Grid: the m^2 pieces of the barycentric grid of `t`, from `slot` on, in the order
// of `subdivide_triangle`.
fn emit_grid(t: Tri, m: u32, first: u32) {
    let e1 = (t.b - t.a) / f32(m);
    let e2 = (t.c - t.a) / f32(m);
    var slot = first;
    for (var j = 0u; j < m; j++) {
        for (var i = 0u; i < m - j; i++) {
            let p00 = t.a + e1 * f32(i) + e2 * f32(j);
            let p10 = t.a + e1 * f32(i + 1u) + e2 * f32(j);
            let p01 = t.a + e1 * f32(i) + e2 * f32(j + 1u);
            write_piece(slot, Tri(p00, p10, p01, 0u));
            slot += 1u;
            if i + j + 1u < m {
                let p11 = t.a + e1 * f32(i + 1u) + e2 * f32(j + 1u);
                write_piece(slot, Tri(p10, p11, p01, 0u));
                slot += 1u;
            }
        }
    }
}

@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let layer = id.y;
    if i >= params.sizes.z || layer >= min(params.sizes.w, MAX_LAYERS) {
        return;
    }
    let cap = atomicLoad(&state[CHOSEN]);
    let pieces = piece_counts[CAPS * (layer * params.sizes.z + i) + cap];
    if pieces == 0u {
        return;
    }
    let slot = atomicAdd(&state[APPEND + layer], pieces);
    let root = caster(i);
    if (params.sizes.x & MODE_GRID) != 0u {
        // pieces = m^2 with m <= 256: the square root is exact after rounding.
        emit_grid(root, u32(round(sqrt(f32(pieces)))), slot);
    } else {
        rtw_walk(clip_to_base(root, layer), layer, cap, slot);
    }
}
