//! Device set-up, buffer helpers, timestamp profiling and shader composition.

pub mod persistent;
pub mod profiler;
pub mod shader;
pub mod traffic;
pub mod warmup;

use anyhow::{Context as _, Result, anyhow};
use wgpu::util::DeviceExt;

/// The wgpu device with the limits and features this project asks for.
pub struct GpuContext {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// `adapter.get_info().name` plus driver, for stats.
    pub adapter_name: String,
    pub timestamps: bool,
    /// Multiplier on every heavy pass's work per submission (its item ranges). Software drivers
    /// (lavapipe) get 1: their submissions stay short so that none is reported as a lost device. A
    /// discrete GPU gets 256 (an integrated one 16): a lavapipe-sized submission would fill a fraction
    /// of its cores and time the launch, not the work. The images do not depend on it (tested,
    /// bit-identical). `FVPL_WORK_SCALE` overrides it.
    pub work_scale: u32,
    /// A CPU adapter (lavapipe): passes that can read their data two ways pick the one a software
    /// driver runs faster (e.g. the k-means search through textures). Results do not depend on it.
    pub software: bool,
    /// The driver: `adapter.get_info()`'s driver and driver info ("llvmpipe"'s is Mesa's version),
    /// for stats and CSVs.
    pub driver: String,
    /// The warm-up kernel (`warm_up`), built on first use.
    pub(crate) warmup: std::cell::OnceCell<warmup::Warmup>,
}

/// The driver as `adapter.get_info()` names it: "NVIDIA 580.82.07", "llvmpipe Mesa 22.3.6 (LLVM
/// 15.0.6)"; "unknown" when the backend says nothing.
pub fn driver_name(info: &wgpu::AdapterInfo) -> String {
    let s = [info.driver.trim(), info.driver_info.trim()]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    if s.is_empty() { "unknown".into() } else { s }
}

/// Storage buffers one shader stage binds at most: colom's shade pass (9 of its own and the
/// scene's 6), and other methods' passes as many. `render::every_method_runs_with_the_fewest_storage_buffers_accepted`
/// runs every method on a device with exactly this many.
pub const MIN_STORAGE_BUFFERS: u32 = 15;

fn too_few_storage_buffers(adapter: &wgpu::Adapter, limits: &wgpu::Limits) -> anyhow::Error {
    anyhow!(
        "adapter {} allows only {} storage buffers per shader stage; fuzzy-vpl needs {MIN_STORAGE_BUFFERS} (the shade pass)",
        adapter.get_info().name,
        limits.max_storage_buffers_per_shader_stage
    )
}

/// The wgpu instance fuzzy-vpl's devices come from: the primary backends (Vulkan here, lavapipe
/// without a GPU; the GL backend only adds noise), `WGPU_BACKEND` overriding.
pub fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    if std::env::var_os("WGPU_BACKEND").is_none() {
        desc.backends = wgpu::Backends::PRIMARY;
    }
    wgpu::Instance::new(desc)
}

/// The optional features fuzzy-vpl uses when the adapter has them: timestamp queries (the per-pass
/// GPU timings).
pub fn wanted_features() -> wgpu::Features {
    wgpu::Features::TIMESTAMP_QUERY
}

/// Limits requested explicitly: what our passes need, clamped to what the adapter has. lavapipe allows
/// 1024 invocations per workgroup, 32 KiB workgroup memory and 128 MiB per storage binding.
pub fn required_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    wgpu::Limits {
        max_storage_buffers_per_shader_stage: adapter.max_storage_buffers_per_shader_stage.min(16),
        max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
        max_buffer_size: adapter.max_buffer_size,
        max_compute_invocations_per_workgroup: adapter
            .max_compute_invocations_per_workgroup
            .min(1024),
        max_compute_workgroup_storage_size: adapter.max_compute_workgroup_storage_size.min(32768),
        max_compute_workgroups_per_dimension: adapter.max_compute_workgroups_per_dimension,
        max_bind_groups: adapter.max_bind_groups.min(4),
        ..Default::default()
    }
}

