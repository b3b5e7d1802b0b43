//! GPU time per pass from timestamp queries.
//!
//! A [`GpuProfiler`] writes a timestamp before and after each scope it wraps
//! ([`GpuProfiler::scope`]), resolves them at the end of the frame
//! ([`GpuProfiler::resolve`]) and reads them back as milliseconds
//! ([`GpuProfiler::read`]). It needs [`wgpu::Features::TIMESTAMP_QUERY`] and
//! [`wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS`] ([`GpuProfiler::FEATURES`];
//! open the device with [`GpuContext::new_headless_with_features`]); on a device
//! without them it records nothing and [`GpuProfiler::unsupported`] says why, so the
//! caller can print CPU times only.
//!
//! ```no_run
//! use shadowmap_wgpu::GpuContext;
//! use shadowmap_wgpu::profile::GpuProfiler;
//!
//! let ctx = GpuContext::new_headless_with_features(GpuProfiler::FEATURES)?;
//! let mut profiler = GpuProfiler::new(&ctx, 16);
//! let mut encoder = ctx.device.create_command_encoder(&Default::default());
//! profiler.scope(&mut encoder, "clear", |_encoder| { /* record passes */ });
//! profiler.resolve(&mut encoder);
//! ctx.queue.submit([encoder.finish()]);
//! for pass in profiler.read(&ctx)? {
//!     println!("{}: {:.3} ms", pass.label, pass.gpu_ms);
//! }
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use crate::{BackendError, GpuContext};

/// One timed scope.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    /// The scope's label.
    pub label: String,
    /// GPU time between its begin and end timestamps, in milliseconds.
    pub gpu_ms: f64,
}

/// The query set and its resolve buffer.
#[derive(Debug)]
struct Queries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    capacity: u32,
}

/// Timestamps around scopes of command recording; see the module docs.
#[derive(Debug)]
pub struct GpuProfiler {
    queries: Option<Queries>,
    labels: Vec<String>,
    period_ns: f64,
}

impl GpuProfiler {
    /// The device features the profiler needs.
    pub const FEATURES: wgpu::Features =
        wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

    /// A profiler with room for `max_scopes` scopes per frame (two timestamps each);
    /// inert where the device lacks [`GpuProfiler::FEATURES`] or `max_scopes` is 0.
    #[must_use]
    pub fn new(ctx: &GpuContext, max_scopes: u32) -> Self {
        let count = max_scopes
            .saturating_mul(2)
            .min(wgpu::QUERY_SET_MAX_QUERIES);
        let supported = ctx.device.features().contains(Self::FEATURES);
        let queries = (supported && count > 0).then(|| Queries {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("shadowmap profiler"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadowmap profiler resolve"),
                size: u64::from(count) * wgpu::QUERY_SIZE as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            capacity: count / 2,
        });
        Self {
            queries,
            labels: Vec::new(),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
        }
    }

    /// `None` when the profiler records; otherwise why it does not.
    #[must_use]
    pub fn unsupported(&self) -> Option<&'static str> {
        match &self.queries {
            Some(_) => None,
            None => Some("the device lacks TIMESTAMP_QUERY / TIMESTAMP_QUERY_INSIDE_ENCODERS"),
        }
    }

    /// Runs `record` between two timestamps labelled `label`. Without support, or
    /// once the frame's scopes are used up, it only runs `record`.
    pub fn scope<T>(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> T,
    ) -> T {
        let index = self.labels.len() as u32;
        let Some(q) = self.queries.as_ref().filter(|q| index < q.capacity) else {
            return record(encoder);
        };
        encoder.write_timestamp(&q.set, 2 * index);
        let out = record(encoder);
        encoder.write_timestamp(&q.set, 2 * index + 1);
        self.labels.push(label.to_owned());
        out
    }

    /// Records the resolve of this frame's timestamps; call once, after the last
    /// scope, before submitting.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(q) = self.queries.as_ref().filter(|_| !self.labels.is_empty()) {
            let used = 2 * self.labels.len() as u32;
            encoder.resolve_query_set(&q.set, 0..used, &q.resolve, 0);
        }
    }

    /// The GPU time of each scope of the submitted frame, in order, and starts a new
    /// frame. Empty without support. Waits for the GPU.
    ///
    /// # Errors
    /// [`BackendError::Readback`] if mapping fails.
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<PassTime>, BackendError> {
        let labels = std::mem::take(&mut self.labels);
        let Some(q) = &self.queries else {
            return Ok(Vec::new());
        };
        if labels.is_empty() {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&ctx.read_buffer(&q.resolve)?);
        Ok(labels
            .into_iter()
            .zip(ticks.chunks_exact(2))
            .map(|(label, pair)| PassTime {
                label,
                gpu_ms: pair[1].saturating_sub(pair[0]) as f64 * self.period_ns * 1e-6,
            })
            .collect())
    }
}
