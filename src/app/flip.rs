//! LDR FLIP on the GPU (`shaders-wgsl/flip.wgsl`): the per-pixel FLIP error of a frame against a
//! reference, both shown as the viewer shows them, its mean reduced to one f32, and its magma
//! picture, all without reading the frame back. What `metrics::flip_map` and `metrics::flip` compute
//! through NVIDIA's C++ (`nv-flip`), at the same 67 pixels per degree; its CPU twin is `metrics::ldr_flip`.
//!
//! Inputs, as the display pass reads them (`display::Images`): A's emission + direct and indirect
//! buffers (vec4 a pixel, render units) with their factor to the scene's units (A's radiance is their
//! sum, as `Frame::radiance`), the reference (vec4 a pixel, the scene's units), and a buffer whose
//! first f32 is the exposure both are shown with (the display pass's `exposure_buffer`, automatic or
//! fixed). Both images are tone-mapped exactly as `export::to_srgb8` writes them (× exposure,
//! clamped, sRGB, 8 bits) before FLIP reads them.
//!
//! It owns its pipelines, its bind-group layout, its uniform (filter weights, tone-map steps and the
//! magma LUT written once) and its buffers, made again only when the size changes: a frame allocates
//! nothing but its bind group (as the display pass).

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::display::Images;
use crate::metrics::ldr_flip as twin;

/// Pixels a workgroup of `filter_x` / `filter_y` covers in a row (`ROW` in the shader).
const ROW: u32 = 64;
/// Threads a workgroup of the mean's reduction (`REDUCE`).
const REDUCE: u32 = 256;
/// The most workgroups a dimension of a dispatch has (WebGPU's default limit).
const MAX_GROUPS: u32 = 65535;
/// The filters' taps at FLIP's default pixels per degree (`SPATIAL_TAPS`, `FEATURE_TAPS`).
const SPATIAL_TAPS: usize = 21;
const FEATURE_TAPS: usize = 19;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FlipParams {
    size: [u32; 4],
    consts: [f32; 4],
    spatial: [[f32; 4]; SPATIAL_TAPS],
    feature: [[f32; 4]; FEATURE_TAPS],
    thresholds: [[f32; 4]; 64],
    linear: [[f32; 4]; 64],
    magma: [[u32; 4]; 64],
}

/// The bytes of `FlipParams` written each frame (size, consts).
const HEADER: usize = 32;

/// 256 scalars as the shader's 64 vec4s.
fn quads<T: Copy + Default>(v: &[T; 256]) -> [[T; 4]; 64] {
    std::array::from_fn(|i| std::array::from_fn(|c| v[4 * i + c]))
}

impl FlipParams {
    /// Everything but the size and A's scale: FLIP's filters at its default pixels per degree, cmax,
    /// the tone map's steps and FLIP's magma LUT.
    fn constants() -> Self {
        let ppd = twin::PIXELS_PER_DEGREE;
        let spatial = twin::spatial_filters(ppd);
        let feature = twin::feature_filter(ppd);
        assert!(spatial.len() == SPATIAL_TAPS && feature.len() == FEATURE_TAPS);
        let lut = nv_flip::magma_lut().to_vec();
        let magma: [u32; 256] = std::array::from_fn(|i| {
            lut[3 * i] as u32 | (lut[3 * i + 1] as u32) << 8 | (lut[3 * i + 2] as u32) << 16
        });
        let cmax = twin::max_distance();
        FlipParams {
            size: [0; 4],
            consts: [1.0, cmax, twin::PC * cmax, 0.0],
            spatial: std::array::from_fn(|k| spatial[k]),
            feature: std::array::from_fn(|k| {
                let [g, d, dd] = feature[k];
                [g, d, dd, 0.0]
            }),
            thresholds: quads(&twin::srgb8_thresholds()),
            linear: quads(&twin::srgb8_linear()),
            magma: quads(&magma),
        }
    }
}

