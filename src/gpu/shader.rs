//! WGSL composition: a pass shader names the shared files it needs with `#import common/NAME.wgsl`
//! lines; they are inlined once each, in order, before naga parses the result. This is all the
//! composition the project needs, so it does without naga_oil.

use std::collections::HashSet;

macro_rules! wgsl {
    ($($path:literal),* $(,)?) => {
        &[$(($path, include_str!(concat!("../../shaders-wgsl/", $path)))),*]
    };
}

/// Every WGSL file of the project, by path relative to `shaders-wgsl/`.
pub const FILES: &[(&str, &str)] = wgsl![
    "common/scene.wgsl",
    "common/bvh.wgsl",
    "common/rng.wgsl",
    "common/sampling.wgsl",
    "common/surface.wgsl",
    "common/lights.wgsl",
    "common/chunk.wgsl",
    "common/gbuffer.wgsl",
    "common/vpl.wgsl",
    "common/alpha.wgsl",
    "common/kmeans.wgsl",
    "common/nearest.wgsl",
    "kmeans/init.wgsl",
    "kmeans/grid.wgsl",
    "kmeans/iterate.wgsl",
    "kmeans/assign.wgsl",
    "kmeans/reps.wgsl",
    "raycast.wgsl",
    "primary.wgsl",
    "direct.wgsl",
    "vpl_trace.wgsl",
    "reference.wgsl",
    "pathtrace.wgsl",
    "kmeans.wgsl",
    "visibility.wgsl",
    "shade.wgsl",
    "wang.wgsl",
    "lightcluster.wgsl",
    "cvrtgi.wgsl",
];

/// The pass shaders (top-level files; `common/` holds shared code, `kmeans/` the steps of the
/// k-means pass), each composed and validated on its own.
pub fn pass_names() -> impl Iterator<Item = &'static str> {
    FILES
        .iter()
        .map(|(p, _)| *p)
        .filter(|p| !p.contains('/'))
        .map(|p| p.trim_end_matches(".wgsl"))
}

fn file(path: &str) -> Option<&'static str> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, s)| *s)
}

/// A file's source: the built-in copy, or with `FVPL_SHADER_DIR` set (shader development) the file
/// under that folder, so WGSL edits need no rebuild.
fn source(path: &str) -> Option<String> {
    match std::env::var_os("FVPL_SHADER_DIR") {
        Some(dir) => std::fs::read_to_string(std::path::Path::new(&dir).join(path)).ok(),
        None => file(path).map(str::to_string),
    }
}

/// The composed source of pass `name` (e.g. "primary").
pub fn compose(name: &str) -> String {
    let mut seen = HashSet::new();
    let mut out = String::new();
    inline(&format!("{name}.wgsl"), &mut seen, &mut out);
    out
}

fn inline(path: &str, seen: &mut HashSet<String>, out: &mut String) {
    if !seen.insert(path.to_string()) {
        return;
    }
    let src = source(path)
        .unwrap_or_else(|| panic!("unknown WGSL file {path} (add it to gpu::shader::FILES)"));
    for line in src.lines() {
        if let Some(dep) = line.trim().strip_prefix("#import ") {
            inline(dep.trim(), seen, out);
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
}

/// Parses and validates a composed shader with naga (no GPU needed).
pub fn validate(name: &str) -> Result<naga::Module, String> {
    let src = compose(name);
    let module = naga::front::wgsl::parse_str(&src).map_err(|e| e.emit_to_string(&src))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string(&src))?;
    Ok(module)
}

/// Creates the shader module for pass `name`.
pub fn module(device: &wgpu::Device, name: &str) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(compose(name).into()),
    };
    let mut checks = wgpu::ShaderRuntimeChecks::checked();
    if std::env::var_os("FVPL_NO_BOUNDS").is_some() {
        checks.bounds_checks = false;
    }
    if std::env::var_os("FVPL_NO_LOOPBOUND").is_some() {
        checks.force_loop_bounding = false;
    }
    unsafe { device.create_shader_module_trusted(desc, checks) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_wgsl_file_is_listed() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/shaders-wgsl");
        let mut on_disk = Vec::new();
        for sub in ["", "common/", "kmeans/"] {
            for e in std::fs::read_dir(format!("{dir}/{sub}")).unwrap() {
                let name = e.unwrap().file_name().into_string().unwrap();
                if name.ends_with(".wgsl") {
                    on_disk.push(format!("{sub}{name}"));
                }
            }
        }
        for f in &on_disk {
            assert!(
                file(f).is_some(),
                "{f} exists but is not in gpu::shader::FILES"
            );
        }
    }

    #[test]
    fn every_pass_shader_validates_under_naga() {
        let mut n = 0;
        for name in pass_names() {
            if let Err(e) = validate(name) {
                panic!("{name}.wgsl does not validate:\n{e}");
            }
            n += 1;
        }
        assert!(n >= 3);
    }
}
