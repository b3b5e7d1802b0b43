// techniques: any
// Stencil shadow volumes: the camera's surfaces, the volumes' two-sided stencil
// count (z-pass or z-fail, set by the pipeline's stencil state), then the per-pixel
// classification (lit, shadowed, background) of every visible surface.
//
// Depth is reversed-Z with the far plane at infinity (cleared to 0, `Greater`
// passes): volume vertices with w = 0 land exactly on depth 0. Every pass computes
// its position with the same @invariant expression, so a front cap drawn over the
// caster's own triangle gets exactly the caster's depth.

struct Frame {
    clip_from_world: mat4x4<f32>,
    // Camera eye (xyz) and the view depth up to which surfaces count (w).
    eye: vec4<f32>,
    // Unit view direction (xyz).
    forward: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;

struct SurfaceOut {
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
};

@vertex
fn vs_surface(@location(0) position: vec4<f32>) -> SurfaceOut {
    var out: SurfaceOut;
    out.clip = frame.clip_from_world * position;
    out.world = position.xyz;
    return out;
}

// Marks the pixel as a surface (1); surfaces past the depth range are left out,
// as the ray caster's primary rays stop there.
@fragment
fn fs_surface(in: SurfaceOut) -> @location(0) u32 {
    if dot(in.world - frame.eye.xyz, frame.forward.xyz) > frame.eye.w {
        discard;
    }
    return 1u;
}

struct VolumeOut {
    @invariant @builtin(position) clip: vec4<f32>,
};

@vertex
fn vs_volume(@location(0) position: vec4<f32>) -> VolumeOut {
    var out: VolumeOut;
    out.clip = frame.clip_from_world * position;
    return out;
}

// A full-screen triangle on the far plane (depth 0): drawn with `Less`, it covers
// exactly the pixels that hold a surface.
@vertex
fn vs_fullscreen(@builtin(vertex_index) index: u32) -> VolumeOut {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VolumeOut;
    out.clip = vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

// Shadowed (2): drawn where the stencil count is not zero.
@fragment
fn fs_shadowed() -> @location(0) u32 {
    return 2u;
}
