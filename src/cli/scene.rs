//! What every subcommand that opens a scene shares: the scene argument, its added lights, and the
//! checks of what the device holds.

use anyhow::Result;
use clap::Args;

use crate::gpu::GpuContext;
use crate::input::bad;
use crate::scene::{self, Scene, extra_lights};
use crate::settings::{ClusterSettings, FrameSettings, LightSettings};

#[derive(Args, Clone)]
pub struct SceneArgs {
    /// A .gltf/.glb path or builtin:NAME (builtin:cornell, builtin:conference).
    #[arg(default_value = "builtin:cornell")]
    pub scene: String,
    #[command(flatten)]
    pub lights: LightSettings,
    /// Load a file that requires glTF extension NAME, which fuzzy-vpl does not know, ignoring it
    /// (repeatable). Only for extensions that change neither geometry nor diffuse colour.
    #[arg(long, value_name = "NAME")]
    pub allow_extension: Vec<String>,
    /// Let the scene's buffer and image URIs name files outside its folder (absolute paths,
    /// file: URIs, '..' or symbolic links leading out), which are refused otherwise: a scene from
    /// elsewhere could read any file you can and show it in the image.
    #[arg(long)]
    pub allow_outside_uris: bool,
}

/// What a picture is made with: the camera, the frame and the clustering (`render` and `view`).
#[derive(Args)]
pub struct ShotArgs {
    /// Use the Nth glTF camera (0-based); default: the scene's first camera, else a view of its
    /// bounds.
    #[arg(long)]
    pub camera: Option<usize>,
    #[command(flatten)]
    pub frame: FrameSettings,
    #[command(flatten)]
    pub cluster: ClusterSettings,
    #[command(flatten)]
    pub method: crate::method::MethodSettings,
}

impl ShotArgs {
    /// With `--paper`, the frame and clustering at the paper's choices where the command line
    /// (`given`: the ids of the options it gave) did not set them (`settings::paper::apply`).
    pub fn apply_paper(&mut self, given: &[String]) {
        if self.cluster.paper {
            let given = |id: &str| given.iter().any(|g| g == id);
            crate::settings::paper::apply(&mut self.frame, &mut self.cluster, &given);
        }
    }
}

impl SceneArgs {
    /// The scene with the added lights and the emitter scale; warns about what the loader dropped
    /// and about a scene without light.
    pub fn load(&self) -> Result<Scene> {
        let opts = scene::LoadOptions {
            allow_extensions: self.allow_extension.clone(),
            allow_outside_uris: self.allow_outside_uris,
        };
        let mut s = scene::load_with(&self.scene, &opts)?;
        // The scene and its files are inputs no output of the run may replace.
        let mut inputs: Vec<(&str, &std::path::Path)> = s
            .report
            .files
            .iter()
            .map(|f| ("the scene's file", f.as_path()))
            .collect();
        if let Some(p) = &s.path {
            inputs.push(("the scene", p.as_path()));
        }
        crate::files::note_inputs(&inputs);
        for w in &s.report.warnings {
            eprintln!("warning: {}: {w}", self.scene);
        }
        let l = &self.lights;
        for v in &l.sun {
            s.lights
                .push(extra_lights::parse_sun(v).map_err(|e| bad(format!("--sun {v}: {e}")))?);
        }
        for v in &l.point {
            s.lights
                .push(extra_lights::parse_point(v).map_err(|e| bad(format!("--point {v}: {e}")))?);
        }
        // The scaled emitters and the image they light must stay within f32: above 1e36 the image
        // overflows, below 1e-44 it rounds to 0.
        let brightest = s.max_emission() * l.light_scale as f64;
        if brightest > 0.0 && !(1e-44..=1e36).contains(&brightest) {
            return Err(bad(format!(
                "{}: the brightest emitter emits {brightest:.3e} with --light-scale {}; outside 1e-44..1e36 the image does not fit in f32",
                self.scene, l.light_scale
            )));
        }
        s.scale_light_power(l.light_scale as f64);
        if !s.has_light() {
            eprintln!(
                "warning: {}: the scene has no light (no emissive material, no punctual light of non-zero power); it renders black. Add one with --sun or --point.",
                self.scene
            );
        }
        Ok(s)
    }

    /// The scene's camera `index`, or its default view.
    pub fn camera(&self, scene: &Scene, index: Option<usize>) -> Result<scene::Camera> {
        match index {
            Some(i) => scene.cameras.get(i).cloned().ok_or_else(|| {
                bad(format!(
                    "{}: --camera {i}: the scene has {} camera(s)",
                    self.scene,
                    scene.cameras.len()
                ))
            }),
            None => Ok(scene.default_camera()),
        }
    }
}

/// The most VPLs this device holds (`render::check_vpls`), as bad input.
pub fn check_vpls(ctx: &GpuContext, vpls: u32) -> Result<()> {
    crate::render::check_vpls(ctx, vpls).map_err(bad)
}

/// The largest image this device renders: each per-pixel buffer is one storage binding.
pub fn check_size(ctx: &GpuContext, width: u32, height: u32, bytes_per_pixel: u64) -> Result<()> {
    crate::render::check_frame_size(ctx, width, height, bytes_per_pixel).map_err(|e| {
        bad(format!(
            "--width/--height {width}x{height}: {} pixels, at most {} on this adapter ({} bytes a pixel in one {}-byte storage binding)",
            width as u64 * height as u64,
            e.most,
            e.bytes,
            e.binding
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--vpls` may fill the VPL buffer's binding exactly, not one VPL more (cargo-mutants: `>` as `>=`
    /// survived; the tests asked only for far too many).
    #[test]
    fn vpls_may_fill_the_binding_exactly() {
        let ctx = GpuContext::new_headless().unwrap();
        let most = ctx.max_binding() / crate::gi::vpl_trace::VPL_BYTES;
        let most = u32::try_from(most).unwrap_or(u32::MAX);
        assert!(check_vpls(&ctx, most).is_ok());
        if most < u32::MAX {
            assert!(check_vpls(&ctx, most + 1).is_err());
        }
    }
}
