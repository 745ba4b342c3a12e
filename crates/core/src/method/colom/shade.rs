//! Step 6: Eq. (6) per pixel with Ṽ of Eq. (8) or (9) (`shaders-wgsl/shade.wgsl`); CPU twin in
//! `cpu::shade`.

use std::cell::OnceCell;

use bytemuck::{Pod, Zeroable};

use crate::gi::dispatch::{Gpu, Run};
use crate::gi::dispatch::{Kernel, copy_to_texture};
use crate::gi::pass::Pass;
use crate::gi::scene_gpu::{SceneGpu, data_texture_layout, storage_layout, uniform_layout};
use crate::gpu::GpuContext;
use crate::settings::{ClusterLight, MAX_F};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadeParams {
    pub num_lights: u32,
    pub words: u32,
    pub f: u32,
    pub weighted: u32,
    pub d_min2: f32,
    pub _pad: [u32; 3],
}

/// The inputs of one shading dispatch.
pub struct ShadeInputs<'a> {
    pub gbuffer: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    pub bits: &'a wgpu::Buffer,
    pub assign: &'a wgpu::Buffer,
    pub weights: &'a wgpu::Buffer,
    pub indirect: &'a wgpu::Buffer,
    pub pixels: u32,
    pub params: ShadeParams,
    /// How the lights reach a pixel (`--cluster-light`).
    pub light: ClusterLight,
}

/// The most bit words (32 lights each) one invocation walks per dispatch: 16,384 lights, so the
/// paper's settings (at most 8,192 lights) shade in one dispatch per pixel range as before.
pub const WORDS_PER_DISPATCH: u32 = 512;

/// The most visibility patterns a word's table holds (`MAX_PATTERNS` in shade.wgsl).
pub const MAX_PATTERNS: u32 = 8;

/// `FVPL_SHADE_PATTERNS`, `patterns`' variable: 0..=`MAX_PATTERNS` (`method::ENV_INTEGERS`).
pub const PATTERNS_ENV: crate::method::EnvInteger = crate::method::EnvInteger {
    name: "FVPL_SHADE_PATTERNS",
    lo: 0,
    hi: MAX_PATTERNS,
};

/// The shader's `PATTERNS`: the visibility patterns of a word whose Eq. (9) Ṽ `eq6_indirect`
/// tabulates once instead of computing it per light; `FVPL_SHADE_PATTERNS` (0..8) chooses, default
/// 0 (Ṽ per light). The image is the same bit for bit for every value (tests/clustered.rs). 0 is
/// the fastest on lavapipe, measured (docs/architecture.md); on a GPU `scripts/gpu-bench` times
/// both.
pub fn patterns() -> u32 {
    std::env::var(PATTERNS_ENV.name)
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .map_or(0, |p| p.min(MAX_PATTERNS))
}

pub struct Shade {
    /// One pipeline per F (the shader's `override F`) and cluster light (point, spread: its
    /// `override CLUSTER_SPREAD`), built the first time that pair is shaded.
    kernels: [[OnceCell<Kernel>; 2]; MAX_F as usize],
    /// The shader's `PATTERNS` (`patterns()` when built).
    patterns: u32,
    params: crate::gpu::persistent::Uniform<ShadeParams>,
    lights: crate::gi::dispatch::DataTextureSlot,
}

impl Default for Shade {
    fn default() -> Self {
        Self::new()
    }
}

impl Shade {
    pub fn new() -> Self {
        Self::with_patterns(patterns())
    }

    /// With `PATTERNS` = `patterns` (at most `MAX_PATTERNS`).
    pub fn with_patterns(patterns: u32) -> Self {
        Shade {
            kernels: Default::default(),
            patterns: patterns.min(MAX_PATTERNS),
            params: crate::gpu::persistent::Uniform::new("shade params"),
            lights: crate::gi::dispatch::DataTextureSlot::new(
                "shade lights",
                wgpu::TextureFormat::Rgba32Float,
            ),
        }
    }

    fn kernel(&self, ctx: &GpuContext, scene: &SceneGpu, f: u32, spread: bool) -> &Kernel {
        let f = f.clamp(1, MAX_F);
        self.kernels[f as usize - 1][spread as usize].get_or_init(|| {
            let mut entries = vec![
                uniform_layout(1),
                storage_layout(2, true),
                data_texture_layout(3, wgpu::TextureSampleType::Float { filterable: false }),
            ];
            entries.extend((4..=6).map(|b| storage_layout(b, true)));
            entries.push(storage_layout(7, false));
            let overrides = [
                ("F", f as f64),
                ("PATTERNS", self.patterns as f64),
                ("CLUSTER_SPREAD", spread as u32 as f64),
            ];
            Kernel::new(ctx, scene, "shade", &entries, &overrides)
        })
    }

    pub fn record(&self, g: &mut Gpu, i: &ShadeInputs) {
        let ctx = g.ctx;
        let params = self.params.set(ctx, &i.params);
        // The lights as a texture (3 texels each; see shade.wgsl).
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let n = i.params.num_lights as u64;
        let (lights, lights_view) = self.lights.get(ctx, 3 * n);
        copy_to_texture(&mut enc, i.lights, &lights, 48 * n);
        ctx.queue.submit([enc.finish()]);
        let kernel = self.kernel(ctx, g.scene, i.params.f, i.light == ClusterLight::Spread);
        let bg = kernel.bind_group_with_textures(
            ctx,
            &[
                (1, params),
                (2, i.gbuffer),
                (4, i.bits),
                (5, i.assign),
                (6, i.weights),
                (7, i.indirect),
            ],
            &[(3, &lights_view)],
        );
        // At most WORDS_PER_DISPATCH bit words (32 lights each) a pixel per dispatch: lavapipe ends
        // all loops of a SIMD batch after 65,535 trips (docs/architecture.md), and the walk over the
        // lights takes one a light; 131,072 lights in one dispatch lost the last ones. About 2^22
        // light terms per submission.
        let words = i.params.words.max(1);
        let per_dispatch = words.min(WORDS_PER_DISPATCH);
        let lights = i.params.num_lights.clamp(1, per_dispatch * 32);
        let per = ((1u32 << 22) / lights).max(64);
        let run = Run {
            label: Pass::Shade.name(),
            group: &bg,
            seed: 0,
        };
        kernel.run_2d(
            g,
            run,
            (i.pixels, per),
            (words, per_dispatch),
            &mut |_, _| true,
        );
    }
}
