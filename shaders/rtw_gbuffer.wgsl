// techniques: rtw
// The eye-space G-buffer of RTW's backward analysis, rendered from the camera: per
// pixel the world position and its distance from the eye, and the surface normal
// with the flag 1 (a sample); the clear colour (flag 0) marks the background. The
// normal is the flat face normal from the position's screen derivatives (its sign
// does not matter: the importance uses |n . l|). rtw_importance.wgsl reads it.

struct GBufferFrame {
    clip_from_world: mat4x4<f32>,
    // xyz: the eye, w: 1.
    eye: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: GBufferFrame;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
}

struct GBufferOut {
    @location(0) position_distance: vec4<f32>,
    @location(1) normal_flags: vec4<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.clip_from_world * vec4<f32>(position, 1.0);
    out.world = position;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    let n = cross(dpdx(in.world), dpdy(in.world));
    let len = length(n);
    var normal = vec3<f32>(0.0);
    if len > 0.0 && len < 3.0e38 {
        normal = n / len;
    }
    var out: GBufferOut;
    out.position_distance = vec4<f32>(in.world, distance(in.world, frame.eye.xyz));
    out.normal_flags = vec4<f32>(normal, 1.0);
    return out;
}
