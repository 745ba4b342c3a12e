//! The scene on the GPU: bind group 0 of every pass (`shaders-wgsl/common/scene.wgsl`).
//! Uploaded once per scene; all triangle arrays are in BVH slot order.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::bvh::SceneBvh;
use crate::gpu::GpuContext;
use crate::scene::{LightKind, Scene};

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SceneInfo {
    pub num_tris: u32,
    pub num_nodes: u32,
    pub num_emitters: u32,
    pub num_lights: u32,
    pub emit_power: f32,
    pub eps: f32,
    pub extent: f32,
    pub _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuTriShade {
    pub n0: [f32; 4],
    pub n1: [f32; 4],
    pub n2: [f32; 4],
    pub extra: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub base_color: [f32; 4],
    pub emissive: [f32; 4],
    pub tex: [i32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuTexInfo {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub _pad: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuEmitter {
    pub slot: u32,
    pub cdf: f32,
    pub area: f32,
    pub power: f32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    pub pos_kind: [f32; 4],
    pub dir_cos_outer: [f32; 4],
    pub color_cos_inner: [f32; 4],
}

/// Emitter table: emissive triangles (by slot) with a CDF over power = area × mean emitted radiance
/// (× the mean of the emissive texture when there is one). Shared by the GPU upload and the CPU twins.
pub fn emitter_table(scene: &Scene, bvh: &SceneBvh) -> (Vec<GpuEmitter>, f32) {
    let tex_mean: Vec<Vec3> = scene
        .textures
        .iter()
        .map(|t| {
            let mut s = Vec3::ZERO;
            for c in &t.rgba8 {
                s += Vec3::new(
                    srgb_to_linear(c[0]),
                    srgb_to_linear(c[1]),
                    srgb_to_linear(c[2]),
                );
            }
            s / t.rgba8.len().max(1) as f32
        })
        .collect();
    let mut out = Vec::new();
    let mut total = 0.0f64;
    for (slot, &ti) in bvh.slot_to_triangle.iter().enumerate() {
        let t = &scene.triangles[ti as usize];
        let m = &scene.materials[t.material as usize];
        let mut e = m.emissive;
        if let Some(k) = m.emissive_texture {
            e *= tex_mean[k as usize];
        }
        let area = t.area();
        let power = area * (e.x + e.y + e.z) / 3.0;
        if power > 0.0 && power.is_finite() {
            total += power as f64;
            out.push(GpuEmitter {
                slot: slot as u32,
                cdf: total as f32,
                area,
                power,
            });
        }
    }
    for e in &mut out {
        e.cdf = (e.cdf as f64 / total) as f32;
    }
    if let Some(last) = out.last_mut() {
        last.cdf = 1.0;
    }
    (out, total as f32)
}

pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub struct SceneGpu {
    pub layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    pub info: SceneInfo,
    pub has_textures: bool,
    pub has_emitters: bool,
    pub has_punctual: bool,
    /// Some triangle is alpha-tested (`Scene::alpha_test_flags`).
    pub has_alpha_test: bool,
    pub has_vertex_colors: bool,
    pub emitters: Vec<GpuEmitter>,
}

fn storage_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A layout entry for a storage buffer (`read_only` or read-write) visible to compute.
pub fn storage_layout(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    let mut e = storage_entry(binding);
    e.ty = wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    e
}

pub use crate::bvh::{MAX_TEXELS, MAX_TRIANGLES, TEXEL_ROW, TooBig};

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
}

/// Checks from the scene alone, before the BVH build, that its GPU data fit: triangles and nodes in
/// the data textures (`MAX_TRIANGLES`), and the storage buffers bound whole (texture texels,
/// emissive triangles, materials, lights) within `max_binding` bytes (the adapter's
/// `max_storage_buffer_binding_size`: 128 MiB on lavapipe).
pub fn check_fits(scene: &Scene, max_binding: u64) -> Result<(), TooBig> {
    let n = scene.triangles.len();
    if n > MAX_TRIANGLES {
        return Err(TooBig(format!(
            "{}: {n} triangles, more than the {MAX_TRIANGLES} the GPU data textures hold ({MAX_TEXELS} texels of 16 bytes each, 4 a triangle)",
            scene.name
        )));
    }
    let texels: u64 = scene
        .textures
        .iter()
        .map(|t| t.width as u64 * t.height as u64 * 4)
        .sum();
    let buffers = [
        ("texture texels", texels),
        (
            "emissive triangles",
            scene.emissive_triangle_count() as u64 * std::mem::size_of::<GpuEmitter>() as u64,
        ),
        (
            "materials",
            scene.materials.len() as u64 * std::mem::size_of::<GpuMaterial>() as u64,
        ),
        (
            "lights",
            scene.lights.len() as u64 * std::mem::size_of::<GpuLight>() as u64,
        ),
    ];
    for (what, bytes) in buffers {
        if bytes > max_binding {
            return Err(TooBig(format!(
                "{}: its {what} take {}, more than one storage binding of {} on this adapter",
                scene.name,
                mib(bytes),
                mib(max_binding)
            )));
        }
    }
    Ok(())
}

/// A layout entry for a 2D data texture (`textureLoad` only) visible to compute.
pub fn data_texture_layout(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A layout entry for a write-only 2D storage texture of `format` visible to compute.
pub fn storage_texture_layout(
    binding: u32,
    format: wgpu::TextureFormat,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    }
}

/// A 2D texture of 16-byte texels holding `bytes` row by row (`TEXEL_ROW` texels a row, zero padded).
/// The texel count is checked against the device limit in `SceneBvh::build` (`MAX_TEXELS`).
fn texture_init(
    ctx: &GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    bytes: &[u8],
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    let texels = (bytes.len() / 16).max(1) as u32;
    let rows = texels.div_ceil(TEXEL_ROW);
    let mut data = bytes.to_vec();
    data.resize((rows * TEXEL_ROW * 16) as usize, 0);
    ctx.device.create_texture_with_data(
        &ctx.queue,
        &data_texture_descriptor(label, format, rows),
        wgpu::util::TextureDataOrder::LayerMajor,
        &data,
    )
}

/// The descriptor of a data texture: `rows` rows of `TEXEL_ROW` texels of `format`, sampled by
/// `textureLoad` and filled by a copy (`texture_init` here, `dispatch::data_texture` for per-frame
/// data).
pub fn data_texture_descriptor(
    label: &str,
    format: wgpu::TextureFormat,
    rows: u32,
) -> wgpu::TextureDescriptor<'_> {
    wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: TEXEL_ROW,
            height: rows,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    }
}

/// A layout entry for a uniform buffer visible to compute.
pub fn uniform_layout(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl SceneGpu {
    pub fn upload(ctx: &GpuContext, scene: &Scene, bvh: &SceneBvh) -> SceneGpu {
        let nodes = bvh.gpu_nodes();
        let tris = bvh.gpu_triangles();
        let shade = shading_data(scene, bvh);
        let materials = gpu_materials(scene);
        let (tex_info, texels) = gpu_textures(scene);
        let has_vertex_colors = scene.uses_vertex_colors();
        let colors = vertex_colors(scene, bvh, has_vertex_colors);
        let (emitters, emit_power) = emitter_table(scene, bvh);
        let lights = gpu_lights(scene);
        let extent = scene.extent();
        let info = SceneInfo {
            num_tris: tris.len() as u32,
            num_nodes: nodes.len() as u32,
            num_emitters: emitters.len() as u32,
            num_lights: lights.len() as u32,
            emit_power,
            eps: 1e-5 * extent,
            extent,
            _pad: 0,
        };
        let layout = scene_layout(ctx);
        let buffers = [
            (0, ctx.uniform("scene info", &info)),
            (4, ctx.storage_init("materials", &materials)),
            (5, ctx.storage_init("texture info", &tex_info)),
            (6, ctx.storage_init("texels", &texels)),
            (7, ctx.storage_init("emitters", &emitters)),
            (8, ctx.storage_init("lights", &lights)),
            (10, ctx.storage_init("vertex colours", &colors)),
        ];
        // Nodes, triangles and their shading data are texels (see shaders-wgsl/common/bvh.wgsl and
        // scene.wgsl): not limited by one storage binding.
        let texel_arrays = [
            (
                1,
                wgpu::TextureFormat::Rgba32Uint,
                bytemuck::cast_slice(&nodes),
            ),
            (
                9,
                wgpu::TextureFormat::Rgba32Float,
                bytemuck::cast_slice(&tris),
            ),
            (
                3,
                wgpu::TextureFormat::Rgba32Float,
                bytemuck::cast_slice(&shade),
            ),
        ];
        let bind_group = scene_bind_group(ctx, &layout, &buffers, texel_arrays);
        SceneGpu {
            layout,
            bind_group,
            info,
            has_textures: !scene.textures.is_empty() && scene.uses_textures(),
            has_emitters: !emitters.is_empty(),
            has_punctual: !lights.is_empty(),
            has_alpha_test: bvh.has_alpha_test(),
            has_vertex_colors,
            emitters,
        }
    }

    /// Override constants that compile unused shader paths out.
    pub fn overrides(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("HAS_TEXTURES", self.has_textures as u32 as f64),
            ("HAS_EMITTERS", self.has_emitters as u32 as f64),
            ("HAS_PUNCTUAL", self.has_punctual as u32 as f64),
            ("HAS_ALPHA_TEST", self.has_alpha_test as u32 as f64),
            ("HAS_VERTEX_COLORS", self.has_vertex_colors as u32 as f64),
        ]
    }
}

/// Per BVH slot: the triangle's vertex normals, UVs and material (the texels of binding 3).
fn shading_data(scene: &Scene, bvh: &SceneBvh) -> Vec<GpuTriShade> {
    bvh.slot_to_triangle
        .iter()
        .map(|&i| {
            let t = &scene.triangles[i as usize];
            let n = t.n;
            let uv = t.uv;
            GpuTriShade {
                n0: [n[0].x, n[0].y, n[0].z, uv[0].x],
                n1: [n[1].x, n[1].y, n[1].z, uv[0].y],
                n2: [n[2].x, n[2].y, n[2].z, uv[1].x],
                extra: [uv[1].y, uv[2].x, uv[2].y, f32::from_bits(t.material)],
            }
        })
        .collect()
}

/// The materials (binding 4): base colour, emission with the alpha cutoff, texture indices (-1: none).
fn gpu_materials(scene: &Scene) -> Vec<GpuMaterial> {
    scene
        .materials
        .iter()
        .map(|m| GpuMaterial {
            base_color: m.base_color.into(),
            emissive: m.emissive.extend(m.alpha_cutoff.unwrap_or(0.0)).into(),
            tex: [
                m.base_color_texture.map_or(-1, |t| t as i32),
                m.emissive_texture.map_or(-1, |t| t as i32),
                0,
                0,
            ],
        })
        .collect()
}

/// The textures: where each starts in the texel array and its size (binding 5), and their RGBA8
/// texels one after another (binding 6).
fn gpu_textures(scene: &Scene) -> (Vec<GpuTexInfo>, Vec<u32>) {
    let mut tex_info = Vec::new();
    let mut texels: Vec<u32> = Vec::new();
    for t in &scene.textures {
        tex_info.push(GpuTexInfo {
            offset: texels.len() as u32,
            width: t.width,
            height: t.height,
            _pad: 0,
        });
        texels.extend(t.rgba8.iter().map(|c| u32::from_le_bytes(*c)));
    }
    (tex_info, texels)
}

/// Per BVH slot the three vertex colours (binding 10); one white entry when the scene uses none
/// (`has_vertex_colors`).
fn vertex_colors(scene: &Scene, bvh: &SceneBvh, has_vertex_colors: bool) -> Vec<[f32; 4]> {
    if has_vertex_colors {
        bvh.slot_to_triangle
            .iter()
            .flat_map(|&i| scene.triangles[i as usize].color.map(Into::into))
            .collect()
    } else {
        vec![[1.0; 4]]
    }
}

/// The punctual lights (binding 8): position and kind (0 point, 1 spot, 2 directional), direction
/// and the cosine of the outer cone, colour × intensity and the cosine of the inner cone.
fn gpu_lights(scene: &Scene) -> Vec<GpuLight> {
    scene
        .lights
        .iter()
        .map(|l| {
            let (kind, co, ci) = match l.kind {
                LightKind::Point => (0.0, -1.0, 1.0),
                LightKind::Spot {
                    inner_cone,
                    outer_cone,
                } => (1.0, outer_cone.cos(), inner_cone.cos()),
                LightKind::Directional => (2.0, -1.0, 1.0),
            };
            let c = l.color * l.intensity;
            GpuLight {
                pos_kind: [l.position.x, l.position.y, l.position.z, kind],
                dir_cos_outer: [l.direction.x, l.direction.y, l.direction.z, co],
                color_cos_inner: [c.x, c.y, c.z, ci],
            }
        })
        .collect()
}

/// The layout of bind group 0 (`shaders-wgsl/common/scene.wgsl`).
fn scene_layout(ctx: &GpuContext) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = [
        uniform_layout(0),
        data_texture_layout(1, wgpu::TextureSampleType::Uint),
        data_texture_layout(3, wgpu::TextureSampleType::Float { filterable: false }),
        data_texture_layout(9, wgpu::TextureSampleType::Float { filterable: false }),
    ]
    .into_iter()
    .chain((4..=8).chain([10]).map(storage_entry))
    .collect();
    ctx.device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &entries,
        })
}

