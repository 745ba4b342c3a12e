//! A compute kernel with bounded dispatches: bind group 0 is the scene, group 1 the pass's own
//! resources with the `Chunk` uniform (`shaders-wgsl/common/chunk.wgsl`) at binding 0. A heavy pass runs
//! as several submissions over item ranges so no single submission runs long (software drivers report a
//! long one as a lost device).

use bytemuck::{Pod, Zeroable};

use super::scene_gpu::{SceneGpu, uniform_layout};
use crate::gpu::{GpuContext, profiler::Profiler, shader};

pub const WORKGROUP: u32 = 64;
/// The most workgroups one dispatch row holds (WebGPU's guaranteed minimum per dimension).
const MAX_GROUPS_X: u32 = 65535;

/// What every pass records with: the device, the scene (bind group 0) and the GPU timer.
pub struct Gpu<'a> {
    pub ctx: &'a GpuContext,
    pub scene: &'a SceneGpu,
    pub profiler: &'a mut Profiler,
}

/// One run of a kernel: its profiler label, the pass's bind group (group 1) and the seed its
/// `Chunk` carries.
#[derive(Clone, Copy)]
pub struct Run<'a> {
    pub label: &'a str,
    pub group: &'a wgpu::BindGroup,
    pub seed: u32,
}

/// An entry point `Kernel::run_2d_after` dispatches before each submission's main one, over
/// `invocations(count, sub_count)` invocations (the submission's items and sub range).
#[derive(Clone, Copy)]
pub struct Before<'a> {
    pub entry: &'a str,
    pub invocations: &'a dyn Fn(u32, u32) -> u32,
}

/// Records copies between the passes of `Kernel::run_entries`.
pub type RecordCopies<'a> = dyn Fn(&mut wgpu::CommandEncoder) + 'a;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Chunk {
    pub offset: u32,
    pub count: u32,
    pub seed: u32,
    pub _pad: u32,
    pub sub_offset: u32,
    pub sub_count: u32,
    pub _pad2: [u32; 2],
}

/// Width in texels of the per-frame data textures (as the scene's, `TEXEL_ROW`).
pub const DATA_ROW: u32 = super::scene_gpu::TEXEL_ROW;

/// A `DATA_ROW`-wide 2D texture of `format` (an uncompressed colour format) with room for `texels`
/// texels; texel i is at (i % DATA_ROW, i / DATA_ROW). Fill it with `copy_to_texture`.
pub fn data_texture(
    ctx: &GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    texels: u64,
) -> wgpu::Texture {
    let rows = (texels.max(1) as u32).div_ceil(DATA_ROW);
    crate::gpu::traffic::buffer_made(label);
    ctx.device
        .create_texture(&super::scene_gpu::data_texture_descriptor(
            label, format, rows,
        ))
}

/// A resource a pass keeps from frame to frame (`DataTextureSlot`, `StorageSlot`): made again only
/// when the kept one no longer fits.
struct Kept<T: Clone>(std::sync::Mutex<Option<T>>);

impl<T: Clone> Kept<T> {
    const fn new() -> Self {
        Kept(std::sync::Mutex::new(None))
    }

    /// The kept resource when `fits` says it does, else a new one from `make`, kept from now on.
    fn get(&self, fits: impl FnOnce(&T) -> bool, make: impl FnOnce() -> T) -> T {
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match &*kept {
            Some(r) if fits(r) => r.clone(),
            _ => {
                let r = make();
                *kept = Some(r.clone());
                r
            }
        }
    }
}

/// A pass's data texture kept from frame to frame: made again only when it needs more rows.
pub struct DataTextureSlot {
    label: &'static str,
    format: wgpu::TextureFormat,
    kept: Kept<(wgpu::Texture, wgpu::TextureView)>,
}

impl DataTextureSlot {
    pub const fn new(label: &'static str, format: wgpu::TextureFormat) -> Self {
        DataTextureSlot {
            label,
            format,
            kept: Kept::new(),
        }
    }

    /// A texture of at least `texels` texels and its view.
    pub fn get(&self, ctx: &GpuContext, texels: u64) -> (wgpu::Texture, wgpu::TextureView) {
        let rows = (texels.max(1) as u32).div_ceil(DATA_ROW);
        self.kept.get(
            |(t, _)| t.height() >= rows,
            || {
                let t = data_texture(ctx, self.label, self.format, texels);
                let v = t.create_view(&Default::default());
                (t, v)
            },
        )
    }
}

