//! WGSL composition: a pass shader names the shared files it needs with `#import common/NAME.wgsl`
//! lines; they are inlined once each, in order, before naga parses the result. `#import rust/NAME`
//! inlines a struct declared once in Rust for both sides (`gpu_struct!`, `rust_struct`). This is
//! all the composition the project needs, so it does without naga_oil.

use std::collections::HashSet;

/// Every WGSL file of the project, by path relative to `shaders-wgsl/`, in path order: listed by
/// `build.rs` from the folder, so a new pass (a method's included) adds its file and nothing else.
pub const FILES: &[(&str, &str)] = include!(concat!(env!("OUT_DIR"), "/wgsl_files.rs"));

/// The pass shaders (top-level files; `common/` holds shared code, the other folders the steps of
/// a pass split by stage), each composed and validated on its own.
pub fn pass_names() -> impl Iterator<Item = &'static str> {
    FILES
        .iter()
        .map(|(p, _)| *p)
        .filter(|p| !p.contains('/'))
        .map(|p| p.trim_end_matches(".wgsl"))
}

/// A `#[repr(C)]` struct a shader reads (a pass's uniform parameters), declared once: the Rust
/// struct (`Pod`) and `NAME::WGSL`, the same fields in WGSL, which a shader takes with
/// `#import rust/NAME` (`build.rs` finds the declaration). Field types: `u32`, `f32`,
/// `[u32; 4]` (`vec4<u32>`), `[f32; 4]` (`vec4<f32>`); the caller pads to 16 bytes.
macro_rules! gpu_struct {
    (
        $(#[$m:meta])*
        $vis:vis struct $name:ident {
            $($(#[$fm:meta])* $f:ident : $t:tt),* $(,)?
        }
    ) => {
        $(#[$m])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $($(#[$fm])* $f: $t),*
        }

        impl $name {
            /// The struct in WGSL (`#import rust/NAME`, `gpu::shader::rust_struct`).
            #[allow(dead_code)]
            pub const WGSL: &'static str = concat!(
                "struct ", stringify!($name), " {\n",
                $("    ", stringify!($f), ": ", $crate::gpu::shader::wgsl_type!($t), ",\n",)*
                "}\n"
            );
        }
    };
}
pub(crate) use gpu_struct;

/// The WGSL type of a `gpu_struct!` field's Rust type.
macro_rules! wgsl_type {
    (u32) => {
        "u32"
    };
    (f32) => {
        "f32"
    };
    ([u32; 4]) => {
        "vec4<u32>"
    };
    ([f32; 4]) => {
        "vec4<f32>"
    };
}
pub(crate) use wgsl_type;

/// The WGSL of struct `name` declared in Rust with `gpu_struct!` (what `#import rust/NAME`
/// inlines): `build.rs` writes it from the declaration's text, and the declaring module's test
/// checks it against the macro's `NAME::WGSL`.
pub fn rust_struct(name: &str) -> Option<&'static str> {
    file(&format!("rust/{name}"))
}

fn file(path: &str) -> Option<&'static str> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, s)| *s)
}

/// The most bytes a WGSL file under `FVPL_SHADER_DIR` may hold.
pub const MAX_SOURCE_BYTES: u64 = 4 << 20;

/// A file's source: the built-in copy, or with `FVPL_SHADER_DIR` set (shader development) the file
/// under that folder, so WGSL edits need no rebuild. The error says why the file cannot be had.
fn source(path: &str) -> Result<String, String> {
    match std::env::var_os(SHADER_DIR_ENV) {
        Some(dir) => {
            let file = std::path::Path::new(&dir).join(path);
            crate::files::read_text(&file, MAX_SOURCE_BYTES, "a WGSL file")
                .map_err(|e| format!("{SHADER_DIR_ENV}: {}: cannot read: {e}", file.display()))
        }
        None => file(path)
            .map(str::to_string)
            .ok_or_else(|| format!("unknown WGSL file {path} (not under shaders-wgsl/)")),
    }
}