impl GpuContext {
    /// The most bytes one storage binding of this device holds (lavapipe: 128 MiB). Every buffer the
    /// shaders bind whole (VPLs, per-pixel lists, the visibility bit matrix, a VPL wave) is bounded
    /// by it.
    pub fn max_binding(&self) -> u64 {
        self.device.limits().max_storage_buffer_binding_size
    }

    /// Creates a headless context on the first adapter (any backend wgpu finds: Vulkan on lavapipe here).
    pub fn new_headless() -> Result<Self> {
        pollster::block_on(Self::from_instance(instance(), None))
    }

    pub async fn from_instance(
        instance: wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self> {
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: surface,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| {
                anyhow!(
                    "no GPU adapter found ({e}); on a machine without a GPU install Mesa's software Vulkan driver: apt-get install mesa-vulkan-drivers"
                )
            })?;
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < MIN_STORAGE_BUFFERS {
            return Err(too_few_storage_buffers(&adapter, &limits));
        }
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("fuzzy-vpl"),
                required_features: adapter.features() & wanted_features(),
                required_limits: required_limits(&limits),
                experimental_features: wgpu::ExperimentalFeatures::disabled(),
                memory_hints: wgpu::MemoryHints::Performance,
                trace: wgpu::Trace::Off,
            })
            .await
            .context("requesting a wgpu device")?;
        Self::from_device(instance, adapter, device, queue)
    }

    /// A context on a device the caller created (the library use: fuzzy-vpl renders inside another
    /// wgpu program). The device should have been requested with `required_limits` of its adapter's
    /// limits and, for GPU timings, `wanted_features()`; without timestamp queries the frame's
    /// timings are empty. Fails with one line when the device allows fewer storage buffers per
    /// shader stage than the shade pass binds (`MIN_STORAGE_BUFFERS`).
    pub fn from_device(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Self> {
        let info = adapter.get_info();
        let adapter_name = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
        let limits = device.limits();
        if limits.max_storage_buffers_per_shader_stage < MIN_STORAGE_BUFFERS {
            return Err(too_few_storage_buffers(&adapter, &limits));
        }
        let work_scale = std::env::var("FVPL_WORK_SCALE")
            .ok()
            .and_then(|v| v.parse::<u32>().ok())
            .filter(|&v| v >= 1)
            .unwrap_or(match info.device_type {
                wgpu::DeviceType::Cpu => 1,
                wgpu::DeviceType::DiscreteGpu => 256,
                // Integrated and unknown GPUs: smaller submissions, well inside an OS GPU watchdog.
                _ => 16,
            });
        Ok(GpuContext {
            timestamps: device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
            instance,
            adapter,
            device,
            queue,
            adapter_name,
            work_scale,
            software: info.device_type == wgpu::DeviceType::Cpu,
            driver: driver_name(&info),
            warmup: Default::default(),
        })
    }

    /// Keeps the GPU busy for at least `ms` milliseconds of work before timing (`warmup.rs`);
    /// returns the milliseconds spent.
    pub fn warm_up(&self, ms: f64) -> Result<f64> {
        self.warmup
            .get_or_init(|| warmup::Warmup::new(self))
            .run(self, ms)
    }

    /// "software" or "hardware": what a summary says of where a figure came from.
    pub fn kind(&self) -> &'static str {
        if self.software {
            "software"
        } else {
            "hardware"
        }
    }

    /// A storage buffer initialised from `data` (at least 256 bytes so an empty array still binds to any struct).
    pub fn storage_init<T: bytemuck::Pod>(&self, label: &str, data: &[T]) -> wgpu::Buffer {
        let mut bytes: Vec<u8> = bytemuck::cast_slice(data).to_vec();
        if bytes.len() < 256 {
            bytes.resize(256, 0);
        }
        traffic::uploaded(bytes.len() as u64);
        traffic::buffer_made(label);
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: &bytes,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// An uninitialised (zeroed) storage buffer of `size` bytes.
    pub fn storage(&self, label: &str, size: u64) -> wgpu::Buffer {
        traffic::buffer_made(label);
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(256),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    pub fn uniform<T: bytemuck::Pod>(&self, label: &str, value: &T) -> wgpu::Buffer {
        traffic::uploaded(std::mem::size_of::<T>() as u64);
        traffic::buffer_made(label);
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            })
    }

    /// Writes `data` into `buffer` at `offset` (counted as uploaded: `traffic`).
    pub fn write_buffer(&self, buffer: &wgpu::Buffer, offset: u64, data: &[u8]) {
        traffic::uploaded(data.len() as u64);
        self.queue.write_buffer(buffer, offset, data);
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map_err(|e| anyhow!("GPU wait failed: {e}"))?;
        Ok(())
    }

    /// Copies a buffer back to the CPU (`read_buffer`).
    pub fn read_buffer<T: bytemuck::Pod>(
        &self,
        buffer: &wgpu::Buffer,
        count: usize,
    ) -> Result<Vec<T>> {
        read_buffer(&self.device, &self.queue, buffer, count)
    }
}

