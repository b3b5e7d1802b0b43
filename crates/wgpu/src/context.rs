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
        Self::open(wgpu::Features::empty()).await
    }

    /// [`GpuContext::new_headless`] with those of `wanted` the adapter offers
    /// enabled (e.g. [`crate::profile::GpuProfiler::FEATURES`]); check
    /// `device.features()` for what was granted.
    ///
    /// # Errors
    /// As [`GpuContext::new_headless`].
    pub fn new_headless_with_features(wanted: wgpu::Features) -> Result<Self, BackendError> {
        pollster::block_on(Self::open(wanted))
    }

    async fn open(wanted: wgpu::Features) -> Result<Self, BackendError> {
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
                required_features: wanted & adapter.features(),
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
    /// buffer is unmapped afterwards. The one place the backend maps memory: every
    /// readback ([`GpuContext::read_buffer`], [`GpuContext::read_texture`], a
    /// persistent staging buffer) ends here.
    ///
    /// # Errors
    /// [`BackendError::Readback`] if mapping fails.
    pub fn read_mapped<T>(
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

    /// A fresh `MAP_READ | COPY_DST` buffer of `size` bytes.
    fn staging(&self, size: u64) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadowmap readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Copies a whole buffer into a fresh staging buffer, waits for the GPU and
    /// returns its bytes (a test, debug and report path: it allocates and blocks).
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a buffer without `COPY_SRC` usage;
    /// [`BackendError::Readback`] if mapping fails.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, BackendError> {
        if !buffer.usage().contains(wgpu::BufferUsages::COPY_SRC) {
            return Err(BackendError::InvalidInput("buffer lacks COPY_SRC"));
        }
        let staging = self.staging(buffer.size());
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("shadowmap readback"),
            });
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
        self.queue.submit([encoder.finish()]);
        self.read_mapped(&staging, <[u8]>::to_vec)
    }

    /// Copies mip 0 of every layer of a texture (one `aspect`) into a fresh staging
    /// buffer, waits for the GPU and returns the texels tightly packed: layer-major,
    /// then row-major, row 0 at the top.
    ///
    /// # Errors
    /// [`BackendError::InvalidInput`] for a texture without `COPY_SRC` usage or an
    /// aspect or format that cannot be copied texel by texel (compressed, or both
    /// aspects of depth-stencil); [`BackendError::Readback`] if mapping fails.
    pub fn read_texture(
        &self,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
    ) -> Result<Vec<u8>, BackendError> {
        if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
            return Err(BackendError::InvalidInput("texture lacks COPY_SRC"));
        }
        let format = texture.format();
        let texel = format
            .block_copy_size(Some(aspect))
            .filter(|_| format.block_dimensions() == (1, 1))
            .ok_or(BackendError::InvalidInput(
                "texture aspect cannot be read back",
            ))?;
        let (width, height) = (texture.width(), texture.height());
        let layers = texture.depth_or_array_layers();
        let row = width * texel;
        let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let staging = self.staging(u64::from(padded) * u64::from(height) * u64::from(layers));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("shadowmap readback"),
            });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            texture.size(),
        );
        self.queue.submit([encoder.finish()]);
        self.read_mapped(&staging, |mapped| {
            let mut out = Vec::with_capacity(row as usize * height as usize * layers as usize);
            for chunk in mapped.chunks(padded as usize) {
                out.extend_from_slice(&chunk[..row as usize]);
            }
            out
        })
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
        let bytes = self.read_texture(texture, wgpu::TextureAspect::DepthOnly)?;
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

/// A pipeline drawing [`MeshBuffers`](crate::depth::MeshBuffers) triangle lists, both faces, with `vs_main`
/// and (given colour targets, possibly none) `fs_main` of `module`; `layout` `None`:
/// derived from the shader.
pub(crate) fn mesh_pipeline(
    device: &wgpu::Device,
    (label, layout, module): (&str, Option<&wgpu::PipelineLayout>, &wgpu::ShaderModule),
    depth_stencil: wgpu::DepthStencilState,
    targets: Option<&[Option<wgpu::ColorTargetState>]>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout,
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(crate::depth::MeshBuffers::layout())],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(depth_stencil),
        multisample: Default::default(),
        fragment: targets.map(|targets| wgpu::FragmentState {
            module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A one-layer, one-mip 2-D texture (render targets, G-buffers, read-back images).
pub(crate) fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A [`GpuContext`] for one test, held under a process-wide lock: the GPU tests of
/// one test binary run one at a time (Mesa's llvmpipe has crashed with devices
/// created and dropped on parallel test threads). Dereferences to the context.
#[derive(Debug)]
pub struct TestContext {
    // Dropped first: the device goes while the lock is held.
    ctx: GpuContext,
    _serial: std::sync::MutexGuard<'static, ()>,
}

impl core::ops::Deref for TestContext {
    type Target = GpuContext;
    fn deref(&self) -> &GpuContext {
        &self.ctx
    }
}

/// Held by every [`TestContext`].
static GPU_TESTS: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The context for a GPU test: `Some` when an adapter opens; `None` with a one-line
/// notice on stderr when none does; a panic (test failure) when none does and
/// `SHADOWMAP_REQUIRE_GPU=1` is set, so CI cannot silently skip. The tests of one
/// process that hold a context run one at a time ([`TestContext`]).
///
/// # Panics
/// When no adapter opens and `SHADOWMAP_REQUIRE_GPU=1`.
pub fn test_context(test: &str) -> Option<TestContext> {
    // A test that failed while holding the lock poisons it; the next one may run.
    let serial = GPU_TESTS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    match GpuContext::new_headless() {
        Ok(ctx) => Some(TestContext {
            ctx,
            _serial: serial,
        }),
        Err(e) => {
            let required = std::env::var(REQUIRE_GPU_ENV).is_ok_and(|v| v == "1");
            assert!(!required, "{test}: {REQUIRE_GPU_ENV}=1 but {e}");
            eprintln!("skipping GPU test {test}: {e}");
            None
        }
    }
}
