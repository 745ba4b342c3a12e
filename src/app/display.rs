//! The viewer's display pass (`shaders-wgsl/display.wgsl`): what the image area shows, composed on
//! the GPU from a frame's buffers into an 8-bit texture that egui draws (`register_native_texture`):
//! the automatic exposure reduced on the GPU, every view, exposure, sRGB. The FLIP view is the FLIP
//! pass's (`app::flip`, built on first use): its map of A against the reference at the display's
//! exposure, in magma, written into the same texture. It owns its pipelines, its bind-group layout,
//! its uniform and its output texture, all made once a size: a frame allocates nothing. Its CPU twin
//! is `app::twin`.

use bytemuck::{Pod, Zeroable};

use super::views::View;
use crate::exposure::Exposure;

/// Threads a workgroup of the exposure's reduction (`REDUCE` in the shader).
const REDUCE: u32 = 256;

/// The view as the shader numbers it (`VIEW_*`; FLIP's is drawn by the FLIP pass instead).
pub fn view_code(view: View) -> u32 {
    match view {
        View::Final => 0,
        View::Direct => 1,
        View::Indirect => 2,
        View::SpClusters => 3,
        View::VplPoints => 4,
        View::Reference => 5,
        View::Error => 6,
        View::Split => 7,
        View::Diff => 8,
        View::Flip => 9,
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct DisplayParams {
    size: [u32; 4],
    scale: [f32; 4],
}

/// A frame's images as the pass reads them: emission + direct light and the indirect light, a vec4
/// an image pixel, in render units × `scale`.
#[derive(Clone, Copy)]
pub struct Images<'a> {
    pub direct: &'a wgpu::Buffer,
    pub indirect: &'a wgpu::Buffer,
    pub scale: f32,
}

/// What one display draws.
pub struct DisplayInputs<'a> {
    pub size: (u32, u32),
    pub view: View,
    pub a: Images<'a>,
    /// The split and A−B views' B (same size).
    pub b: Option<Images<'a>>,
    /// The reference, a vec4 a pixel in the scene's units.
    pub reference: Option<&'a wgpu::Buffer>,
    /// Each pixel's nearest SP cluster (`u32::MAX`: none).
    pub labels: Option<&'a wgpu::Buffer>,
    pub exposure: Exposure,
    /// The final view adds the direct light.
    pub direct_on: bool,
    /// The split view's divider, a fraction of the width.
    pub split: f32,
}

/// The pass's output: an `Rgba8Unorm` texture written with sRGB-encoded values, and the view of it
/// egui samples. egui-wgpu (0.37) takes a native texture's values as sRGB-encoded (its own textures
/// are `Rgba8Unorm`, blended in gamma space): a view as `Rgba8UnormSrgb` would hand it linear values
/// and darken the image (tests/views.rs compares the window's pixels with `render`'s PNG).
pub struct Target {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub size: (u32, u32),
}

impl Target {
    /// An output texture of `size`: written as `Rgba8Unorm` storage, sampled by egui as it is
    /// (sRGB-encoded values), read as a texture (the reprojection) and copied (screenshots).
    pub fn new(device: &wgpu::Device, (w, h): (u32, u32), label: &str) -> Target {
        let texture = crate::gpu::texture_2d(
            device,
            label,
            (w, h),
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            usage: Some(wgpu::TextureUsages::TEXTURE_BINDING),
            ..Default::default()
        });
        Target {
            texture,
            view,
            size: (w, h),
        }
    }

    /// The view the passes write.
    pub fn storage_view(&self) -> wgpu::TextureView {
        self.texture.create_view(&wgpu::TextureViewDescriptor {
            usage: Some(wgpu::TextureUsages::STORAGE_BINDING),
            ..Default::default()
        })
    }
}