/// A pass's storage buffer kept from frame to frame: made again only when it needs more bytes.
pub struct StorageSlot {
    label: &'static str,
    kept: Kept<wgpu::Buffer>,
}

impl StorageSlot {
    pub const fn new(label: &'static str) -> Self {
        StorageSlot {
            label,
            kept: Kept::new(),
        }
    }

    /// A storage buffer of at least `bytes` bytes.
    pub fn get(&self, ctx: &GpuContext, bytes: u64) -> wgpu::Buffer {
        self.kept
            .get(|b| b.size() >= bytes, || ctx.storage(self.label, bytes))
    }
}

/// Records a copy of the first `bytes` bytes of `src` into `tex` (a `data_texture`), texel by texel.
pub fn copy_to_texture(
    enc: &mut wgpu::CommandEncoder,
    src: &wgpu::Buffer,
    tex: &wgpu::Texture,
    bytes: u64,
) {
    let texel_bytes = tex.format().block_copy_size(None).expect("a colour format");
    let texels = (bytes / texel_bytes as u64) as u32;
    let row_bytes = DATA_ROW * texel_bytes;
    // Whole rows, then the partial last row.
    let full = texels / DATA_ROW;
    let rest = texels % DATA_ROW;
    let mut copy = |y: u32, w: u32, h: u32| {
        enc.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer: src,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: y as u64 * row_bytes as u64,
                    bytes_per_row: Some(row_bytes),
                    rows_per_image: None,
                },
            },
            wgpu::TexelCopyTextureInfo {
                texture: tex,
                mip_level: 0,
                origin: wgpu::Origin3d { x: 0, y, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
    };
    if full > 0 {
        copy(0, DATA_ROW, full);
    }
    if rest > 0 {
        copy(full, rest, 1);
    }
}

pub struct Kernel {
    pub name: &'static str,
    /// One pipeline per entry point of the shader, in the order given; the first is `run`'s.
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
    pub layout: wgpu::BindGroupLayout,
    /// Whether group 0 is the scene (kernels on plain data, such as k-means, leave it empty).
    uses_scene: bool,
    chunk: wgpu::Buffer,
}

