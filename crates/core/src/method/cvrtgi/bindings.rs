//! cvrtgi's bind group: its layout (`entries`), the buffers of one group (`Bindings`), the lights'
//! words the gathering reads, and a run over the voxel faces.

use crate::gi::dispatch::{Gpu, Kernel, Run};
use crate::gi::scene_gpu::{storage_layout, uniform_layout};
use crate::gpu::GpuContext;

use super::inject::Lighting;

pub(super) fn entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    vec![
        uniform_layout(1),
        storage_layout(2, true),
        storage_layout(3, true),
        storage_layout(4, true),
        storage_layout(5, false),
        storage_layout(6, true),
        storage_layout(7, false),
        storage_layout(8, true),
        storage_layout(9, false),
    ]
}

/// The buffers of one bind group (a binding the entry point does not use gets a small buffer of
/// its own: one buffer may not be bound read-only and writable in one dispatch).
pub(super) struct Bindings<'a> {
    pub(super) params: &'a wgpu::Buffer,
    pub(super) voxels: &'a wgpu::Buffer,
    pub(super) faces: &'a wgpu::Buffer,
    pub(super) lights: Option<&'a wgpu::Buffer>,
    pub(super) vis: Option<&'a wgpu::Buffer>,
    pub(super) irr_in: Option<&'a wgpu::Buffer>,
    pub(super) out: Option<&'a wgpu::Buffer>,
    pub(super) gbuffer: Option<&'a wgpu::Buffer>,
    pub(super) vis_w: Option<&'a wgpu::Buffer>,
}

/// The lights' words as the gathering reads them: each cluster's words, then each lit voxel's
/// position, normal and flux (one zero word where there is none).
pub(super) fn light_words(l: &Lighting) -> Vec<[f32; 4]> {
    let mut words: Vec<[f32; 4]> = l.clusters.iter().flatten().copied().collect();
    for v in &l.lit {
        words.extend([v.pos, v.nrm, v.flux]);
    }
    if words.is_empty() {
        words.push([0.0; 4]);
    }
    words
}

/// Runs kernel `k` over the `faces` voxel faces (none: nothing), 2^14 faces a submission.
pub(super) fn run_faces(
    k: &Kernel,
    g: &mut Gpu,
    label: &'static str,
    group: &wgpu::BindGroup,
    faces: u32,
) {
    if faces > 0 {
        let run = Run {
            label,
            group,
            seed: 0,
        };
        k.run(g, run, faces, 1 << 14, &mut |_, _| {});
    }
}

impl Bindings<'_> {
    pub(super) fn group(&self, ctx: &GpuContext, k: &Kernel) -> wgpu::BindGroup {
        let dummy: Vec<wgpu::Buffer> = (0..6).map(|_| ctx.storage("cvrtgi unused", 16)).collect();
        let opt = [
            self.lights,
            self.vis,
            self.irr_in,
            self.out,
            self.gbuffer,
            self.vis_w,
        ];
        let mut list: Vec<(u32, &wgpu::Buffer)> =
            vec![(1, self.params), (2, self.voxels), (3, self.faces)];
        for (i, b) in opt.iter().enumerate() {
            list.push((4 + i as u32, b.unwrap_or(&dummy[i])));
        }
        k.bind_group(ctx, &list)
    }
}