pub struct Display {
    log_luminance: wgpu::ComputePipeline,
    exposure: wgpu::ComputePipeline,
    display: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    /// The reduction's partial sums (a vec2 a workgroup) and the exposure (an f32).
    partials: wgpu::Buffer,
    exposure_buf: wgpu::Buffer,
    /// Bound where an input is absent (never read then).
    stand_in: wgpu::Buffer,
    target: Option<Target>,
    /// The FLIP view's pass, built on first use.
    flip: Option<super::flip::Flip>,
}

/// The most workgroups a dimension of a dispatch has (WebGPU's default limit).
const MAX_GROUPS: u32 = 65535;

impl Display {
    pub fn new(device: &wgpu::Device) -> Self {
        use crate::gi::scene_gpu::{storage_layout, storage_texture_layout, uniform_layout};
        let mut entries = vec![uniform_layout(0)];
        entries.extend((1..9).map(|b| storage_layout(b, b < 7)));
        entries.push(storage_texture_layout(9, wgpu::TextureFormat::Rgba8Unorm));
        let (layout, [log_luminance, exposure, display]) = crate::gpu::shader::compute_pipelines(
            device,
            "display",
            &entries,
            ["log_luminance", "exposure", "display"],
        );
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        Display {
            log_luminance,
            exposure,
            display,
            layout,
            params: buffer(
                "display params",
                std::mem::size_of::<DisplayParams>() as u64,
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            ),
            partials: buffer("display partials", 256, storage),
            exposure_buf: buffer("display exposure", 256, storage),
            stand_in: buffer("display stand-in", 256, wgpu::BufferUsages::STORAGE),
            target: None,
            flip: None,
        }
    }

    /// The output of the last `record`, if any.
    pub fn target(&self) -> Option<&Target> {
        self.target.as_ref()
    }

    /// The buffer whose first f32 is the exposure the last `record` used (read it back only on
    /// request: screenshots, stats).
    pub fn exposure_buffer(&self) -> &wgpu::Buffer {
        &self.exposure_buf
    }

    /// The FLIP pass, once a FLIP view was drawn: its map and mean (`Flip::mean`) are those of the
    /// last FLIP view.
    pub fn flip(&self) -> Option<&super::flip::Flip> {
        self.flip.as_ref()
    }

    /// Whether the FLIP view of `inputs` is drawn as FLIP (a reference, and a size the FLIP pass
    /// fits, `Flip::fits`); else it is drawn as the final view.
    pub fn draws_flip(device: &wgpu::Device, inputs: &DisplayInputs) -> bool {
        inputs.view == View::Flip
            && inputs.reference.is_some()
            && super::flip::Flip::fits(device, inputs.size)
    }

