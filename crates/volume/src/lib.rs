//! Stencil shadow volumes and projective shadows, GPU-free.
//!
//! The shadow overview's two other real-time shadow systems, beside shadow maps:
//!
//! - **Shadow volumes** (Crow, *Shadow algorithms for computer graphics*, SIGGRAPH
//!   1977; z-fail with caps and an infinite far plane after Everitt and Kilgard,
//!   *Practical and Robust Stenciled Shadow Volumes for Hardware-Accelerated
//!   Rendering*, 2002): exact per pixel. [`EdgeMesh`] checks that a caster is closed
//!   and pairs its edges once; [`ShadowVolume::update`] finds the light-facing
//!   triangles and the silhouette per light and builds the volume (sides extruded to
//!   infinity as `w = 0` points, front and back caps); [`infinite_clip_from_world`]
//!   is the camera projection that keeps those points. [`Partition`] splits a scene
//!   into closed casters and open receivers, reporting the first open edge.
//! - **Projective shadows** (Blinn, *Me and my (fake) shadow*, 1988): the occluders
//!   drawn black on white from the light, projected onto separate receivers with
//!   homogeneous texture coordinates ([`ProjectiveShadow`]; [`OccluderMask`] is the
//!   CPU reference of the mask and its lookup).
//!
//! The crate needs `alloc` (meshes and volumes are buffers) and builds `no_std` with
//! the `libm` feature.
//!
//! # Example
//!
//! ```
//! use glam::{Vec3, Vec4};
//! use shadowmap_frustum::Light;
//! use shadowmap_volume::{EdgeMesh, ShadowVolume, VolumeError};
//!
//! // A unit tetrahedron, counter-clockwise seen from outside.
//! let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
//! let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
//! let mesh = EdgeMesh::new(&p, &tris)?;
//! assert_eq!(mesh.edges.len(), 6);
//!
//! let light = Light::Point { position: Vec3::new(0.2, 5.0, 0.2), range: 100.0 };
//! let mut volume = ShadowVolume::new();
//! volume.update(&mesh, &light)?;
//! // The silhouette seen from above is the triangle's outline: one closed loop.
//! assert_eq!(volume.silhouette.len(), 3);
//! // Two triangles per side edge; the sides reach infinity (w = 0).
//! assert_eq!(volume.sides().len(), 3 * 2 * 3);
//! assert!(volume.sides().iter().any(|v: &Vec4| v.w == 0.0));
//!
//! // An open mesh is refused, naming the edge.
//! let open = EdgeMesh::new(&p, &tris[..3]);
//! assert!(matches!(open, Err(VolumeError::OpenEdge { .. })));
//! # Ok::<(), VolumeError>(())
//! ```
//!
//! # Conventions
//!
//! The workspace's (see `shadowmap-frustum`): right-handed world, `y` up, WebGPU clip
//! space, matrices named destination-from-source, `f32` in the API and `f64` inside.
//! Triangles are counter-clockwise seen from outside. The camera projection of the
//! volumes is reversed-Z (depth 1 at the near plane, 0 at infinity).

#![no_std]

extern crate alloc;

mod error;
mod mesh;
mod projection;
mod projective;
mod volume;

pub use error::VolumeError;
pub use mesh::{Edge, EdgeMesh, Partition};
pub use projection::{ProjectiveShadow, infinite_clip_from_world};
pub use projective::{MAX_MASK_SIDE, OccluderMask};
pub use volume::{ShadowVolume, silhouette_edges};