/// Bind group 0: the uploaded `buffers` and, uploaded here as data textures, the `texel_arrays`
/// (binding, format, bytes).
fn scene_bind_group(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, wgpu::Buffer)],
    texel_arrays: [(u32, wgpu::TextureFormat, &[u8]); 3],
) -> wgpu::BindGroup {
    let texel_views = texel_arrays.map(|(binding, format, bytes)| {
        let tex = texture_init(ctx, "bvh texels", format, bytes);
        (binding, tex.create_view(&Default::default()))
    });
    let bind_entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .map(|(binding, b)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: b.as_entire_binding(),
        })
        .chain(texel_views.iter().map(|(binding, v)| wgpu::BindGroupEntry {
            binding: *binding,
            resource: wgpu::BindingResource::TextureView(v),
        }))
        .collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("scene"),
        layout,
        entries: &bind_entries,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Texture};

    /// Storage buffers bound whole are refused past the binding size, naming the scene and the
    /// buffer: one 64×64 texture is 16 KiB of texels (64 · 64 · 4 bytes).
    #[test]
    fn storage_buffers_past_one_binding_are_refused() {
        let s = Scene {
            name: "big.glb".into(),
            materials: vec![Material::default()],
            textures: vec![Texture {
                name: "t".into(),
                width: 64,
                height: 64,
                rgba8: vec![[0; 4]; 64 * 64],
            }],
            ..Default::default()
        };
        assert!(check_fits(&s, 16 * 1024).is_ok());
        let e = check_fits(&s, 16 * 1024 - 1).unwrap_err().to_string();
        assert!(
            e.starts_with("big.glb: its texture texels take 0.0 MiB")
                && e.contains("storage binding"),
            "{e}"
        );
        // 48 bytes a material.
        let many = Scene {
            materials: vec![Material::default(); 100],
            textures: Vec::new(),
            ..s.clone()
        };
        assert!(check_fits(&many, 4800).is_ok());
        assert!(
            check_fits(&many, 4799)
                .unwrap_err()
                .to_string()
                .contains("materials")
        );
        assert_eq!(MAX_TRIANGLES, 8_388_608);
    }
}
