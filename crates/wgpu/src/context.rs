//! Headless device acquisition, and the GPU-test policy (skip or require).

use core::fmt;

/// What can go wrong in the backend.
#[derive(Debug)]
#[non_exhaustive]
pub enum BackendError {
    /// No adapter was found (no GPU and no software Vulkan driver).
    NoAdapter(String),
    /// The adapter refused the device request.
    RequestDevice(String),
    /// wgpu reported a validation or out-of-memory error inside an error scope.
    Wgpu(String),
    /// Reading a buffer back failed.
    Readback(String),
    /// An input was out of range (size zero, too many layers, mismatched tables, ...).
    InvalidInput(&'static str),
    /// Writing an image failed.
    Io(String),
}

impl fmt::Display for BackendError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoAdapter(e) => write!(f, "no GPU adapter: {e}"),
            Self::RequestDevice(e) => write!(f, "device request failed: {e}"),
            Self::Wgpu(e) => write!(f, "wgpu error: {e}"),
            Self::Readback(e) => write!(f, "readback failed: {e}"),
            Self::InvalidInput(e) => write!(f, "invalid input: {e}"),
            Self::Io(e) => write!(f, "i/o error: {e}"),
        }
    }
}

impl std::error::Error for BackendError {}

/// A headless device and queue.
#[derive(Debug)]
pub struct GpuContext {
    /// The adapter the device came from.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
}

impl GpuContext {
    /// Opens the first adapter wgpu offers (a real GPU first, then software such as
    /// llvmpipe) with default limits and no optional features.
    ///
    /// # Errors
    /// [`BackendError::NoAdapter`] when there is none, [`BackendError::RequestDevice`]
    /// when the device request fails.
    pub fn new_headless() -> Result<Self, BackendError> {
        pollster::block_on(Self::new_headless_async())
    }

    /// [`GpuContext::new_headless`] without blocking.
    ///
    /// # Errors
    /// As [`GpuContext::new_headless`].
    pub async fn new_headless_async() -> Result<Self, BackendError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                ..Default::default()
            })
            .await
            .map_err(|e| BackendError::NoAdapter(e.to_string()))?;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("shadowmap"),
                required_features: wgpu::Features::empty(),
                required_limits: wgpu::Limits::default().using_resolution(adapter.limits()),
                ..Default::default()
            })
            .await
            .map_err(|e| BackendError::RequestDevice(e.to_string()))?;
        Ok(Self {
            adapter,
            device,
            queue,
        })
    }

    /// The adapter's name and backend, for logs and recorded timings.
    pub fn describe(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
    }

    /// Maps a `MAP_READ` buffer, waits for it, and hands its bytes to `read`; the
    /// buffer is unmapped afterwards.
    pub(crate) fn read_mapped<T>(
        &self,
        buffer: &wgpu::Buffer,
        read: impl FnOnce(&[u8]) -> T,
    ) -> Result<T, BackendError> {
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| BackendError::Readback(e.to_string()))?;
        receiver
            .recv()
            .map_err(|e| BackendError::Readback(e.to_string()))?
            .map_err(|e| BackendError::Readback(e.to_string()))?;
        let value = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| BackendError::Readback(e.to_string()))?;
            read(&view)
        };
        buffer.unmap();
        Ok(value)
    }

    /// Reads every layer of a `Depth32Float` texture (mip 0) back: layer-major, then
    /// row-major, row 0 at the top. Waits for the GPU.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for another format or a texture without
    /// `COPY_SRC`; [`BackendError::Readback`] if mapping fails.
    pub fn read_depth_texture(&self, texture: &wgpu::Texture) -> Result<Vec<f32>, BackendError> {
        if texture.format() != wgpu::TextureFormat::Depth32Float {
            return Err(BackendError::InvalidInput("not a Depth32Float texture"));
        }
        if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
            return Err(BackendError::InvalidInput("depth texture lacks COPY_SRC"));
        }
        let bytes = crate::depth::read_texture(
            self,
            texture,
            wgpu::TextureAspect::DepthOnly,
            texture.width(),
            texture.height(),
            texture.depth_or_array_layers(),
            4,
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Runs `f` inside validation and out-of-memory error scopes, waits for the GPU,
    /// and turns any captured error into [`BackendError::Wgpu`].
    ///
    /// # Errors
    /// The first error `f` returns, or the first one wgpu captured.
    pub fn scoped<T>(
        &self,
        f: impl FnOnce(&Self) -> Result<T, BackendError>,
    ) -> Result<T, BackendError> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let result = f(self);
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        let validation = pollster::block_on(validation.pop());
        let oom = pollster::block_on(oom.pop());
        if let Some(e) = validation.or(oom) {
            return Err(BackendError::Wgpu(e.to_string()));
        }
        result
    }
}

/// The environment variable that turns a missing adapter into a test failure.
pub const REQUIRE_GPU_ENV: &str = "SHADOWMAP_REQUIRE_GPU";

/// The context for a GPU test: `Some` when an adapter opens; `None` with a one-line
/// notice on stderr when none does; a panic (test failure) when none does and
/// `SHADOWMAP_REQUIRE_GPU=1` is set, so CI cannot silently skip.
///
/// # Panics
/// When no adapter opens and `SHADOWMAP_REQUIRE_GPU=1`.
pub fn test_context(test: &str) -> Option<GpuContext> {
    match GpuContext::new_headless() {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            let required = std::env::var(REQUIRE_GPU_ENV).is_ok_and(|v| v == "1");
            assert!(!required, "{test}: {REQUIRE_GPU_ENV}=1 but {e}");
            eprintln!("skipping GPU test {test}: {e}");
            None
        }
    }
}
