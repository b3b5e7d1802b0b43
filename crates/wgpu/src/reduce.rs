//! Min/max reduction of a depth buffer on the GPU, for depth bounds (SDSM, Lauritzen et
//! al. 2011; the truncated view frustum of IPSM).
//!
//! The reduction works on *raw* depth (what the depth buffer holds) and skips the
//! background: texels holding the clear value, depth `>= 1` (or `<= 0` with reversed-Z),
//! the same rule as [`shadowmap_rtw::ImportanceMap::accumulate_forward`]. The CPU turns
//! the raw range into view depths with [`RawDepthRange::view_depth_bounds`], which is
//! what [`shadowmap_frustum::CascadeSplits::from_depth_bounds`] consumes.
//!
//! ```text
//! pass 1 (reduce_tiles):    32x32 tile -> partial (min, max)    16x16 workgroups, 2x2 texels each
//! pass 2 (reduce_partials): partials   -> (min, max)            one 256-wide workgroup
//! ```
//!
//! Depths are non-negative, so the reduction runs on their bit patterns with `u32`
//! min/max, which is exact: the GPU result equals the CPU min/max of the same values.
//!
//! # Example
//! ```
//! use shadowmap_frustum::{Camera, DepthBounds};
//! use shadowmap_wgpu::reduce::DepthReduction;
//! use shadowmap_wgpu::{BackendError, GpuContext};
//!
//! /// Visible view-depth bounds of the eye's depth buffer (already rendered).
//! fn visible_depth(
//!     ctx: &GpuContext,
//!     depth: &wgpu::Texture,
//!     camera: &Camera,
//! ) -> Result<Option<DepthBounds>, BackendError> {
//!     let mut reduction = DepthReduction::new(ctx, camera.reversed_z);
//!     let mut encoder = ctx.device.create_command_encoder(&Default::default());
//!     reduction.encode(ctx, &mut encoder, depth)?;
//!     ctx.queue.submit([encoder.finish()]);
//!     // `None`: every texel is background.
//!     Ok(reduction.read(ctx)?.and_then(|raw| raw.view_depth_bounds(camera).ok()))
//! }
//! ```

use glam::DVec4;
use shadowmap_frustum::{Camera, DepthBounds, FrustumError};

use crate::{BackendError, GpuContext};

/// Side of the square tile one workgroup of the first pass reduces.
pub const REDUCE_TILE: u32 = 32;

/// The smallest and largest visible raw depth of a depth buffer (as stored, in
/// `[0, 1]`; with reversed-Z, `max` is the nearest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawDepthRange {
    /// Smallest visible raw depth.
    pub min: f32,
    /// Largest visible raw depth.
    pub max: f32,
}

impl RawDepthRange {
    /// The CPU reference reduction: min and max over the visible depths, skipping the
    /// background (`>= 1`, or `<= 0` with `reversed_z`) and NaN. `None` when nothing is
    /// visible.
    #[must_use]
    pub fn from_depths(depths: &[f32], reversed_z: bool) -> Option<Self> {
        depths
            .iter()
            .copied()
            .filter(|&d| is_visible(d, reversed_z))
            .fold(None, |range, d| {
                Some(match range {
                    None => Self { min: d, max: d },
                    Some(Self { min, max }) => Self {
                        min: min.min(d),
                        max: max.max(d),
                    },
                })
            })
    }

    /// The view-depth bounds (distance along the viewing direction) of this raw range
    /// for `camera`'s projection, computed in `f64` from the inverse projection at the
    /// centre of the screen (view depth depends only on raw depth for perspective and
    /// orthographic projections). Reversed-Z is handled: the bounds are ordered.
    ///
    /// Documented fallback: a raw range that maps to non-finite depths (a singular
    /// projection) gives the camera's whole depth range.
    ///
    /// # Errors
    /// As [`Camera::validate`].
    pub fn view_depth_bounds(&self, camera: &Camera) -> Result<DepthBounds, FrustumError> {
        let (near, far) = camera.depth_range()?;
        let view_from_clip = camera.clip_from_view()?.as_dmat4().inverse();
        let view_depth = |raw: f32| {
            let v = view_from_clip * DVec4::new(0.0, 0.0, f64::from(raw), 1.0);
            (-v.z / v.w) as f32
        };
        let (a, b) = (view_depth(self.min), view_depth(self.max));
        if !(a.is_finite() && b.is_finite()) {
            return Ok(DepthBounds {
                min: near,
                max: far,
            });
        }
        Ok(DepthBounds {
            min: a.min(b),
            max: a.max(b),
        })
    }
}