/// What one FLIP evaluation reads.
pub struct FlipInputs<'a> {
    pub size: (u32, u32),
    /// The image compared (the test image).
    pub a: Images<'a>,
    /// The reference, a vec4 a pixel in the scene's units.
    pub reference: &'a wgpu::Buffer,
    /// A buffer whose first f32 is the exposure (`Display::exposure_buffer`).
    pub exposure: &'a wgpu::Buffer,
}

/// The buffers of one size.
struct Sized {
    size: (u32, u32),
    /// `filter_x`'s sums: the reference's then A's (n vec4 each).
    csf: wgpu::Buffer,
    features: wgpu::Buffer,
    map: wgpu::Buffer,
    /// [0]: the mean; [1 + g]: workgroup g's sum.
    sums: wgpu::Buffer,
}

pub struct Flip {
    filter_x: wgpu::ComputePipeline,
    filter_y: wgpu::ComputePipeline,
    mean_partial: wgpu::ComputePipeline,
    mean_final: wgpu::ComputePipeline,
    colour: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// Bound where no picture is asked for (never written then): a 1 × 1 texture's storage view.
    stand_in: wgpu::TextureView,
    /// FLIP's cmax (`metrics::ldr_flip::max_distance`).
    cmax: f32,
    sized: Option<Sized>,
}

/// The mean's reduction grid for `n` pixels: (x, y) workgroups.
fn reduce_grid(n: u32) -> (u32, u32) {
    let groups = n.div_ceil(REDUCE).max(1);
    (groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS))
}

