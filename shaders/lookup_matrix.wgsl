// techniques: uniform, lispsm, xpsm, tsm
// Shadow lookup of a matrix technique: `uv_from_world`, divide by w. XPSM's warped
// Z bias (step 18) moves clip z by the world bias times `z_bias_scale` before the
// division; the other techniques have `z_bias_scale = 0` and are biased in depth
// units by the caller.
//
// Interface (shared by every lookup_*.wgsl, composed into render_scene.wgsl):
//   shadow_lookup(world, view_depth, world_bias, second) -> (u, v, depth, layer),
//     layer < 0 where the technique does not cover the point;
//   shadow_blend_weight(world, view_depth) -> weight of the `second` lookup.

struct MatrixShadow {
    clip_from_world: mat4x4<f32>,
    uv_from_world: mat4x4<f32>,
    // x: reversed-Z, y: XPSM z-bias scale.
    params: vec4<f32>,
}

@group(1) @binding(0) var<uniform> shadow: MatrixShadow;

fn shadow_lookup(world: vec3<f32>, view_depth: f32, world_bias: f32, second: bool) -> vec4<f32> {
    let h = shadow.uv_from_world * vec4<f32>(world, 1.0);
    if !(h.w > 0.0) {
        return vec4<f32>(0.0, 0.0, 0.0, -1.0);
    }
    let dz = world_bias * shadow.params.y;
    let z = select(h.z - dz, h.z + dz, shadow.params.x > 0.5);
    return vec4<f32>(h.xy / h.w, z / h.w, 0.0);
}

fn shadow_blend_weight(world: vec3<f32>, view_depth: f32) -> f32 {
    return 0.0;
}
