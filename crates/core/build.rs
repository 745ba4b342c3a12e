//! Lists every WGSL file under `shaders-wgsl/` for `gpu::shader::FILES` (a pass's shader, a
//! method's included, is found by its file alone: no list to edit), and adds `rust/NAME`, the WGSL
//! of each struct declared in Rust with `gpu_struct!` under `src/` (a shader's `#import
//! rust/NAME`): read from the declaration's text here, so that the shader composition names no
//! module that declares one (each such module's test checks the text against the macro's
//! `NAME::WGSL`).

use std::path::Path;

/// The paths in `dir`, sorted (the lists do not depend on the file system's order).
fn sorted(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    entries
}

fn walk(dir: &Path, rel: &str, out: &mut Vec<String>) {
    for p in sorted(dir) {
        let name = p.file_name().unwrap().to_str().expect("UTF-8 file names");
        if p.is_dir() {
            walk(&p, &format!("{rel}{name}/"), out);
        } else if name.ends_with(".wgsl") {
            out.push(format!("{rel}{name}"));
        }
    }
}

/// The WGSL type of a `gpu_struct!` field's Rust type (as `gpu::shader::wgsl_type!`).
fn wgsl_type(t: &str) -> &'static str {
    match t.split_whitespace().collect::<String>().as_str() {
        "u32" => "u32",
        "f32" => "f32",
        "[u32;4]" => "vec4<u32>",
        "[f32;4]" => "vec4<f32>",
        other => panic!("gpu_struct!: field type {other} has no WGSL type here"),
    }
}

/// Every `gpu_struct!` under `dir` as (name, WGSL text), the text as `NAME::WGSL` writes it.
fn rust_structs(dir: &Path, out: &mut Vec<(String, String)>) {
    for p in sorted(dir) {
        if p.is_dir() {
            rust_structs(&p, out);
            continue;
        }
        if p.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let src = std::fs::read_to_string(&p).expect("a source file");
        // Not a unit test's own struct.
        let src = src.split("#[cfg(test)]").next().unwrap_or_default();
        for (at, _) in src.match_indices("gpu_struct! {") {
            let body = &src[at..];
            let head = body.find("struct ").expect("gpu_struct!: a struct") + "struct ".len();
            let open = body[head..].find('{').expect("gpu_struct!: its fields") + head;
            let close = body[open..].find('}').expect("gpu_struct!: its end") + open;
            let name = body[head..open].trim().to_string();
            if name.starts_with('$') {
                continue; // the macro's own definition
            }
            let mut wgsl = format!("struct {name} {{\n");
            for line in body[open + 1..close].lines().map(str::trim) {
                if line.is_empty() || line.starts_with("///") || line.starts_with('#') {
                    continue;
                }
                let (field, ty) = line.trim_end_matches(',').split_once(':').expect("a field");
                wgsl += &format!("    {}: {},\n", field.trim(), wgsl_type(ty));
            }
            wgsl += "}\n";
            out.push((name, wgsl));
        }
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders-wgsl");
    println!("cargo:rerun-if-changed=../../shaders-wgsl");
    let mut files = Vec::new();
    walk(&root, "", &mut files);
    let mut code = String::from("&[\n");
    // Each path is resolved where the crate compiles (`CARGO_MANIFEST_DIR` at compile time), not
    // where this script last ran: a target directory copied into another checkout (a worktree)
    // then reads that checkout's shaders, not the original's.
    for f in &files {
        code += &format!(
            "    ({f:?}, include_str!(concat!(env!(\"CARGO_MANIFEST_DIR\"), {:?}))),\n",
            format!("/../../shaders-wgsl/{f}")
        );
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    println!("cargo:rerun-if-changed=src");
    let mut structs = Vec::new();
    rust_structs(&src, &mut structs);
    for (name, wgsl) in &structs {
        code += &format!("    (\"rust/{name}\", {wgsl:?}),\n");
    }
    code += "]\n";
    let out = Path::new(&std::env::var("OUT_DIR").unwrap()).join("wgsl_files.rs");
    std::fs::write(out, code).expect("writing wgsl_files.rs");
}
