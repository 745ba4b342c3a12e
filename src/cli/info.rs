//! `fuzzy-vpl info`: what a scene holds and which passes would run.

use anyhow::Result;
use clap::Args;

use super::scene::SceneArgs;
use crate::render::{RenderSettings, Renderer};
use crate::scene::{self, Scene};

#[derive(Args)]
pub struct InfoArgs {
    #[command(flatten)]
    scene: SceneArgs,
}

/// Fixed decimals for everyday units, exponents for scenes in other units (1e-15 or 1e12).
fn num(x: f32, d: usize) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        format!("{x:.d$}")
    } else {
        format!("{x:.3e}")
    }
}

fn print_cameras(s: &Scene) {
    println!("cameras:             {}", s.cameras.len());
    for (i, c) in s.cameras.iter().enumerate() {
        let e = c.eye();
        println!(
            "  [{i}] {:<16} eye ({}, {}, {}) yfov {:.1} deg",
            c.name,
            num(e.x, 3),
            num(e.y, 3),
            num(e.z, 3),
            c.yfov.to_degrees()
        );
    }
}

pub fn run(a: InfoArgs) -> Result<()> {
    let s = a.scene.load()?;
    let (lo, hi) = s.bounds();
    println!("scene:               {}", a.scene.scene);
    println!("triangles:           {}", s.triangles.len());
    println!("dropped degenerate:  {}", s.report.dropped_degenerate);
    println!(
        "generated normals:   {} triangles",
        s.report.generated_normals
    );
    println!("materials:           {}", s.materials.len());
    println!("textures:            {}", s.textures.len());
    println!("emissive triangles:  {}", s.emissive_triangle_count());
    let kinds = |k: fn(&scene::LightKind) -> bool| s.lights.iter().filter(|l| k(&l.kind)).count();
    println!(
        "punctual lights:     {} (point {}, spot {}, directional {})",
        s.lights.len(),
        kinds(|k| matches!(k, scene::LightKind::Point)),
        kinds(|k| matches!(k, scene::LightKind::Spot { .. })),
        kinds(|k| matches!(k, scene::LightKind::Directional)),
    );
    print_cameras(&s);
    println!(
        "bounds:              ({}, {}, {}) .. ({}, {}, {})",
        num(lo.x, 4),
        num(lo.y, 4),
        num(lo.z, 4),
        num(hi.x, 4),
        num(hi.y, 4),
        num(hi.z, 4)
    );
    let g = s.geometry_scale();
    if g != 1.0 {
        println!(
            "unit frame:          rendered with the geometry scaled by 2^{} (Scene::geometry_scale)",
            g.log2().round() as i32
        );
    }
    match crate::gi::scene_gpu::check_fits(&s, u64::MAX) {
        Ok(()) => println!(
            "GPU data:            {} of at most {} triangles",
            s.triangles.len(),
            crate::gi::scene_gpu::MAX_TRIANGLES
        ),
        Err(e) => println!("GPU data:            does not fit: {e}"),
    }
    println!(
        "extensions used:     {}",
        s.report.extensions_used.join(", ")
    );
    println!("features:            {}", s.features().join(", "));
    let passes: Vec<&str> = Renderer::passes_for(&s, &RenderSettings::default())
        .iter()
        .map(|p| p.name())
        .collect();
    println!("passes (render):     {}", passes.join(" -> "));
    let tested = s.alpha_test_flags().into_iter().filter(|&f| f).count();
    if tested > 0 {
        let materials = s
            .materials
            .iter()
            .filter(|m| m.alpha_cutoff.is_some())
            .count();
        println!(
            "alpha test:          {tested} triangles ({materials} alpha-masked materials); in every pass that traces rays"
        );
    } else {
        println!("alpha test:          none (the passes are compiled without it)");
    }
    Ok(())
}
