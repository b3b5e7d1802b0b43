//! GPU time per pass from timestamp queries, and the CPU time of recording it.
//!
//! A [`GpuProfiler`] writes a timestamp before and after each scope it wraps
//! ([`GpuProfiler::scope`]), resolves them at the end of the frame
//! ([`GpuProfiler::resolve`]) and reads them back as milliseconds
//! ([`GpuProfiler::read`]). It also measures the CPU time the scope's recording took
//! (encoding, uploads queued, validation). GPU times need
//! [`wgpu::Features::TIMESTAMP_QUERY`] and
//! [`wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS`] ([`GpuProfiler::FEATURES`];
//! open the device with [`GpuContext::new_headless_with_features`]); on a device
//! without them every scope reads with CPU time only and
//! [`GpuProfiler::unsupported`] says why.
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
//!     println!("{}: CPU {:.3} ms, GPU {:?} ms", pass.label, pass.cpu_ms, pass.gpu_ms);
//! }
//! # Ok::<(), shadowmap_wgpu::BackendError>(())
//! ```

use std::time::Instant;

use crate::{BackendError, GpuContext};

/// One timed scope.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    /// The scope's label.
    pub label: String,
    /// CPU time of recording the scope, in milliseconds.
    pub cpu_ms: f64,
    /// GPU time between its begin and end timestamps, in milliseconds; `None`
    /// without timestamp support or past the profiler's scopes.
    pub gpu_ms: Option<f64>,
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
    /// This frame's scopes: label, CPU ms, whether it has timestamps.
    scopes: Vec<(String, f64, bool)>,
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
            scopes: Vec::new(),
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

    /// Runs `record` between two timestamps labelled `label` and measures its CPU
    /// time. Without support, or once the frame's timestamps are used up, the scope
    /// gets CPU time only. Scopes may span several encoders of one frame (resolve in
    /// the last one, submitted last).
    pub fn scope<T>(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> T,
    ) -> T {
        let index = self.timed_scopes();
        let queries = self.queries.as_ref().filter(|q| index < q.capacity);
        if let Some(q) = queries {
            encoder.write_timestamp(&q.set, 2 * index);
        }
        let start = Instant::now();
        let out = record(encoder);
        let cpu_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(q) = queries {
            encoder.write_timestamp(&q.set, 2 * index + 1);
        }
        self.scopes
            .push((label.to_owned(), cpu_ms, queries.is_some()));
        out
    }

    /// Scopes of this frame with timestamps.
    fn timed_scopes(&self) -> u32 {
        self.scopes.iter().filter(|s| s.2).count() as u32
    }

    /// Records the resolve of this frame's timestamps; call once, after the last
    /// scope, before submitting.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let used = 2 * self.timed_scopes();
        if let Some(q) = self.queries.as_ref().filter(|_| used > 0) {
            encoder.resolve_query_set(&q.set, 0..used, &q.resolve, 0);
        }
    }

    /// Each scope of the submitted frame, in order, with its CPU time and (with
    /// timestamps) its GPU time, and starts a new frame. Waits for the GPU.
    ///
    /// # Errors
    /// [`BackendError::Readback`] if mapping fails.
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<PassTime>, BackendError> {
        let scopes = std::mem::take(&mut self.scopes);
        let ticks: Vec<u64> = match &self.queries {
            Some(q) if scopes.iter().any(|s| s.2) => {
                bytemuck::pod_collect_to_vec(&ctx.read_buffer(&q.resolve)?)
            }
            _ => Vec::new(),
        };
        let mut pairs = ticks.chunks_exact(2);
        Ok(scopes
            .into_iter()
            .map(|(label, cpu_ms, timed)| PassTime {
                label,
                cpu_ms,
                gpu_ms: timed
                    .then(|| pairs.next())
                    .flatten()
                    .map(|pair| pair[1].saturating_sub(pair[0]) as f64 * self.period_ns * 1e-6),
            })
            .collect())
    }
}