    /// Records the display of `inputs` into `enc`; the output texture is made again only when the
    /// size changes (returns true then: a texture registered with egui must be updated). The FLIP
    /// view without a reference (or too large, `draws_flip`) is drawn as the final view.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        enc: &mut wgpu::CommandEncoder,
        inputs: &DisplayInputs,
    ) -> bool {
        let (w, h) = inputs.size;
        let n = w * h;
        let groups = n.div_ceil(REDUCE).max(1);
        let grid = (groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS));
        let partial_bytes = grid.0 as u64 * grid.1 as u64 * 8;
        if self.partials.size() < partial_bytes {
            self.partials = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("display partials"),
                size: partial_bytes,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
        }
        let remade = self.target.as_ref().is_none_or(|t| t.size != (w, h));
        if remade {
            self.target = Some(Target::new(device, (w, h), "display"));
        }
        let flip = Self::draws_flip(device, inputs);
        let view = if inputs.view == View::Flip && !flip {
            view_code(View::Final)
        } else {
            view_code(inputs.view)
        };
        let flags = inputs.direct_on as u32 | (inputs.exposure.is_auto() as u32) << 1;
        let fixed = match inputs.exposure {
            Exposure::Fixed(e) => e,
            Exposure::Auto => 1.0,
        };
        let b = inputs.b.unwrap_or(inputs.a);
        let p = DisplayParams {
            size: [w, h, view, flags],
            scale: [inputs.a.scale, b.scale, fixed, inputs.split],
        };
        crate::gpu::traffic::uploaded(std::mem::size_of::<DisplayParams>() as u64);
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        let out = self.target.as_ref().expect("made above").storage_view();
        let buffers = [
            &self.params,
            inputs.a.direct,
            inputs.a.indirect,
            b.direct,
            b.indirect,
            inputs.reference.unwrap_or(&self.stand_in),
            inputs.labels.unwrap_or(&self.stand_in),
            &self.partials,
            &self.exposure_buf,
        ];
        let entries = crate::gpu::bind_entries(&buffers, &[&out]);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("display"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, &group, &[]);
        pass.set_pipeline(&self.log_luminance);
        pass.dispatch_workgroups(grid.0, grid.1, 1);
        pass.set_pipeline(&self.exposure);
        pass.dispatch_workgroups(1, 1, 1);
        if !flip {
            pass.set_pipeline(&self.display);
            pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
            return remade;
        }
        drop(pass);
        let f = self
            .flip
            .get_or_insert_with(|| super::flip::Flip::new(device));
        let reference = inputs.reference.expect("draws_flip");
        f.record(
            device,
            queue,
            enc,
            &super::flip::FlipInputs {
                size: (w, h),
                a: inputs.a,
                reference,
                exposure: &self.exposure_buf,
            },
            Some(&out),
        );
        remade
    }
}

/// (key, emission + direct, indirect): a frame's images on the CPU under the key that says when
/// they change.
pub type KeyedImages<'a> = (String, &'a [[f32; 3]], &'a [[f32; 3]]);

/// Where a frame's images are: on the CPU (the split display path: uploaded to the window's device
/// when their key changes) or in the frame's own buffers on the window's device (shared).
pub enum Source<'a> {
    Cpu(KeyedImages<'a>),
    /// The frame, and a key that changes when its buffers do (the refinement at rest).
    Gpu(String, &'a crate::render::GpuFrame),
}

impl Source<'_> {
    fn key(&self) -> &str {
        match self {
            Source::Cpu(k) => &k.0,
            Source::Gpu(k, _) => k,
        }
    }
}

/// What the window's display pass draws this window frame (`Viewer::gpu_view`): the latest frame's
/// images on the CPU (the split display path: the GI device is another device) with the keys that
/// tell whether each must be uploaded again.
pub struct GpuView<'a> {
    /// Why the view shows something else (no reference yet, nothing pinned as B, …).
    pub note: Option<&'static str>,
    /// The camera the image shows.
    pub camera: crate::scene::Camera,
    /// Shared path, the camera moved since the frame: show it reprojected (`reproject_gpu`) from
    /// its camera to the current one (render units), with its G-buffer.
    pub reproject: Option<(
        crate::gi::primary::CameraParams,
        crate::gi::primary::CameraParams,
        &'a wgpu::Buffer,
    )>,
    pub size: (u32, u32),
    pub view: View,
    /// A's images keyed by the frame id and its direct-light estimates.
    pub a: Source<'a>,
    pub b: Option<Source<'a>>,
    pub reference: Option<(String, &'a [[f32; 3]])>,
    pub labels: Option<(String, &'a [u32])>,
    pub exposure: Exposure,
    pub direct_on: bool,
    pub split: f32,
}

impl GpuView<'_> {
    /// Everything the drawn image depends on.
    pub fn key(&self) -> String {
        format!(
            "{:?} {:?} {} {:?} {:?} {:?} {:?} {} {}",
            self.size,
            self.view,
            self.a.key(),
            self.b.as_ref().map(|b| b.key()),
            self.reference.as_ref().map(|r| &r.0),
            self.labels.as_ref().map(|l| &l.0),
            self.exposure,
            self.direct_on,
            self.split
        )
    }
}