fn is_visible(d: f32, reversed_z: bool) -> bool {
    if reversed_z {
        d > 0.0 && d <= 1.0
    } else {
        (0.0..1.0).contains(&d)
    }
}

/// Bytes of one partial or of the result: `(min bits, max bits)`.
const PAIR_BYTES: u64 = 8;

/// The GPU min/max depth reduction: two compute pipelines and their buffers.
///
/// One instance reduces any number of depth buffers of any size. Per call,
/// [`DepthReduction::encode`] creates a texture view and two bind groups (the input
/// texture varies); the partials buffer grows on demand and is otherwise reused.
#[derive(Debug)]
pub struct DepthReduction {
    reversed_z: bool,
    tiles: wgpu::ComputePipeline,
    partials_pass: wgpu::ComputePipeline,
    partials: wgpu::Buffer,
    result: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl DepthReduction {
    /// Compiles the two passes; `reversed_z` selects which clear value is background
    /// (0 instead of 1).
    #[must_use]
    pub fn new(ctx: &GpuContext, reversed_z: bool) -> Self {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("reduce_depth"),
            source: wgpu::ShaderSource::Wgsl(crate::shaders::REDUCE_DEPTH.into()),
        });
        let constants = [("REVERSED_Z", if reversed_z { 1.0 } else { 0.0 })];
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: None,
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                },
                cache: None,
            })
        };
        let tiles = pipeline("reduce_tiles");
        let partials_pass = pipeline("reduce_partials");
        let partials = partials_buffer(device, 64);
        let result = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reduce_depth result"),
            size: PAIR_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("reduce_depth readback"),
            size: PAIR_BYTES,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            reversed_z,
            tiles,
            partials_pass,
            partials,
            result,
            readback,
        }
    }

    /// Whether depth 0 (not 1) is the background.
    #[must_use]
    pub const fn reversed_z(&self) -> bool {
        self.reversed_z
    }

    /// The buffer holding the result, `(min bits, max bits)` as two `u32`
    /// (`min > max` when nothing is visible), for GPU consumers that want the bounds
    /// without a readback.
    #[must_use]
    pub const fn result_buffer(&self) -> &wgpu::Buffer {
        &self.result
    }

    /// Records the reduction of mip 0, layer 0 of `depth` and the copy of the result
    /// into the readback buffer. Call [`DepthReduction::read`] after submitting.
    ///
    /// `depth` must be a single-sampled 2-D texture with a depth aspect and
    /// `TEXTURE_BINDING` usage (any depth format; with a stencil aspect only depth is
    /// read).
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a texture that breaks those rules or has more
    /// tiles than one dispatch can cover.
    pub fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::Texture,
    ) -> Result<(), BackendError> {
        if !depth.format().has_depth_aspect() {
            return Err(BackendError::InvalidInput(
                "depth reduction: not a depth texture",
            ));
        }
        if depth.sample_count() != 1 || depth.dimension() != wgpu::TextureDimension::D2 {
            return Err(BackendError::InvalidInput(
                "depth reduction: texture must be 2-D and single-sampled",
            ));
        }
        if !depth.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
            return Err(BackendError::InvalidInput(
                "depth reduction: texture lacks TEXTURE_BINDING usage",
            ));
        }
        let (groups_x, groups_y) = (
            depth.width().div_ceil(REDUCE_TILE),
            depth.height().div_ceil(REDUCE_TILE),
        );
        let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension;
        if groups_x > max_groups || groups_y > max_groups {
            return Err(BackendError::InvalidInput(
                "depth reduction: texture too large for one dispatch",
            ));
        }
        let partial_bytes = u64::from(groups_x) * u64::from(groups_y) * PAIR_BYTES;
        if self.partials.size() < partial_bytes {
            self.partials = partials_buffer(&ctx.device, partial_bytes.next_power_of_two());
        }
        let view = depth.create_view(&wgpu::TextureViewDescriptor {
            label: Some("reduce_depth input"),
            dimension: Some(wgpu::TextureViewDimension::D2),
            aspect: wgpu::TextureAspect::DepthOnly,
            base_mip_level: 0,
            mip_level_count: Some(1),
            base_array_layer: 0,
            array_layer_count: Some(1),
            ..Default::default()
        });
        // The partials binding has exactly one pair per tile: the final pass reads its
        // length with arrayLength.
        let partials = wgpu::BufferBinding {
            buffer: &self.partials,
            offset: 0,
            size: wgpu::BufferSize::new(partial_bytes),
        };
        let tiles_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("reduce_tiles"),
            layout: &self.tiles.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(partials.clone()),
                },
            ],
        });
        let final_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("reduce_partials"),
            layout: &self.partials_pass.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(partials),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: self.result.as_entire_binding(),
                },
            ],
        });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("reduce_depth"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.tiles);
            pass.set_bind_group(0, &tiles_group, &[]);
            pass.dispatch_workgroups(groups_x, groups_y, 1);
            pass.set_pipeline(&self.partials_pass);
            pass.set_bind_group(0, &final_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&self.result, 0, &self.readback, 0, PAIR_BYTES);
        Ok(())
    }

    /// Maps the readback buffer (blocking until the GPU is done) and returns the range
    /// of the last submitted [`DepthReduction::encode`], `None` when every texel was
    /// background.
    ///
    /// # Errors
    /// [`BackendError::Readback`] when mapping fails.
    pub fn read(&self, ctx: &GpuContext) -> Result<Option<RawDepthRange>, BackendError> {
        let words: Vec<u32> = ctx.read_mapped(&self.readback, bytemuck::pod_collect_to_vec)?;
        let (lo, hi) = match words.as_slice() {
            [lo, hi, ..] => (*lo, *hi),
            _ => return Err(BackendError::Readback("short result".into())),
        };
        if lo > hi {
            return Ok(None);
        }
        Ok(Some(RawDepthRange {
            min: f32::from_bits(lo),
            max: f32::from_bits(hi),
        }))
    }
}

