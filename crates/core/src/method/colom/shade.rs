//! Step 6: Eq. (6) per pixel with Ṽ of Eq. (8) or (9) (`shaders-wgsl/shade.wgsl`); CPU twin in
//! `cpu::shade`.

use std::cell::OnceCell;

use bytemuck::{Pod, Zeroable};

use crate::gi::dispatch::{Before, Kernel, chunk_items, copy_to_texture};
use crate::gi::dispatch::{Gpu, Run};
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
    /// The image's width and height in pixels (the shader shades it in 8 × 8 tiles).
    pub width: u32,
    pub height: u32,
    pub _pad: u32,
}

/// The inputs of one shading dispatch.
pub struct ShadeInputs<'a> {
    pub gbuffer: &'a wgpu::Buffer,
    pub lights: &'a wgpu::Buffer,
    pub bits: &'a wgpu::Buffer,
    pub assign: &'a wgpu::Buffer,
    pub weights: &'a wgpu::Buffer,
    pub indirect: &'a wgpu::Buffer,
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

/// `FVPL_SHADE_TILE_CULL`, `tile_cull`'s variable: 0 or 1 (`method::ENV_INTEGERS`).
pub const TILE_CULL_ENV: crate::method::EnvInteger = crate::method::EnvInteger {
    name: "FVPL_SHADE_TILE_CULL",
    lo: 0,
    hi: 1,
};

/// The shader's `TILE_CULL`: each 8 × 8 tile skips the lights that no point of its bounds can see
/// or be seen by (`may_light_box`, docs/clustering.md, "Lights no point of a tile can see").
/// `FVPL_SHADE_TILE_CULL=0` walks every light the visibility rows see, for measuring what it saves;
/// the default is 1.
pub fn tile_cull() -> bool {
    std::env::var(TILE_CULL_ENV.name)
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .is_none_or(|v| v != 0)
}

/// The side of the square tiles a shading workgroup shades (`TILE` in shade.wgsl): 8 × 8 pixels,
/// one workgroup.
pub const TILE: u32 = 8;

/// The shading dispatches' items for a `width` × `height` image: 64 a tile, the tiles row-major
/// (`tile_pixel` in shade.wgsl maps an item to its pixel, or to none past the image's edge).
pub fn tile_items(width: u32, height: u32) -> u32 {
    width.div_ceil(TILE) * height.div_ceil(TILE) * TILE * TILE
}

pub struct Shade {
    /// One pipeline per F (the shader's `override F`) and cluster light (point, spread: its
    /// `override CLUSTER_SPREAD`), built the first time that pair is shaded.
    kernels: [[OnceCell<Kernel>; 2]; MAX_F as usize],
    /// The shader's `PATTERNS` (`patterns()` when built).
    patterns: u32,
    /// The shader's `TILE_CULL` (`tile_cull()` when built).
    tile_cull: bool,
    params: crate::gpu::persistent::Uniform<ShadeParams>,
    /// The lights as the walk reads them: 2 texels each (`pack_lights`, from `packed_lights`).
    lights: crate::gi::dispatch::DataTextureSlot,
    /// `pack_lights`' output (32 bytes a light), copied into `lights`.
    packed_lights: crate::gi::dispatch::StorageSlot,
    /// The tiles' boxes (4 × 16 bytes a tile, the entry point `tile_box`).
    tile_boxes: crate::gi::dispatch::StorageSlot,
    /// A submission's light masks (a word a tile and bit word, the entry point `tile_mask`).
    tile_masks: crate::gi::dispatch::StorageSlot,
}

impl Default for Shade {
    fn default() -> Self {
        Self::new()
    }
}

impl Shade {
    pub fn new() -> Self {
        Self::with_options(patterns(), tile_cull())
    }

    /// With `PATTERNS` = `patterns` (at most `MAX_PATTERNS`) and `TILE_CULL` = `tile_cull`.
    pub fn with_options(patterns: u32, tile_cull: bool) -> Self {
        Shade {
            kernels: Default::default(),
            patterns: patterns.min(MAX_PATTERNS),
            tile_cull,
            params: crate::gpu::persistent::Uniform::new("shade params"),
            lights: crate::gi::dispatch::DataTextureSlot::new(
                "shade lights",
                wgpu::TextureFormat::Rgba32Uint,
            ),
            packed_lights: crate::gi::dispatch::StorageSlot::new("shade packed lights"),
            tile_boxes: crate::gi::dispatch::StorageSlot::new("shade tile boxes"),
            tile_masks: crate::gi::dispatch::StorageSlot::new("shade tile masks"),
        }
    }