/// The variable naming a folder of WGSL files read instead of the built-in ones.
pub const SHADER_DIR_ENV: &str = "FVPL_SHADER_DIR";

/// The composed source of pass `name` (e.g. "primary"). Panics on a missing file: `cli` checks
/// every pass composes (`try_compose`) before any work when `FVPL_SHADER_DIR` is set.
pub fn compose(name: &str) -> String {
    try_compose(name).unwrap_or_else(|e| panic!("{e}"))
}

/// The composed source of pass `name`, or why a file it needs cannot be read.
pub fn try_compose(name: &str) -> Result<String, String> {
    let mut seen = HashSet::new();
    let mut out = String::new();
    inline(&format!("{name}.wgsl"), &mut seen, &mut out)?;
    Ok(out)
}

fn inline(path: &str, seen: &mut HashSet<String>, out: &mut String) -> Result<(), String> {
    if !seen.insert(path.to_string()) {
        return Ok(());
    }
    let src = match path.strip_prefix("rust/") {
        // Always the built-in text: it is the Rust struct's (`rust_struct`).
        Some(name) => rust_struct(name)
            .map(str::to_string)
            .ok_or_else(|| format!("unknown Rust struct {name} (no gpu_struct! declares it)"))?,
        None => source(path)?,
    };
    for line in src.lines() {
        if let Some(dep) = line.trim().strip_prefix("#import ") {
            inline(dep.trim(), seen, out)?;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    Ok(())
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

/// Whether values of type `ty` hold an array (an array, or a struct with one at any depth).
fn holds_array(types: &naga::UniqueArena<naga::Type>, ty: naga::Handle<naga::Type>) -> bool {
    match &types[ty].inner {
        naga::TypeInner::Array { .. } | naga::TypeInner::BindingArray { .. } => true,
        naga::TypeInner::Struct { members, .. } => members.iter().any(|m| holds_array(types, m.ty)),
        _ => false,
    }
}

/// The functions of `module` with a parameter that is an array, or a struct holding one, passed by
/// value, as `function(parameter)`. A GPU compiler copies such an argument through local memory on
/// every call: `eq9_weighted_visibility` taking two 16-element arrays by value, called once per
/// light per pixel, made the fuzzy shade pass 8-13x slower on an H100 with the same images
/// (docs/architecture.md, "WGSL for real GPUs"). Pass a `ptr<function, ...>` instead. Read from
/// naga's IR, so comments, formatting and aliases cannot hide one.
pub fn by_value_array_parameters(module: &naga::Module) -> Vec<String> {
    let functions = module
        .functions
        .iter()
        .map(|(_, f)| f)
        .chain(module.entry_points.iter().map(|e| &e.function));
    let mut found = Vec::new();
    for f in functions {
        for (i, a) in f.arguments.iter().enumerate() {
            if holds_array(&module.types, a.ty) {
                let name = f.name.as_deref().unwrap_or("<unnamed>");
                let arg = a.name.clone().unwrap_or_else(|| format!("#{i}"));
                found.push(format!("{name}({arg})"));
            }
        }
    }
    found
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

/// The bind-group layout of `entries` (group 0) and the compute pipelines of shader `name`'s
/// `entry_points` over it, for passes that own their resources outside `gi::dispatch::Kernel` (the
/// display, the reprojection, `gi::compose`).
pub fn compute_pipelines<const N: usize>(
    device: &wgpu::Device,
    name: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
    entry_points: [&str; N],
) -> (wgpu::BindGroupLayout, [wgpu::ComputePipeline; N]) {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(name),
        entries,
    });
    let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(name),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let module = module(device, name);
    let pipelines = entry_points.map(|entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pl),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    });
    (layout, pipelines)
}

#[cfg(test)]
mod tests {
    use super::*;

    gpu_struct! {
        struct Two {
            /// A doc comment stays Rust's.
            a: [f32; 4],
            b: u32,
        }
    }

