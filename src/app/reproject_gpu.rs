//! The reprojection of the shared display path on the GPU (`shaders-wgsl/reproject.wgsl`): the last
//! frame as displayed, shown from the current camera while the next one renders, from the frame's
//! own G-buffer on the window's device; nothing read back. The split path keeps the CPU warp
//! (`reproject.rs`), whose frame is on the CPU anyway. CPU twin: `cpu::reproject`.

use bytemuck::{Pod, Zeroable};

use crate::gi::primary::CameraParams;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ReprojectParams {
    old: CameraParams,
    new: CameraParams,
}

/// The most workgroups a dimension of a dispatch has (WebGPU's default limit).
const MAX_GROUPS: u32 = 65535;

pub struct Reproject {
    clear: wgpu::ComputePipeline,
    splat_depth: wgpu::ComputePipeline,
    splat_source: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// Per new pixel: depth and source (made again when the size changes), and the output.
    scratch: Option<(wgpu::Buffer, wgpu::Buffer, u32)>,
    target: Option<super::display::Target>,
}

impl Reproject {
    pub fn new(device: &wgpu::Device) -> Self {
        use crate::gi::scene_gpu::{
            data_texture_layout, storage_layout, storage_texture_layout, uniform_layout,
        };
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let (layout, [clear, splat_depth, splat_source, resolve]) =
            crate::gpu::shader::compute_pipelines(
                device,
                "reproject",
                &[
                    uniform_layout(0),
                    storage_layout(1, true),
                    storage_layout(2, false),
                    storage_layout(3, false),
                    data_texture_layout(4, float),
                    storage_texture_layout(5, wgpu::TextureFormat::Rgba8Unorm),
                ],
                ["clear", "splat_depth", "splat_source", "resolve"],
            );
        Reproject {
            clear,
            splat_depth,
            splat_source,
            resolve,
            layout,
            params: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("reproject params"),
                size: std::mem::size_of::<ReprojectParams>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            scratch: None,
            target: None,
        }
    }

    pub fn target(&self) -> Option<&super::display::Target> {
        self.target.as_ref()
    }

    /// Records the reprojection of `image` (the old frame as displayed: an `Rgba8Unorm` texture
    /// with `TEXTURE_BINDING`, of `old`'s size) with its G-buffer (4 vec4s a pixel, render units)
    /// from camera `old` to `new` (render units, the same size) into `enc`. Returns true when the
    /// output texture was made again (an egui registration must be updated).
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        enc: &mut wgpu::CommandEncoder,
        image: &wgpu::Texture,
        gbuffer: &wgpu::Buffer,
        (old, new): (&CameraParams, &CameraParams),
    ) -> bool {
        let (w, h) = (old.size[0], old.size[1]);
        let n = w * h;
        let p = ReprojectParams {
            old: *old,
            new: CameraParams {
                size: old.size,
                ..*new
            },
        };
        crate::gpu::traffic::uploaded(std::mem::size_of::<ReprojectParams>() as u64);
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        if self.scratch.as_ref().is_none_or(|s| s.2 != n) {
            let b = |label| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: (n as u64 * 4).max(256),
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                })
            };
            self.scratch = Some((b("reproject depth"), b("reproject source"), n));
        }
        let remade = self.target.as_ref().is_none_or(|t| t.size != (w, h));
        if remade {
            self.target = Some(super::display::Target::new(device, (w, h), "reproject"));
        }
        let (depth, source, _) = self.scratch.as_ref().expect("made above");
        let out = self.target.as_ref().expect("made above");
        let old_view = image.create_view(&wgpu::TextureViewDescriptor {
            usage: Some(wgpu::TextureUsages::TEXTURE_BINDING),
            ..Default::default()
        });
        let out_view = out.storage_view();
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("reproject"),
            layout: &self.layout,
            entries: &crate::gpu::bind_entries(
                &[&self.params, gbuffer, depth, source],
                &[&old_view, &out_view],
            ),
        });
        let groups = n.div_ceil(64).max(1);
        let grid = (groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS));
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("reproject"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, &group, &[]);
        for p in [&self.clear, &self.splat_depth, &self.splat_source] {
            pass.set_pipeline(p);
            pass.dispatch_workgroups(grid.0, grid.1, 1);
        }
        pass.set_pipeline(&self.resolve);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        remade
    }
}