fn partials_buffer(device: &wgpu::Device, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("reduce_depth partials"),
        size,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_reference_skips_background() {
        let d = [1.0, 0.25, 0.5, f32::NAN, 0.75, 1.0];
        assert_eq!(
            RawDepthRange::from_depths(&d, false),
            Some(RawDepthRange {
                min: 0.25,
                max: 0.75
            })
        );
        let r = [0.0, 0.25, 0.5, 0.0];
        assert_eq!(
            RawDepthRange::from_depths(&r, true),
            Some(RawDepthRange {
                min: 0.25,
                max: 0.5
            })
        );
        assert_eq!(RawDepthRange::from_depths(&[1.0; 4], false), None);
        assert_eq!(RawDepthRange::from_depths(&[0.0; 4], true), None);
        assert_eq!(RawDepthRange::from_depths(&[], true), None);
    }

    #[test]
    fn raw_range_maps_to_view_depths_with_and_without_reversed_z() {
        use glam::Vec3;
        use shadowmap_frustum::Projection;
        for reversed in [false, true] {
            let camera = Camera::look_to(
                Vec3::ZERO,
                Vec3::NEG_Z,
                Vec3::Y,
                Projection::perspective(1.0, 1.5, 0.5, 100.0),
            )
            .unwrap()
            .with_reversed_z(reversed);
            let clip_from_view = camera.clip_from_view().unwrap();
            let raw = |z: f32| {
                let c = clip_from_view * glam::Vec4::new(0.3, -0.2, -z, 1.0);
                c.z / c.w
            };
            let (a, b) = (raw(2.0), raw(40.0));
            let range = RawDepthRange {
                min: a.min(b),
                max: a.max(b),
            };
            let bounds = range.view_depth_bounds(&camera).unwrap();
            assert!((bounds.min - 2.0).abs() < 1e-3, "{reversed}: {bounds:?}");
            assert!((bounds.max - 40.0).abs() < 0.1, "{reversed}: {bounds:?}");
        }
    }
}