impl Kernel {
    /// Builds the pipeline of `shaders-wgsl/<name>.wgsl` (entry point `main`); `entries` are group 1's
    /// bindings from 1 on.
    pub fn new(
        ctx: &GpuContext,
        scene: &SceneGpu,
        name: &'static str,
        entries: &[wgpu::BindGroupLayoutEntry],
        extra_constants: &[(&'static str, f64)],
    ) -> Kernel {
        Self::with_entries(ctx, Some(scene), name, &["main"], entries, extra_constants)
    }

    /// Pipelines for several entry points sharing group 1's layout. With `scene: None` group 0 stays
    /// empty (the shader must not import `common/scene.wgsl`).
    pub fn with_entries(
        ctx: &GpuContext,
        scene: Option<&SceneGpu>,
        name: &'static str,
        entry_points: &[&'static str],
        entries: &[wgpu::BindGroupLayoutEntry],
        extra_constants: &[(&'static str, f64)],
    ) -> Kernel {
        let mut all = vec![uniform_layout(0)];
        all.extend_from_slice(entries);
        let layout = ctx
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(name),
                entries: &all,
            });
        let pl = ctx
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(name),
                bind_group_layouts: &[scene.map(|s| &s.layout), Some(&layout)],
                immediate_size: 0,
            });
        let module = shader::module(&ctx.device, name);
        let mut constants = scene.map(|s| s.overrides()).unwrap_or_default();
        constants.extend_from_slice(extra_constants);
        let pipelines = entry_points
            .iter()
            .map(|&entry| {
                let p = ctx
                    .device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&pl),
                        module: &module,
                        entry_point: Some(entry),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants: &constants,
                            zero_initialize_workgroup_memory: true,
                        },
                        cache: None,
                    });
                (entry, p)
            })
            .collect();
        let chunk = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("chunk"),
            size: std::mem::size_of::<Chunk>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Kernel {
            name,
            pipelines,
            layout,
            uses_scene: scene.is_some(),
            chunk,
        }
    }

    /// Group 1 bind group: binding 0 is the chunk uniform, the rest as given (binding, buffer).
    pub fn bind_group(
        &self,
        ctx: &GpuContext,
        buffers: &[(u32, &wgpu::Buffer)],
    ) -> wgpu::BindGroup {
        self.bind_group_with_textures(ctx, buffers, &[])
    }

    /// Like `bind_group`, with texture views (binding, view) as well.
    pub fn bind_group_with_textures(
        &self,
        ctx: &GpuContext,
        buffers: &[(u32, &wgpu::Buffer)],
        textures: &[(u32, &wgpu::TextureView)],
    ) -> wgpu::BindGroup {
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: self.chunk.as_entire_binding(),
        }];
        for (b, buf) in buffers {
            entries.push(wgpu::BindGroupEntry {
                binding: *b,
                resource: buf.as_entire_binding(),
            });
        }
        for (b, view) in textures {
            entries.push(wgpu::BindGroupEntry {
                binding: *b,
                resource: wgpu::BindingResource::TextureView(view),
            });
        }
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.name),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// Runs the kernel over items `0..total` in submissions of at most `per_chunk` items, timing each
    /// under `label`. `progress` is called after each submission with (done, total).
    pub fn run(
        &self,
        g: &mut Gpu,
        r: Run,
        total: u32,
        per_chunk: u32,
        progress: &mut dyn FnMut(u32, u32),
    ) {
        self.run_2d(g, r, (total, per_chunk), (1, 1), &mut |done, all| {
            progress(done as u32, all as u32);
            true
        })
    }

    /// Runs entry point `entry` over `total` items in one submission (small kernels: k-means steps).
    pub fn run_entry(&self, g: &mut Gpu, r: Run, entry: &str, total: u32) {
        let index = self.entry_index(entry);
        self.submit(g, r, (None, index), total, (0, 1), 0);
    }

    /// Runs several small steps `(entry, items)` in order in one submission, then waits. The steps
    /// are dispatches of one compute pass timed under `label` (wgpu puts a barrier between
    /// dispatches that share a writable buffer); the pass ends after step `after.0` so that
    /// `after.1` can record copies, and a new one starts. With `FVPL_PROFILE_STEPS` set each step is
    /// its own pass timed under `label.entry` (a diagnosis aid: every pass then adds its own start
    /// and end to the total). The chunk covers every invocation (offset 0, no count limit): each
    /// entry point must bound its items itself. For light work only (k-means steps).
    pub fn run_entries(
        &self,
        g: &mut Gpu,
        r: Run,
        steps: &[(&str, u32)],
        after: Option<(&str, &RecordCopies)>,
    ) {
        let (ctx, label) = (g.ctx, r.label);
        self.write_chunk(ctx, 0, u32::MAX, (0, 1), r.seed);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let detail = std::env::var_os("FVPL_PROFILE_STEPS").is_some();
        let ends_pass = |entry: &str| detail || after.is_some_and(|(e, _)| e == entry);
        let mut first = 0;
        while first < steps.len() {
            let mut last = first;
            while last + 1 < steps.len() && !ends_pass(steps[last].0) {
                last += 1;
            }
            let name = if detail {
                format!("{label}.{}", steps[first].0)
            } else {
                label.to_string()
            };
            self.in_pass(&mut enc, g, Run { label: &name, ..r }, |pass| {
                for &(entry, total) in &steps[first..=last] {
                    pass.set_pipeline(&self.pipelines[self.entry_index(entry)].1);
                    dispatch_items(pass, total);
                }
            });
            if let Some((entry, record)) = after
                && entry == steps[last].0
            {
                record(&mut enc);
            }
            first = last + 1;
        }
        g.profiler.submit(ctx, enc);
        let _ = ctx.wait();
    }

    /// Like `run`, over items × a second range (`sub`: total, per chunk), e.g. pixels × VPLs. Each
    /// submission covers one item range and one sub range; `progress` gets (chunks done, chunks) and
    /// returns whether to go on (false stops before the next submission).
    pub fn run_2d(
        &self,
        g: &mut Gpu,
        r: Run,
        items: (u32, u32),
        sub: (u32, u32),
        progress: &mut dyn FnMut(u64, u64) -> bool,
    ) {
        self.run_2d_after(g, r, items, sub, None, progress)
    }

    /// `run_2d`, where each submission first dispatches `before`'s entry point (the same chunk
    /// uniform), then the first entry point (in one compute pass: wgpu puts a barrier between
    /// dispatches that share a writable buffer).
    pub fn run_2d_after(
        &self,
        g: &mut Gpu,
        r: Run,
        items: (u32, u32),
        sub: (u32, u32),
        before: Option<Before>,
        progress: &mut dyn FnMut(u64, u64) -> bool,
    ) {
        let (total, per_chunk) = items;
        let per_chunk = chunk_items(g.ctx, total, per_chunk);
        let (sub_total, sub_per) = (sub.0, sub.1.max(1));
        let before = before.map(|b| (self.entry_index(b.entry), b.invocations));
        let chunks = total.div_ceil(per_chunk) as u64 * sub_total.div_ceil(sub_per).max(1) as u64;
        let mut done = 0u64;
        let mut offset = 0;
        while offset < total {
            let count = per_chunk.min(total - offset);
            let mut sub_offset = 0;
            loop {
                let sub_count = sub_per.min(sub_total.saturating_sub(sub_offset));
                let first = before.map(|(index, n)| (index, n(count, sub_count)));
                self.submit(g, r, (first, 0), count, (sub_offset, sub_count), offset);
                done += 1;
                if !progress(done, chunks) {
                    return;
                }
                sub_offset += sub_count;
                if sub_offset >= sub_total {
                    break;
                }
            }
            offset += count;
        }
    }

    /// One bounded submission of pipeline `pipelines.1` over items `offset..offset + count`, after
    /// `pipelines.0` (index, invocations) when given, in the same pass with the same chunk.
    fn submit(
        &self,
        g: &mut Gpu,
        r: Run,
        pipelines: (Option<(usize, u32)>, usize),
        count: u32,
        sub: (u32, u32),
        offset: u32,
    ) {
        let ctx = g.ctx;
        self.write_chunk(ctx, offset, count, sub, r.seed);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        self.in_pass(&mut enc, g, r, |pass| {
            if let Some((first, invocations)) = pipelines.0 {
                pass.set_pipeline(&self.pipelines[first].1);
                dispatch_items(pass, invocations);
            }
            pass.set_pipeline(&self.pipelines[pipelines.1].1);
            dispatch_items(pass, count);
        });
        g.profiler.submit(ctx, enc);
        // Waiting keeps each submission short and bounded on software drivers.
        let _ = ctx.wait();
    }

    /// Sets the `Chunk` uniform the next submission's passes read: items `offset..offset + count`,
    /// sub range `sub` (offset, count).
    fn write_chunk(&self, ctx: &GpuContext, offset: u32, count: u32, sub: (u32, u32), seed: u32) {
        let c = Chunk {
            offset,
            count,
            seed,
            _pad: 0,
            sub_offset: sub.0,
            sub_count: sub.1,
            _pad2: [0; 2],
        };
        ctx.write_buffer(&self.chunk, 0, bytemuck::bytes_of(&c));
    }

    fn entry_index(&self, entry: &str) -> usize {
        self.pipelines
            .iter()
            .position(|(e, _)| *e == entry)
            .unwrap_or_else(|| panic!("{}: no entry point {entry}", self.name))
    }

    /// Records `f` in a compute pass timed under `label` with the scene's and the pass's bind
    /// groups set.
    fn in_pass(
        &self,
        enc: &mut wgpu::CommandEncoder,
        g: &mut Gpu,
        r: Run,
        f: impl FnOnce(&mut wgpu::ComputePass<'_>),
    ) {
        let scene = g.scene;
        g.profiler.compute_pass(enc, r.label, |pass| {
            if self.uses_scene {
                pass.set_bind_group(0, &scene.bind_group, &[]);
            }
            pass.set_bind_group(1, r.group, &[]);
            f(pass)
        })
    }
}

/// The items a submission of `Kernel::run_2d` covers, given `per_chunk` (at least one workgroup):
/// scaled by the adapter's work scale on the item range only (a pass that sums over the sub range,
/// the reference: each VPL range adds to the pixel, keeps its ranges, so its rounding, and the
/// image, do not depend on the scale), at most `total` and one dispatch's. A multiple of 64 when
/// `per_chunk` and `total` are.
pub fn chunk_items(ctx: &GpuContext, total: u32, per_chunk: u32) -> u32 {
    let per_chunk = per_chunk.clamp(WORKGROUP, WORKGROUP * MAX_GROUPS_X);
    let scale = ctx.work_scale.max(1) as u64;
    (per_chunk as u64 * scale)
        .min(total.max(1) as u64)
        .min((WORKGROUP * MAX_GROUPS_X) as u64)
        .max(per_chunk as u64) as u32
}

/// Workgroups for `count` invocations, in rows of 65535 groups.
fn dispatch_items(pass: &mut wgpu::ComputePass, count: u32) {
    let groups = count.div_ceil(WORKGROUP).max(1);
    pass.dispatch_workgroups(groups.min(MAX_GROUPS_X), groups.div_ceil(MAX_GROUPS_X), 1);
}