impl Flip {
    pub fn new(device: &wgpu::Device) -> Self {
        use crate::gi::scene_gpu::{storage_layout, storage_texture_layout, uniform_layout};
        let mut entries = vec![uniform_layout(0)];
        entries.extend((1..9).map(|b| storage_layout(b, b < 5)));
        entries.push(storage_texture_layout(9, wgpu::TextureFormat::Rgba8Unorm));
        let (layout, [filter_x, filter_y, mean_partial, mean_final, colour]) =
            crate::gpu::shader::compute_pipelines(
                device,
                "flip",
                &entries,
                [
                    "filter_x",
                    "filter_y",
                    "mean_partial",
                    "mean_final",
                    "colour",
                ],
            );
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("flip params"),
            contents: bytemuck::bytes_of(&FlipParams::constants()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let stand_in = super::display::Target::new(device, (1, 1), "flip stand-in").storage_view();
        Flip {
            filter_x,
            filter_y,
            mean_partial,
            mean_final,
            colour,
            layout,
            params,
            stand_in,
            cmax: twin::max_distance(),
            sized: None,
        }
    }

    /// Whether images of `size` fit the device's storage bindings (the filters' sums hold two vec4
    /// a pixel: 4.2 million pixels under WebGPU's default 128 MiB).
    pub fn fits(device: &wgpu::Device, (w, h): (u32, u32)) -> bool {
        let n = w as u64 * h as u64;
        n > 0 && n * 32 <= device.limits().max_storage_buffer_binding_size && h <= MAX_GROUPS
    }

    /// The buffers for `size`, made again only when it changes.
    fn ensure(&mut self, device: &wgpu::Device, size: (u32, u32)) {
        if self.sized.as_ref().is_none_or(|s| s.size != size) {
            let n = size.0 as u64 * size.1 as u64;
            let grid = reduce_grid(size.0 * size.1);
            let buffer = |label, bytes: u64| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: bytes.max(256),
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })
            };
            self.sized = Some(Sized {
                size,
                csf: buffer("flip csf", n * 32),
                features: buffer("flip features", n * 32),
                map: buffer("flip map", n * 4),
                sums: buffer("flip sums", (1 + grid.0 as u64 * grid.1 as u64) * 4),
            });
        }
    }

    /// The FLIP error of each pixel of the last `record` (an f32 a pixel, row-major).
    pub fn map(&self) -> Option<&wgpu::Buffer> {
        self.sized.as_ref().map(|s| &s.map)
    }

    /// The buffer whose first f32 is the mean FLIP error of the last `record` (for the error plot:
    /// read 4 bytes back, or bind it).
    pub fn mean(&self) -> Option<&wgpu::Buffer> {
        self.sized.as_ref().map(|s| &s.sums)
    }

    /// Records FLIP of `inputs` into `enc`: the map and its mean, and with `picture` (an
    /// `Rgba8Unorm` storage view of `inputs.size`, e.g. the display's target) the map in magma.
    /// Panics when the size does not fit (`fits`).
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        enc: &mut wgpu::CommandEncoder,
        inputs: &FlipInputs,
        picture: Option<&wgpu::TextureView>,
    ) {
        let (w, h) = inputs.size;
        assert!(
            Self::fits(device, inputs.size),
            "FLIP: {w} x {h} does not fit"
        );
        let n = w * h;
        // Only the size and A's scale change: the constants after them were written at creation.
        let header = (
            [w, h, n, 0u32],
            [inputs.a.scale, self.cmax, twin::PC * self.cmax, 0.0f32],
        );
        let mut bytes = [0u8; HEADER];
        bytes[..16].copy_from_slice(bytemuck::bytes_of(&header.0));
        bytes[16..].copy_from_slice(bytemuck::bytes_of(&header.1));
        crate::gpu::traffic::uploaded(HEADER as u64);
        queue.write_buffer(&self.params, 0, &bytes);
        self.ensure(device, inputs.size);
        let s = self.sized.as_ref().expect("made by ensure");
        let buffers = [
            &self.params,
            inputs.a.direct,
            inputs.a.indirect,
            inputs.reference,
            inputs.exposure,
            &s.csf,
            &s.features,
            &s.map,
            &s.sums,
        ];
        let entries = crate::gpu::bind_entries(&buffers, &[picture.unwrap_or(&self.stand_in)]);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("flip"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("flip"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, &group, &[]);
        let rows = (w.div_ceil(ROW), h);
        pass.set_pipeline(&self.filter_x);
        pass.dispatch_workgroups(rows.0, rows.1, 1);
        pass.set_pipeline(&self.filter_y);
        pass.dispatch_workgroups(rows.0, rows.1, 1);
        let grid = reduce_grid(n);
        pass.set_pipeline(&self.mean_partial);
        pass.dispatch_workgroups(grid.0, grid.1, 1);
        pass.set_pipeline(&self.mean_final);
        pass.dispatch_workgroups(1, 1, 1);
        if picture.is_some() {
            pass.set_pipeline(&self.colour);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shader's filter sizes are FLIP's at its default pixels per degree (`metrics::ldr_flip`), and its
    /// uniform is laid out as `FlipParams`.
    #[test]
    fn shader_constants_match_flip() {
        let module = crate::gpu::shader::validate("flip").unwrap();
        let constant = |name: &str| -> u32 {
            let (_, c) = module
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("no constant {name}"));
            match module.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::U32(v)) => v,
                ref e => panic!("{name}: {e:?}"),
            }
        };
        let ppd = twin::PIXELS_PER_DEGREE;
        assert_eq!(
            constant("SPATIAL_RADIUS") as usize,
            twin::spatial_radius(ppd)
        );
        assert_eq!(
            constant("FEATURE_RADIUS") as usize,
            twin::feature_radius(ppd)
        );
        assert_eq!(constant("SPATIAL_TAPS") as usize, SPATIAL_TAPS);
        assert_eq!(constant("FEATURE_TAPS") as usize, FEATURE_TAPS);
        assert_eq!(constant("ROW"), ROW);
        assert_eq!(constant("REDUCE"), REDUCE);
        assert_eq!(
            constant("TILE"),
            ROW + 2 * twin::spatial_radius(ppd).max(twin::feature_radius(ppd)) as u32
        );
        let params = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("FlipParams"))
            .expect("FlipParams");
        assert_eq!(
            params.1.inner.size(module.to_ctx()) as usize,
            std::mem::size_of::<FlipParams>()
        );
        assert_eq!(HEADER, 32);
    }
}