    /// The shader's `PATTERNS`.
    pub fn patterns(&self) -> u32 {
        self.patterns
    }

    /// The shader's `TILE_CULL`.
    pub fn tile_cull(&self) -> bool {
        self.tile_cull
    }

    fn kernel(&self, ctx: &GpuContext, scene: &SceneGpu, f: u32, spread: bool) -> &Kernel {
        let f = f.clamp(1, MAX_F);
        self.kernels[f as usize - 1][spread as usize].get_or_init(|| {
            let mut entries = vec![
                uniform_layout(1),
                storage_layout(2, true),
                data_texture_layout(3, wgpu::TextureSampleType::Uint),
            ];
            entries.extend((4..=6).map(|b| storage_layout(b, true)));
            entries.push(storage_layout(7, false));
            entries.push(storage_layout(8, false));
            entries.push(storage_layout(9, false));
            entries.push(storage_layout(10, true));
            entries.push(storage_layout(11, false));
            let overrides = [
                ("F", f as f64),
                ("PATTERNS", self.patterns as f64),
                ("CLUSTER_SPREAD", spread as u32 as f64),
                ("TILE_CULL", self.tile_cull as u32 as f64),
            ];
            Kernel::with_entries(
                ctx,
                Some(scene),
                "shade",
                &["main", "tile_box", "tile_mask", "pack_lights"],
                &entries,
                &overrides,
            )
        })
    }

    pub fn record(&self, g: &mut Gpu, i: &ShadeInputs) {
        let ctx = g.ctx;
        let params = self.params.set(ctx, &i.params);
        // The lights as a texture, 2 texels each (`pack_lights` in shade.wgsl).
        let n = i.params.num_lights as u64;
        let (lights_tex, lights_view) = self.lights.get(ctx, 2 * n);
        let packed_lights = self.packed_lights.get(ctx, 32 * n.max(1));
        let kernel = self.kernel(ctx, g.scene, i.params.f, i.light == ClusterLight::Spread);
        let items = tile_items(i.params.width, i.params.height);
        // At most WORDS_PER_DISPATCH bit words (32 lights each) a pixel per dispatch: lavapipe ends
        // all loops of a SIMD batch after 65,535 trips (docs/architecture.md), and the walk over the
        // lights takes one a light; 131,072 lights in one dispatch lost the last ones. About 2^22
        // light terms per submission, in whole workgroups (tiles): a multiple of 64 items.
        let words = i.params.words.max(1);
        let per_dispatch = words.min(WORDS_PER_DISPATCH);
        let lights = i.params.num_lights.clamp(1, per_dispatch * 32);
        let per = ((1u32 << 22) / lights).max(64) / 64 * 64;
        // The boxes: 64 bytes a tile (`items` bytes); a submission's masks: a word a tile of its
        // items and bit word of its range.
        let tile_boxes = self.tile_boxes.get(ctx, items as u64);
        let chunk_tiles = chunk_items(ctx, items, per) / (TILE * TILE);
        let tile_masks = self
            .tile_masks
            .get(ctx, 4 * chunk_tiles as u64 * per_dispatch as u64);
        let bg = kernel.bind_group_with_textures(
            ctx,
            &[
                (1, params),
                (2, i.gbuffer),
                (4, i.bits),
                (5, i.assign),
                (6, i.weights),
                (7, i.indirect),
                (8, &tile_boxes),
                (9, &tile_masks),
                (10, i.lights),
                (11, &packed_lights),
            ],
            &[(3, &lights_view)],
        );
        let run = Run {
            label: Pass::Shade.name(),
            group: &bg,
            seed: 0,
        };
        // With the tile cull: each tile's box (an invocation a tile), then in each submission its
        // tiles' masks (an invocation a tile and bit word) before the walk.
        let masks = |count: u32, sub_count: u32| count / (TILE * TILE) * sub_count;
        let before = self.tile_cull.then_some(Before {
            entry: "tile_mask",
            invocations: &masks,
        });
        // The lights' texels, then (with the tile cull) each tile's box, in one submission.
        let copy = |enc: &mut wgpu::CommandEncoder| {
            copy_to_texture(enc, &packed_lights, &lights_tex, 32 * n)
        };
        let mut steps = vec![("pack_lights", i.params.num_lights)];
        if self.tile_cull {
            steps.push(("tile_box", items / (TILE * TILE)));
        }
        kernel.run_entries(g, run, &steps, Some(("pack_lights", &copy)));
        kernel.run_2d_after(
            g,
            run,
            (items, per),
            (words, per_dispatch),
            before,
            &mut |_, _| true,
        );
    }
}
