// techniques: tiles
// Shadow lookup of a tiled cube map (`shadowmap_paraboloid::TiledCube`): the first
// kept face whose window holds the point (the windows are disjoint up to rounding,
// as `CubeMap::map_point` selects), the cell under the face's uv, the cell's tile
// from the table, the point's place in the tile (past its guard border) and the
// tile's square of the atlas. Mirrors `TiledCube::map_point` followed by
// `TiledCube::atlas_sample`. Same interface as lookup_matrix.wgsl; the layer is 0.

struct TiledShadow {
    // Each kept face's lookup matrix (texture space, divide by w), layer order.
    uv_from_world: array<mat4x4<f32>, 6>,
    // x: kept faces, y: cells per face side, z: where the cell table starts in
    // `tile_data`, w: 0.
    counts: vec4<u32>,
    // x: guard border in texels, y: the depth texture's side in texels, z, w: 0.
    params: vec4<f32>,
}

@group(1) @binding(0) var<uniform> shadow: TiledShadow;
// Per tile, 8 values: atlas offset x, y (texels, border included), interior side,
// span (cells per side), first cell column, row, 0, 0. Then per cell, face by face,
// rows top to bottom: its tile's index. Whole numbers below 2^24, exact in f32.
@group(1) @binding(1) var<storage, read> tile_data: array<f32>;

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let faces = min(shadow.counts.x, 6u);
    let grid = max(shadow.counts.y, 1u);
    for (var i = 0u; i < faces; i++) {
        let h = shadow.uv_from_world[i] * vec4<f32>(world, 1.0);
        if !(h.w > 0.0) {
            continue;
        }
        let s = h.xyz / h.w;
        if !(all(s.xy >= vec2<f32>(0.0)) && all(s.xy <= vec2<f32>(1.0))) {
            continue;
        }
        let g = f32(grid);
        let cell = min(vec2<u32>(max(floor(s.xy * g), vec2<f32>(0.0))), vec2<u32>(grid - 1u));
        let entry = shadow.counts.z + (i * grid + cell.y) * grid + cell.x;
        let tile = u32(tile_data[entry]) * 8u;
        let offset = vec2<f32>(tile_data[tile], tile_data[tile + 1u]);
        let side = tile_data[tile + 2u];
        let span = tile_data[tile + 3u];
        let first = vec2<f32>(tile_data[tile + 4u], tile_data[tile + 5u]);
        let within = (s.xy * g - first) / span;
        let texel = offset + shadow.params.x + within * side;
        return vec4<f32>(texel / shadow.params.y, s.z, 0.0);
    }
    return vec4<f32>(0.0, 0.0, 0.0, -1.0);
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