    /// `gpu_struct!`'s WGSL by hand, and its import.
    #[test]
    fn a_rust_struct_is_its_wgsl() {
        let want = "struct Two {\n    a: vec4<f32>,\n    b: u32,\n}\n";
        assert_eq!(Two::WGSL, want);
        assert_eq!(std::mem::size_of::<Two>(), 20);
        let mut out = String::new();
        inline("rust/VisParams", &mut HashSet::new(), &mut out).unwrap();
        assert!(out.starts_with("struct VisParams {\n"), "{out}");
        let e = inline("rust/Nope", &mut HashSet::new(), &mut String::new()).unwrap_err();
        assert!(e.contains("unknown Rust struct Nope"), "{e}");
    }

    #[test]
    fn every_wgsl_file_is_listed() {
        // Walked here on its own (not with build.rs's walk): every folder, however deep.
        fn walk(dir: &std::path::Path, rel: &str, out: &mut Vec<String>) {
            for e in std::fs::read_dir(dir).unwrap() {
                let e = e.unwrap();
                let name = e.file_name().into_string().unwrap();
                if e.path().is_dir() {
                    walk(&e.path(), &format!("{rel}{name}/"), out);
                } else if name.ends_with(".wgsl") {
                    out.push(format!("{rel}{name}"));
                }
            }
        }
        let mut on_disk = Vec::new();
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../shaders-wgsl");
        walk(std::path::Path::new(dir), "", &mut on_disk);
        for f in &on_disk {
            assert!(
                file(f).is_some(),
                "{f} exists but is not in gpu::shader::FILES (build.rs)"
            );
        }
        let files = FILES.iter().filter(|(p, _)| !p.starts_with("rust/"));
        assert_eq!(
            on_disk.len(),
            files.count(),
            "FILES lists a file not on disk"
        );
        assert!(
            on_disk.iter().any(|f| f.starts_with("common/")),
            "{on_disk:?}"
        );
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

    /// The rule of docs/architecture.md, "WGSL for real GPUs": no function takes an array by value.
    #[test]
    fn no_wgsl_function_takes_an_array_by_value() {
        let mut found = Vec::new();
        for name in pass_names() {
            let module = validate(name).unwrap_or_else(|e| panic!("{name}.wgsl: {e}"));
            found.extend(
                by_value_array_parameters(&module)
                    .into_iter()
                    .map(|f| format!("{name}.wgsl: {f}")),
            );
        }
        assert!(
            found.is_empty(),
            "WGSL functions taking an array (or a struct holding one) by value; pass a \
             ptr<function, ...> instead (docs/architecture.md):\n{}",
            found.join("\n")
        );
    }

    /// The rule finds a planted by-value array, directly, in a struct, behind an alias and in a
    /// nested struct, and lets pointers and plain values through.
    #[test]
    fn the_by_value_rule_names_planted_functions() {
        let src = "
            alias Row = array<u32, 4>;
            struct Slots { w: array<f32, 4>, n: u32 }
            struct Outer { s: Slots }
            struct Plain { a: vec4<f32>, b: u32 }
            fn direct(a: array<f32, 4>) -> f32 { return a[0]; }
            fn aliased(x: u32, r: Row) -> u32 { return r[x & 3u]; }
            fn in_struct(s: Slots) -> f32 { return s.w[0]; }
            fn nested(o: Outer) -> u32 { return o.s.n; }
            fn by_pointer(a: ptr<function, array<f32, 4>>) -> f32 { return (*a)[0]; }
            fn plain(p: Plain, v: vec3<f32>) -> f32 { return p.a.x + v.y; }
            @compute @workgroup_size(1)
            fn main() {
                var a: array<f32, 4>;
                var s: Slots;
                var o: Outer;
                let x = direct(a) + in_struct(s) + by_pointer(&a) + plain(Plain(), vec3<f32>());
                let y = aliased(1u, Row()) + nested(o);
            }
        ";
        let module = naga::front::wgsl::parse_str(src).unwrap();
        assert_eq!(
            by_value_array_parameters(&module),
            ["direct(a)", "aliased(r)", "in_struct(s)", "nested(o)"]
        );
    }
}
