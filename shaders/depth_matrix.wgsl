// techniques: uniform, cascades, lispsm, xpsm, tsm
// Depth pass of the matrix techniques: one `clip_from_world` per layer (a cascade is
// one layer of a 2-D array texture). Depth-only: no fragment stage.

struct MatrixShadow {
    clip_from_world: mat4x4<f32>,
    uv_from_world: mat4x4<f32>,
    // x: reversed-Z, y: XPSM z-bias scale.
    params: vec4<f32>,
}

@group(0) @binding(0) var<uniform> layer: MatrixShadow;

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return layer.clip_from_world * vec4<f32>(position, 1.0);
}
