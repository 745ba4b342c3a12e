//! A frame's final radiance written into a caller's texture (`Renderer::render_to_texture`): the
//! frame's direct and indirect buffers summed on the GPU into an `Rgba32Float` storage texture, as
//! `GpuFrame::read` sums them on the CPU (`shaders-wgsl/compose.wgsl`). Nothing goes through the CPU
//! but a 32-byte uniform.

use bytemuck::{Pod, Zeroable};

use super::scene_gpu::{storage_layout, storage_texture_layout, uniform_layout};
use crate::gpu::GpuContext;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ComposeParams {
    size: [u32; 4],
    scale: [f32; 4],
}

/// A frame's light on the GPU, as the renderer hands it over: emission + direct and the indirect
/// light (a vec4 an image pixel each, render units) at the image's size, and the factor to the
/// scene's units.
pub struct FrameLight<'a> {
    pub direct: &'a wgpu::Buffer,
    pub indirect: &'a wgpu::Buffer,
    pub size: (u32, u32),
    pub output_scale: f32,
}

pub struct Compose {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// For a caller's texture without `STORAGE_BINDING`: the pass writes this one, of the same size,
    /// and a GPU copy moves it over (made once a size).
    scratch: std::cell::RefCell<Option<wgpu::Texture>>,
}

impl Compose {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let (layout, [pipeline]) = crate::gpu::shader::compute_pipelines(
            device,
            "compose",
            &[
                uniform_layout(0),
                storage_layout(1, true),
                storage_layout(2, true),
                storage_texture_layout(3, wgpu::TextureFormat::Rgba32Float),
            ],
            ["compose"],
        );
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("compose params"),
            size: std::mem::size_of::<ComposeParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Compose {
            pipeline,
            layout,
            params,
            scratch: Default::default(),
        }
    }

    /// Writes a frame's final radiance (its `light` at its `size`) into `texture` (`Rgba32Float`,
    /// the frame's size, with `STORAGE_BINDING` or `COPY_DST` usage) and submits.
    pub fn record(&self, ctx: &GpuContext, light: &FrameLight, texture: &wgpu::Texture) {
        let (w, h) = light.size;
        let direct = texture
            .usage()
            .contains(wgpu::TextureUsages::STORAGE_BINDING);
        let mut scratch = self.scratch.borrow_mut();
        if !direct && scratch.as_ref().is_none_or(|t| t.size() != texture.size()) {
            *scratch = Some(crate::gpu::texture_2d(
                &ctx.device,
                "compose scratch",
                (texture.width(), texture.height()),
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
            ));
        }
        let target = if direct {
            texture
        } else {
            scratch.as_ref().expect("made above")
        };
        let p = ComposeParams {
            size: [w, h, 0, 0],
            scale: [light.output_scale, 0.0, 0.0, 0.0],
        };
        ctx.write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        let view = target.create_view(&Default::default());
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("compose"),
            layout: &self.layout,
            entries: &crate::gpu::bind_entries(
                &[&self.params, light.direct, light.indirect],
                &[&view],
            ),
        });
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("compose"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
        if !direct {
            enc.copy_texture_to_texture(
                target.as_image_copy(),
                texture.as_image_copy(),
                texture.size(),
            );
        }
        ctx.queue.submit([enc.finish()]);
    }
}
