// techniques: any
// Projective shadows: the occluders drawn from the light into a mask (1 where an
// occluder is), then the camera's view: receivers look the mask up through
// homogeneous texture coordinates (interpolated as a vec4, divided per fragment),
// occluders are drawn fully lit. Output classes: 1 lit, 2 shadowed (0 background).

struct Frame {
    clip_from_world: mat4x4<f32>,
    // Camera eye (xyz) and the view depth up to which surfaces count (w).
    eye: vec4<f32>,
    // Unit view direction (xyz).
    forward: vec4<f32>,
};

struct Projective {
    // The light's clip space from world space (the occluder mask).
    clip_from_world: mat4x4<f32>,
    // Homogeneous mask coordinates (s, t, _, q) from world space, v down.
    uv_from_world: mat4x4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> projective: Projective;
@group(1) @binding(0) var mask: texture_2d<u32>;

@vertex
fn vs_occluder_mask(@location(0) position: vec3<f32>) -> @builtin(position) vec4<f32> {
    return projective.clip_from_world * vec4<f32>(position, 1.0);
}

@fragment
fn fs_occluder_mask() -> @location(0) u32 {
    return 1u;
}

struct CameraOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) stq: vec4<f32>,
};

@vertex
fn vs_camera(@location(0) position: vec3<f32>) -> CameraOut {
    var out: CameraOut;
    let p = vec4<f32>(position, 1.0);
    out.clip = frame.clip_from_world * p;
    out.world = position;
    out.stq = projective.uv_from_world * p;
    return out;
}

fn in_range(world: vec3<f32>) -> bool {
    return dot(world - frame.eye.xyz, frame.forward.xyz) <= frame.eye.w;
}

// Occluders: fully lit (no self-shadowing).
@fragment
fn fs_occluder(in: CameraOut) -> @location(0) u32 {
    if !in_range(in.world) {
        discard;
    }
    return 1u;
}

// Receivers: shadowed where the mask holds an occluder.
@fragment
fn fs_receiver(in: CameraOut) -> @location(0) u32 {
    if !in_range(in.world) {
        discard;
    }
    if in.stq.w <= 0.0 {
        return 1u;
    }
    let side = vec2<f32>(textureDimensions(mask));
    let texel = floor(in.stq.xy / in.stq.w * side);
    if any(texel < vec2<f32>(0.0)) || any(texel >= side) {
        return 1u;
    }
    let occluded = textureLoad(mask, vec2<i32>(texel), 0).x;
    return select(1u, 2u, occluded != 0u);
}
