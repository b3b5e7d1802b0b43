// techniques: paraboloid
// The paraboloid projection of `shadowmap_paraboloid::ParaboloidMap::project`, shared
// by the paraboloid depth pass, its lookup and the caster refinement: the renderer
// composes it into their `@compose paraboloid_side` regions (see `compose::expand`).
//
//   d = q / |q|          front: (x, s) = ( d.x, -d.z)      back: (x, s) = (-d.x, d.z)
//   disc = (x, d.y) / (1 + s)     with 1 + s = (x^2 + d.y^2) / (1 - s) where s < 0
//                                 (accurate near the pole)
//
// q is the light-space point (the light at the origin, the front side facing -Z).

// Returns (x, d.y, 1 + s, s): the disc point times its divisor, the divisor, and the
// cosine of the angle from the side's axis (the hemisphere clip distance).
fn paraboloid_side(q: vec3<f32>, back: bool) -> vec4<f32> {
    let d = q / max(length(q), 1e-30);
    var x = d.x;
    var s = -d.z;
    if back {
        x = -d.x;
        s = d.z;
    }
    let denom = select((x * x + d.y * d.y) / (1.0 - s), 1.0 + s, s >= 0.0);
    return vec4<f32>(x, d.y, denom, s);
}
