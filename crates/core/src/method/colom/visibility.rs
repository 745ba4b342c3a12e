//! Step 5: a shadow ray per (SP-cluster representative, light) pair into a bit matrix
//! (`shaders-wgsl/visibility.wgsl`).

use crate::gi::dispatch::{Gpu, Run};
use crate::gi::dispatch::{Kernel, copy_to_texture};
use crate::gi::pass::Pass;
use crate::gi::scene_gpu::{SceneGpu, data_texture_layout, storage_layout, uniform_layout};
use crate::gpu::GpuContext;

crate::gpu::shader::gpu_struct! {
    /// `visibility.wgsl`'s parameters.
    pub(crate) struct VisParams {
        num_sp_clusters: u32,
        num_lights: u32,
        /// Words per row: ceil(num_lights / 32).
        words: u32,
        /// Rows of the previous frame's matrix (same lights) whose kept representatives may be
        /// copied instead of traced: 0 for none (temporal reuse off, or the lights changed).
        reuse_rows: u32,
        /// 1: skip pairs that do not face each other (`--visibility-facing on`, not in the
        /// paper); 0: V is pure visibility, as the paper's (the default).
        facing: u32,
        _pad0: u32,
        _pad1: u32,
        _pad2: u32,
    }
}

/// The previous frame's visibility matrix, for rows a warm start may copy (the light list must be
/// the same one).
pub struct Previous {
    pub bits: std::sync::Arc<wgpu::Buffer>,
    pub rows: u32,
    pub words: u32,
}

pub struct Visibility {
    kernel: Kernel,
    params: crate::gpu::persistent::Uniform<VisParams>,
    /// Bound where there is no previous matrix (made once).
    none: std::sync::OnceLock<wgpu::Buffer>,
    /// Bit matrices by size: a frame's stays held while the next one may copy its rows.
    bits: crate::gpu::persistent::Pool<u64, wgpu::Buffer>,
    lights: crate::gi::dispatch::DataTextureSlot,
}

/// What step 5 reads: the SP-cluster representatives (`kmeans.wgsl` `rep_points`, `k_sp` of them),
/// the lights (`num_lights` VPLs or VPL-cluster representatives), the previous frame's matrix whose
/// rows a warm start may copy, and `facing`: skip (bit 0) pairs whose representatives do not face
/// each other (`ClusterSettings::visibility_facing`); off, V is pure visibility, as in the paper.
#[derive(Clone, Copy)]
pub struct VisInputs<'a> {
    pub rep_points: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    pub num_lights: u32,
    pub k_sp: u32,
    pub previous: Option<&'a Previous>,
    pub facing: bool,
}

impl Visibility {
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Self {
        let entries = [
            uniform_layout(1),
            storage_layout(2, true),
            data_texture_layout(4, wgpu::TextureSampleType::Float { filterable: false }),
            storage_layout(5, false),
            storage_layout(6, true),
        ];
        Visibility {
            kernel: Kernel::new(ctx, scene, "visibility", &entries, &[]),
            params: crate::gpu::persistent::Uniform::new("visibility params"),
            none: Default::default(),
            bits: Default::default(),
            lights: crate::gi::dispatch::DataTextureSlot::new(
                "visibility lights",
                wgpu::TextureFormat::Rgba32Float,
            ),
        }
    }

    /// Returns the bit matrix (`k_sp` rows of ceil(num_lights / 32) words) and the words per row.
    pub fn record(&self, g: &mut Gpu, i: &VisInputs) -> (std::sync::Arc<wgpu::Buffer>, u32) {
        let VisInputs {
            rep_points,
            lights,
            num_lights,
            k_sp,
            previous,
            facing,
        } = *i;
        let ctx = g.ctx;
        let words = num_lights.div_ceil(32).max(1);
        let params = self.params.set(
            ctx,
            &VisParams {
                num_sp_clusters: k_sp,
                num_lights,
                words,
                reuse_rows: previous
                    .filter(|p| p.words == words)
                    .map_or(0, |p| p.rows.min(k_sp)),
                facing: facing as u32,
                _pad0: 0,
                _pad1: 0,
                _pad2: 0,
            },
        );
        let none = self.none.get_or_init(|| ctx.storage("no previous bits", 4));
        let prev_bits = previous.map_or(none, |p| &*p.bits);
        // Every word is written (a bit per pair), so a matrix reused from the pool needs no clear.
        let size = k_sp as u64 * words as u64 * 4;
        let (bits, _) = self
            .bits
            .take(&size, || ctx.storage("visibility bits", size));
        // The lights as a texture (3 texels each; see visibility.wgsl).
        let n = num_lights as u64;
        let (tex, view) = self.lights.get(ctx, 3 * n);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        copy_to_texture(&mut enc, lights, &tex, 48 * n);
        ctx.queue.submit([enc.finish()]);
        let bg = self.kernel.bind_group_with_textures(
            ctx,
            &[(1, params), (2, rep_points), (5, &bits), (6, prev_bits)],
            &[(4, &view)],
        );
        // About 2^20 rays per submission (32 per item).
        let run = Run {
            label: Pass::Visibility.name(),
            group: &bg,
            seed: 0,
        };
        self.kernel
            .run(g, run, k_sp * words, 1 << 15, &mut |_, _| {});
        (bits, words)
    }
}
