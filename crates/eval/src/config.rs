//! Evaluation configurations: a scene, a light, a scripted camera path and the depth
//! range.
//!
//! [`standard_configurations`] lists the cases of the report, each chosen to stress
//! one weakness of shadow-map parameterizations:
//!
//! | name | scene | light | what it shows |
//! |---|---|---|---|
//! | `overhead` | city block | directional, straight down | the textbook case of the closed-form storage factors (`n = 1`, `f = 1000`, fovY 60°, view horizontal) |
//! | `behind` | city block | directional, from behind the viewer (10° from the view direction) | light almost along the view: warps fade toward uniform |
//! | `facing` | city block | directional, toward the viewer (142° from the view direction) | dueling frusta |
//! | `facing_spot` | city block | spot in front, aimed at the viewer | dueling frusta with a perspective light |
//! | `facing_point` | city block | point in front of the viewer | dueling frusta with an omni light |
//! | `grazing` | fence | directional, 7° above the horizon | long thin shadows, projection aliasing |
//! | `sweep_30` .. `sweep_150` | terrain | directional at 30°, 60°, 120°, 150° from the view direction | the angle between view and light |
//! | `top_down` | city block | directional, 16° from the view direction | top-down camera |
//! | `point_near`, `point_mid`, `point_far` | city block | point light 8 m, 40 m, 150 m ahead | distance of an omni light |
//! | `point_inside` | indoor room | point light inside the view frustum | IPSM's dual fallback |
//! | `close_wall` | fence | directional | a wall 1 m away beside a vista to 1000 m |
//!
//! Every configuration has a scripted camera path (a short walk with a slow turn) of
//! [`ConfigOptions::path_frames`] frames over a static scene and light, for the
//! temporal metrics; frame 0 is the frame of the per-pixel metrics and the images.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use shadowmap_frustum::{Camera, Light, Projection};

use crate::EvalError;
use crate::scene::{Mesh, Scene};

mod sweep;
pub use sweep::sweep_configurations;

/// Knobs shared by every configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ConfigOptions {
    /// Seed of the procedural scenes.
    pub seed: u64,
    /// Frames of each camera path, at least 1 (1: no temporal metrics).
    pub path_frames: usize,
    /// Image width over height.
    pub aspect: f32,
}

impl Default for ConfigOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            path_frames: 6,
            aspect: 16.0 / 9.0,
        }
    }
}

impl ConfigOptions {
    /// With this scene seed.
    #[must_use]
    pub const fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// With this many frames per path.
    #[must_use]
    pub const fn with_path_frames(mut self, frames: usize) -> Self {
        self.path_frames = frames;
        self
    }
    /// With this aspect ratio.
    #[must_use]
    pub const fn with_aspect(mut self, aspect: f32) -> Self {
        self.aspect = aspect;
        self
    }
}

/// A scripted camera path: the camera walks from `eye` by `travel` while turning by
/// `yaw` radians about the world `y` axis, sampled at `frames` evenly spaced times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPath {
    /// Eye at the first frame.
    pub eye: DVec3,
    /// Viewing direction at the first frame.
    pub forward: DVec3,
    /// Up hint (world `y` unless the camera looks straight down).
    pub up: DVec3,
    /// Displacement of the eye from the first to the last frame.
    pub travel: DVec3,
    /// Turn about world `y` from the first to the last frame, radians.
    pub yaw: f64,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Near plane distance.
    pub near: f64,
    /// Far plane distance.
    pub far: f64,
}

impl CameraPath {
    /// The cameras of the path, `frames` of them (frame 0 at `eye`).
    ///
    /// # Errors
    /// [`EvalError::InvalidView`] when a frame is rejected by `shadowmap-frustum`
    /// (degenerate direction, bad depth range, ...) or `frames` is zero.
    pub fn sample(&self, frames: usize, aspect: f32) -> Result<Vec<Camera>, EvalError> {
        if frames == 0 {
            return Err(EvalError::InvalidView {
                message: "a camera path needs at least one frame".into(),
            });
        }
        let projection =
            Projection::perspective(self.fov_y as f32, aspect, self.near as f32, self.far as f32);
        (0..frames)
            .map(|k| {
                let t = if frames > 1 {
                    k as f64 / (frames - 1) as f64
                } else {
                    0.0
                };
                let eye = self.eye + self.travel * t;
                let turn = glam::DQuat::from_rotation_y(self.yaw * t);
                let forward = turn * self.forward;
                let up = turn * self.up;
                Camera::look_to(eye.as_vec3(), forward.as_vec3(), up.as_vec3(), projection).map_err(
                    |e| EvalError::InvalidView {
                        message: e.to_string(),
                    },
                )
            })
            .collect()
    }
}

