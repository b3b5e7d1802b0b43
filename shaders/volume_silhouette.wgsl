// techniques: any
// Silhouette edges of a closed mesh for one light, one invocation per edge: an edge
// is on the silhouette when exactly one of its two triangles faces the light, and
// is written oriented as that triangle runs along it (the CPU reference is
// shadowmap_volume::ShadowVolume::update).

struct Light {
    // xyz: the position (w = 1, point and spot lights) or the unit direction the
    // light travels (w = 0, directional).
    source: vec4<f32>,
    // x: number of edges.
    counts: vec4<u32>,
};

@group(0) @binding(0) var<uniform> light: Light;
@group(0) @binding(1) var<storage, read> positions: array<vec4<f32>>;
// Triangles as vertex indices (xyz).
@group(0) @binding(2) var<storage, read> triangles: array<vec4<u32>>;
// Edges: vertices (x, y) as triangle z runs along them, triangles (z, w).
@group(0) @binding(3) var<storage, read> edges: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read_write> found: atomic<u32>;
@group(0) @binding(5) var<storage, read_write> silhouette: array<vec2<u32>>;

fn faces_light(t: u32) -> bool {
    let tri = triangles[t];
    let a = positions[tri.x].xyz;
    let n = cross(positions[tri.y].xyz - a, positions[tri.z].xyz - a);
    let toward = select(-light.source.xyz, light.source.xyz - a, light.source.w > 0.5);
    return dot(n, toward) > 0.0;
}

@compute @workgroup_size(64)
fn find_silhouette(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= light.counts.x {
        return;
    }
    let e = edges[id.x];
    let first = faces_light(e.z);
    if first == faces_light(e.w) {
        return;
    }
    let slot = atomicAdd(&found, 1u);
    silhouette[slot] = select(e.yx, e.xy, first);
}
