//! Lists every WGSL file under `shaders-wgsl/` for `gpu::shader::FILES` (a pass's shader, a
//! method's included, is found by its file alone: no list to edit).

use std::path::Path;

fn walk(dir: &Path, rel: &str, out: &mut Vec<String>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        let name = p.file_name().unwrap().to_str().expect("UTF-8 file names");
        if p.is_dir() {
            walk(&p, &format!("{rel}{name}/"), out);
        } else if name.ends_with(".wgsl") {
            out.push(format!("{rel}{name}"));
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
    code += "]\n";
    let out = Path::new(&std::env::var("OUT_DIR").unwrap()).join("wgsl_files.rs");
    std::fs::write(out, code).expect("writing wgsl_files.rs");
}