/// The window device's copies of a frame's images (the split display path): buffers kept from frame
/// to frame and grown when a larger frame comes, each written only when its key changes.
#[derive(Default)]
pub struct Uploads {
    slots: [Option<(String, wgpu::Buffer)>; 6],
}

impl Uploads {
    /// Slot `i` holding `data` under `key`: written (and counted, `gpu::traffic`) only when the key
    /// changed.
    fn put<T: bytemuck::Pod>(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        i: usize,
        key: &str,
        data: &[T],
    ) -> &wgpu::Buffer {
        let bytes = (std::mem::size_of_val(data) as u64).max(256);
        let slot = &mut self.slots[i];
        let stale = slot
            .as_ref()
            .is_none_or(|(k, b)| k != key || b.size() < bytes);
        if stale {
            if slot.as_ref().is_none_or(|(_, b)| b.size() < bytes) {
                *slot = Some((
                    String::new(),
                    device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some("display upload"),
                        size: bytes,
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                ));
            }
            let (k, b) = slot.as_mut().expect("made above");
            crate::gpu::traffic::uploaded(std::mem::size_of_val(data) as u64);
            queue.write_buffer(b, 0, bytemuck::cast_slice(data));
            *k = key.to_string();
        }
        &slot.as_ref().expect("written").1
    }

    /// `v`'s images on the window device, and the display's inputs over them.
    pub fn inputs<'a>(
        &'a mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        v: &'a GpuView<'a>,
    ) -> DisplayInputs<'a> {
        let vec4 = |img: &[[f32; 3]]| -> Vec<[f32; 4]> {
            img.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect()
        };
        // CPU images into slots (first, second) under their key.
        let upload = |this: &mut Self, first: usize, src: &Source| {
            if let Source::Cpu((key, d, i)) = src {
                let d4 = vec4_if(&this.slots[first], key, d, vec4);
                this.put(device, queue, first, key, &d4);
                let i4 = vec4_if(&this.slots[first + 1], key, i, vec4);
                this.put(device, queue, first + 1, key, &i4);
            }
        };
        upload(self, 0, &v.a);
        if let Some(b) = &v.b {
            upload(self, 2, b);
        }
        if let Some(r) = &v.reference {
            let r4 = vec4_if(&self.slots[4], &r.0, r.1, vec4);
            self.put(device, queue, 4, &r.0, &r4);
        }
        if let Some(l) = &v.labels {
            self.put(device, queue, 5, &l.0, l.1);
        }
        let this: &'a Self = self;
        let buf = |i: usize| &this.slots[i].as_ref().expect("uploaded").1;
        let images = |first: usize, src: &'a Source<'a>| match src {
            Source::Cpu(_) => Images {
                direct: buf(first),
                indirect: buf(first + 1),
                scale: 1.0,
            },
            Source::Gpu(_, g) => Images {
                direct: &g.buffers.radiance,
                indirect: g.buffers.image_indirect(),
                scale: g.output_scale,
            },
        };
        DisplayInputs {
            size: v.size,
            view: v.view,
            a: images(0, &v.a),
            b: v.b.as_ref().map(|b| images(2, b)),
            reference: v.reference.as_ref().map(|_| buf(4)),
            labels: v.labels.as_ref().map(|_| buf(5)),
            exposure: v.exposure,
            direct_on: v.direct_on,
            split: v.split,
        }
    }
}

/// `img` as vec4s when slot `slot` does not hold it under `key` yet (else nothing: no conversion for
/// an image already on the device).
fn vec4_if(
    slot: &Option<(String, wgpu::Buffer)>,
    key: &str,
    img: &[[f32; 3]],
    vec4: impl Fn(&[[f32; 3]]) -> Vec<[f32; 4]>,
) -> Vec<[f32; 4]> {
    match slot {
        Some((k, b)) if k == key && b.size() >= (img.len() as u64 * 16).max(256) => Vec::new(),
        _ => vec4(img),
    }
}
