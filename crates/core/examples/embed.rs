//! fuzzy-vpl's GI inside another wgpu program: the program owns the device and the texture, and
//! fuzzy-vpl renders a frame of a scene into that texture.
//!
//! ```sh
//! cargo run --release -p fuzzy-vpl-core --example embed -- OUT.png [SCENE]
//! ```
//!
//! SCENE is a built-in scene (`builtin:cornell`, the default) or a glTF file. The example creates
//! its own headless device with the features and limits fuzzy-vpl asks for, renders the scene's
//! default camera with the paper's fuzzy clustering (`Method::Colom`, weighted) into an
//! `Rgba32Float` texture, reads that texture back, and writes it as a PNG (auto exposure, sRGB).
//! It exits 1 if the image is black.

use std::path::PathBuf;

use anyhow::{Context as _, Result, bail};
use fuzzy_vpl_core::{
    ClusterSettings, FrameSettings, GpuContext, Method, MethodSettings, RenderSettings, Renderer,
};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let out = PathBuf::from(args.next().context("usage: embed OUT.png [SCENE]")?);
    let spec = args.next().unwrap_or_else(|| "builtin:cornell".into());

    // The host program's device: any adapter, the features and limits fuzzy-vpl needs.
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("host device"),
        required_features: adapter.features() & fuzzy_vpl_core::gpu::wanted_features(),
        required_limits: fuzzy_vpl_core::gpu::required_limits(&adapter.limits()),
        ..Default::default()
    }))?;
    let ctx = GpuContext::from_device(instance, adapter, device, queue)?;

    // The scene and the settings: one frame at 320×240 with 2048 VPLs, clustered as in the paper.
    let scene = fuzzy_vpl_core::scene::load(&spec)?;
    let camera = scene.default_camera();
    let settings = RenderSettings {
        frame: FrameSettings {
            width: 320,
            height: 240,
            vpls: 2048,
            ..Default::default()
        },
        cluster: ClusterSettings {
            vpl_clusters: 512,
            sp_clusters: 256,
            ..Default::default()
        },
        method: MethodSettings {
            method: Method::Colom,
            ..Default::default()
        },
        ..Default::default()
    };

    // The host's texture: fuzzy-vpl writes linear radiance into it.
    let (w, h) = (settings.frame.width, settings.frame.height);
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host texture"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba32Float,
        usage: wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let mut renderer = Renderer::new(&ctx, &scene)?;
    // A compute pass writes the texture from the frame's buffers: nothing goes through the CPU.
    let frame = renderer
        .render_to_texture(&camera, &settings, &texture)?
        .meta;
    println!(
        "{}: {w}×{h}, {} VPLs, passes {:?}, {:.1} ms on {}",
        scene.name,
        frame.vpls,
        frame.passes.iter().map(|p| p.name()).collect::<Vec<_>>(),
        frame.frame_ms(),
        ctx.adapter_name
    );

    // What the host would do with its texture; here: read it back and write a PNG.
    let bytes = fuzzy_vpl_core::gpu::read_texture(&ctx.device, &ctx.queue, &texture)?;
    let radiance: Vec<[f32; 3]> = bytes
        .chunks_exact(16)
        .map(|t| {
            let p: [f32; 4] = bytemuck::pod_read_unaligned(t);
            [p[0], p[1], p[2]]
        })
        .collect();
    let mean =
        radiance.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / (3 * radiance.len()) as f32;
    let exposure = fuzzy_vpl_core::exposure::auto_exposure(&radiance);
    fuzzy_vpl_core::export::write_png_rgb8(
        &out,
        w,
        h,
        fuzzy_vpl_core::export::to_srgb8(&radiance, exposure),
    )?;
    println!("wrote {} (mean radiance {mean:.4})", out.display());
    if !(mean > 0.0 && mean.is_finite()) {
        bail!("the image is black or not finite (mean {mean})");
    }
    Ok(())
}