/// Copies the first `count` elements of a buffer (`COPY_SRC` usage) back to the CPU, waiting for
/// the device; the bytes count in `traffic`.
pub fn read_buffer<T: bytemuck::Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
    count: usize,
) -> Result<Vec<T>> {
    let size = (count * std::mem::size_of::<T>()) as u64;
    if size == 0 {
        return Ok(Vec::new());
    }
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    queue.submit([enc.finish()]);
    let out = mapped(device, &staging, "a readback buffer", |view| {
        bytemuck::cast_slice::<u8, T>(view).to_vec()
    })?;
    traffic::read_back(size);
    Ok(out)
}

/// Maps `buffer` (`MAP_READ`, its copies submitted) for reading, waits for the device, and hands
/// its bytes to `read`; unmaps it after. `what` names the buffer in the errors.
pub fn mapped<R>(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    what: &str,
    read: impl FnOnce(&[u8]) -> R,
) -> Result<R> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .map_err(|e| anyhow!("GPU wait failed: {e}"))?;
    rx.recv()
        .map_err(|_| anyhow!("readback callback dropped"))?
        .map_err(|e| anyhow!("mapping {what} failed: {e}"))?;
    let view = slice
        .get_mapped_range()
        .map_err(|e| anyhow!("reading {what} failed: {e}"))?;
    let out = read(&view);
    drop(view);
    buffer.unmap();
    Ok(out)
}

/// Copies a whole 2D texture (`COPY_SRC` usage, a format with a fixed texel size) back to the CPU:
/// its texels row by row from the top, without the copy's row padding.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<u8>> {
    let (w, h) = (texture.width(), texture.height());
    let texel = texture
        .format()
        .block_copy_size(None)
        .ok_or_else(|| anyhow!("texture format {:?} has no texel size", texture.format()))?;
    let tight = w * texel;
    let row =
        tight.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([enc.finish()]);
    let out = mapped(device, &buffer, "the texture readback", |view| {
        let mut out = Vec::with_capacity((tight * h) as usize);
        for y in 0..h as usize {
            out.extend_from_slice(&view[y * row as usize..][..tight as usize]);
        }
        out
    })?;
    traffic::read_back(row as u64 * h as u64);
    Ok(out)
}

/// Number of workgroups of `size` covering `n` items.
pub fn groups(n: u32, size: u32) -> u32 {
    n.div_ceil(size)
}

/// The bind group entries of a group whose bindings 0, 1, … are `buffers`, each bound whole,
/// followed by `views` (texture views) at the next bindings.
pub fn bind_entries<'a>(
    buffers: &[&'a wgpu::Buffer],
    views: &[&'a wgpu::TextureView],
) -> Vec<wgpu::BindGroupEntry<'a>> {
    let buffers = buffers.iter().map(|b| b.as_entire_binding());
    let views = views.iter().map(|v| wgpu::BindingResource::TextureView(v));
    buffers
        .chain(views)
        .enumerate()
        .map(|(i, resource)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource,
        })
        .collect()
}

/// A 2D texture of `(width, height)` pixels, one mip level, one sample.
pub fn texture_2d(
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