/// One evaluation case: scene, light and camera path.
#[derive(Clone, Debug)]
pub struct Configuration {
    /// Short identifier (`overhead`, `facing_spot`, ...), used in file names.
    pub name: String,
    /// One line for the report.
    pub description: String,
    /// The geometry; every triangle casts and receives.
    pub scene: Arc<Scene>,
    /// The light (static along the path).
    pub light: Light,
    /// The cameras of the path; frame 0 is the measured frame.
    pub path: Vec<Camera>,
}

impl Configuration {
    /// The first (measured) camera.
    #[must_use]
    pub fn camera(&self) -> &Camera {
        &self.path[0]
    }

    /// Which family of techniques applies: `"directional"`, `"spot"` or `"point"`.
    #[must_use]
    pub const fn light_kind(&self) -> &'static str {
        match self.light {
            Light::Directional { .. } => "directional",
            Light::Spot { .. } => "spot",
            Light::Point { .. } => "point",
        }
    }
}

struct Spec {
    name: &'static str,
    description: &'static str,
    scene: usize,
    light: Light,
    path: CameraPath,
}

fn path(
    eye: DVec3,
    forward: DVec3,
    travel: DVec3,
    yaw_deg: f64,
    near: f64,
    far: f64,
) -> CameraPath {
    CameraPath {
        eye,
        forward,
        up: DVec3::Y,
        travel,
        yaw: yaw_deg.to_radians(),
        fov_y: 60f64.to_radians(),
        near,
        far,
    }
}

fn directional(d: DVec3) -> Light {
    Light::Directional {
        direction: d.normalize().as_vec3(),
    }
}

/// The light direction at `angle_deg` from the view direction `forward` (horizontal),
/// turned in the vertical plane through `forward` and tipped down where it can be.
fn light_at_angle(forward: DVec3, angle_deg: f64) -> DVec3 {
    let a = angle_deg.to_radians();
    // Rotate the view direction downward by `a` in its vertical plane.
    forward * a.cos() - DVec3::Y * a.sin()
}

/// The configurations of the report (see the module docs), for `options.seed` and
/// `options.path_frames`.
///
/// # Errors
/// [`EvalError::InvalidView`] for `path_frames == 0` or an aspect ratio the cameras
/// reject.
pub fn standard_configurations(options: &ConfigOptions) -> Result<Vec<Configuration>, EvalError> {
    let scenes = [
        Arc::new(Scene::city_block(options.seed)),
        Arc::new(Scene::fence()),
        Arc::new(Scene::terrain_with_trees(options.seed)),
        Arc::new(Scene::indoor_room()),
    ];
    let (city, fence, terrain, room) = (0, 1, 2, 3);
    let v = DVec3::new;
    let walk = v(0.0, 0.0, -3.0);
    let mut specs = vec![
        Spec {
            name: "overhead",
            description: "light straight down, view horizontal (n = 1, f = 1000, fovY = 60°)",
            scene: city,
            light: directional(v(0.0, -1.0, 0.0)),
            path: path(
                v(0.0, 1.7, 130.0),
                v(0.0, 0.0, -1.0),
                walk,
                4.0,
                1.0,
                1000.0,
            ),
        },
        Spec {
            name: "behind",
            description: "light from behind the viewer, 10° from the view direction",
            scene: city,
            light: directional(v(0.05, -0.45, -1.0)),
            path: path(
                v(0.0, 25.0, 140.0),
                v(0.0, -0.25, -1.0),
                walk,
                4.0,
                1.0,
                600.0,
            ),
        },
        Spec {
            name: "facing",
            description: "light toward the viewer (dueling frusta), 142° from the view direction",
            scene: city,
            light: directional(v(0.05, -0.45, 1.0)),
            path: path(
                v(0.0, 25.0, 140.0),
                v(0.0, -0.25, -1.0),
                walk,
                4.0,
                1.0,
                600.0,
            ),
        },
        Spec {
            name: "facing_spot",
            description: "spot light ahead aimed back at the viewer (dueling frusta)",
            scene: city,
            light: Light::Spot {
                position: Vec3::new(0.0, 40.0, -40.0),
                direction: Vec3::new(0.0, -0.45, 1.0).normalize(),
                half_angle: 50f32.to_radians(),
                range: 600.0,
            },
            path: path(
                v(0.0, 25.0, 140.0),
                v(0.0, -0.25, -1.0),
                walk,
                4.0,
                1.0,
                600.0,
            ),
        },
        Spec {
            name: "facing_point",
            description: "point light ahead of the viewer, inside the view (dueling frusta)",
            scene: city,
            light: Light::Point {
                position: Vec3::new(0.0, 40.0, -40.0),
                range: 600.0,
            },
            path: path(
                v(0.0, 25.0, 140.0),
                v(0.0, -0.25, -1.0),
                walk,
                4.0,
                1.0,
                600.0,
            ),
        },
        Spec {
            name: "grazing",
            description: "light 7° above the horizon across a fence",
            scene: fence,
            light: directional(v(0.8, -0.122, -0.6)),
            path: path(
                v(-2.0, 1.7, 8.0),
                v(0.1, -0.12, -1.0),
                v(1.0, 0.0, -0.5),
                3.0,
                0.1,
                300.0,
            ),
        },
    ];
    for angle in [30.0, 60.0, 120.0, 150.0] {
        let forward = v(0.0, 0.0, -1.0);
        specs.push(Spec {
            name: match angle as u32 {
                30 => "sweep_30",
                60 => "sweep_60",
                120 => "sweep_120",
                _ => "sweep_150",
            },
            description: match angle as u32 {
                30 => "terrain, light at 30° from the view direction",
                60 => "terrain, light at 60° from the view direction",
                120 => "terrain, light at 120° from the view direction",
                _ => "terrain, light at 150° from the view direction",
            },
            scene: terrain,
            light: directional(light_at_angle(forward, angle) + v(0.08, 0.0, 0.0)),
            path: path(
                v(0.0, 45.0, 300.0),
                v(0.0, -0.12, -1.0),
                v(0.0, 0.0, -8.0),
                4.0,
                1.0,
                1000.0,
            ),
        });
    }
    specs.extend([
        Spec {
            name: "top_down",
            description: "camera looking straight down, light 16° off the view direction",
            scene: city,
            light: directional(v(0.25, -1.0, 0.15)),
            path: CameraPath {
                up: DVec3::NEG_Z,
                ..path(
                    v(0.0, 150.0, 0.0),
                    v(0.0, -1.0, 0.0),
                    v(4.0, 0.0, -4.0),
                    5.0,
                    1.0,
                    400.0,
                )
            },
        },
        Spec {
            name: "point_near",
            description: "point light 8 m ahead of the viewer, 6 m up",
            scene: city,
            light: Light::Point {
                position: Vec3::new(0.5, 6.0, 110.0),
                range: 400.0,
            },
            path: path(
                v(0.0, 1.7, 118.0),
                v(0.0, -0.05, -1.0),
                walk,
                4.0,
                0.5,
                400.0,
            ),
        },
        Spec {
            name: "point_mid",
            description: "point light 40 m ahead of the viewer, 30 m up",
            scene: city,
            light: Light::Point {
                position: Vec3::new(0.5, 30.0, 78.0),
                range: 400.0,
            },
            path: path(
                v(0.0, 1.7, 118.0),
                v(0.0, -0.05, -1.0),
                walk,
                4.0,
                0.5,
                400.0,
            ),
        },
        Spec {
            name: "point_far",
            description: "point light 150 m ahead of the viewer, 80 m up",
            scene: city,
            light: Light::Point {
                position: Vec3::new(0.5, 80.0, -32.0),
                range: 600.0,
            },
            path: path(
                v(0.0, 1.7, 118.0),
                v(0.0, -0.05, -1.0),
                walk,
                4.0,
                0.5,
                400.0,
            ),
        },
        Spec {
            name: "point_inside",
            description: "indoor room, point light inside the view frustum",
            scene: room,
            light: Light::Point {
                position: Vec3::new(0.0, 2.5, 0.0),
                range: 30.0,
            },
            path: path(
                v(-4.2, 1.6, 3.4),
                v(1.0, -0.2, -0.8),
                v(0.4, 0.0, -0.4),
                6.0,
                0.1,
                30.0,
            ),
        },
        Spec {
            name: "close_wall",
            description: "a wall 1 m away beside an open vista to 1000 m",
            scene: fence,
            light: directional(v(-0.4, -0.7, 0.6)),
            path: path(
                v(18.0, 1.7, -2.2),
                v(1.0, -0.03, -0.35),
                v(1.0, 0.0, 0.0),
                4.0,
                0.1,
                1000.0,
            ),
        },
    ]);
    specs
        .into_iter()
        .map(|s| {
            Ok(Configuration {
                name: s.name.to_string(),
                description: s.description.to_string(),
                scene: Arc::clone(&scenes[s.scene]),
                light: s.light,
                path: s.path.sample(options.path_frames, options.aspect)?,
            })
        })
        .collect()
}

/// A configuration for a user mesh with an automatic camera and light: the camera
/// stands outside the mesh's bounding box, 30° above its centre on the `+z` side, at
/// 1.6 times the box's radius, looking at the centre; the light is directional from
/// the upper left (`(-0.4, -1, -0.3)`); the depth range covers the box.
///
/// # Errors
/// [`EvalError::InvalidMesh`] for a mesh without finite bounds, with zero size, or
/// so large that the camera's position overflows `f32`;
/// [`EvalError::InvalidView`] as [`CameraPath::sample`].
pub fn mesh_configuration(
    name: &str,
    mesh: Mesh,
    options: &ConfigOptions,
) -> Result<Configuration, EvalError> {
    let bounds = mesh.bounds().ok_or_else(|| EvalError::InvalidMesh {
        message: format!("{name}: mesh has no bounds"),
    })?;
    let centre = bounds.center().as_dvec3();
    let radius = 0.5 * bounds.size().as_dvec3().length();
    if !(radius.is_finite() && radius > 0.0) {
        return Err(EvalError::InvalidMesh {
            message: format!("{name}: mesh has zero size"),
        });
    }
    let dir_to_eye = DVec3::new(0.0, 0.5, 0.866).normalize();
    let distance = 1.6 * radius / (30f64.to_radians()).sin();
    let eye = centre + dir_to_eye * distance;
    let near = (distance - radius).max(distance * 1e-3) * 0.5;
    let far = distance + 2.0 * radius;
    // The camera is f32: its eye and planes must be finite there.
    let reach = eye.abs().max_element() + far;
    if !(reach as f32).is_finite() {
        return Err(EvalError::InvalidMesh {
            message: format!(
                "{name}: a bounding radius of {radius:.3e} puts the camera {reach:.3e} from the \
                 origin, beyond the f32 range of cameras"
            ),
        });
    }
    let cam_path = CameraPath {
        eye,
        forward: -dir_to_eye,
        up: DVec3::Y,
        travel: (DVec3::X) * (0.05 * radius),
        yaw: 2f64.to_radians(),
        fov_y: 60f64.to_radians(),
        near,
        far,
    };
    Ok(Configuration {
        name: "user_mesh".to_string(),
        description: format!("user mesh {name}, automatic camera and light"),
        scene: Arc::new(Scene::new(name, mesh)),
        light: directional(DVec3::new(-0.4, -1.0, -0.3)),
        path: cam_path.sample(options.path_frames, options.aspect)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_angle_sweep_has_the_named_angles() {
        let f = DVec3::NEG_Z;
        for a in [30.0f64, 60.0, 120.0, 150.0] {
            let d = light_at_angle(f, a).normalize();
            assert!((d.dot(f).acos().to_degrees() - a).abs() < 1e-9);
        }
    }

    #[test]
    fn path_moves_and_turns() {
        let p = path(
            DVec3::ZERO,
            DVec3::NEG_Z,
            DVec3::new(0.0, 0.0, -3.0),
            10.0,
            1.0,
            100.0,
        );
        let cams = p.sample(3, 1.5).unwrap();
        assert_eq!(cams.len(), 3);
        assert!((cams[2].eye().z + 3.0).abs() < 1e-6);
        let turn = cams[2].forward().dot(cams[0].forward()).acos().to_degrees();
        assert!((turn - 10.0).abs() < 1e-3);
        assert!(p.sample(0, 1.5).is_err());
    }
}
