//! glTF loading: crafted valid and malformed files, the assimp glTF test corpus, and the real scenes.

use fuzzy_vpl::scene::{self, LightKind, Scene, SceneError, builtin, gltf_load};
use glam::{Vec2, Vec3, Vec4};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

mod common;

// ---------------------------------------------------------------------------------------------
// Helpers

/// A fresh, empty directory for one test, removed when dropped.
struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn temp_dir(test: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("fuzzy-vpl-scene-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

fn b64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Little-endian bytes of f32 vectors, as a glTF float accessor stores them.
fn le_bytes<const N: usize>(data: &[[f32; N]]) -> Vec<u8> {
    data.iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect()
}

/// A glTF document under construction with one binary buffer.
struct Doc {
    json: Value,
    bin: Vec<u8>,
}

impl Doc {
    fn new() -> Doc {
        Doc {
            json: json!({"asset": {"version": "2.0"}, "bufferViews": [], "accessors": [],
                         "meshes": [], "nodes": [], "scenes": [{"nodes": []}], "scene": 0}),
            bin: Vec::new(),
        }
    }

    fn arr(&mut self, key: &str) -> &mut Vec<Value> {
        if self.json.get(key).is_none() {
            self.json[key] = json!([]);
        }
        self.json[key].as_array_mut().unwrap()
    }

    fn push(&mut self, key: &str, v: Value) -> usize {
        let a = self.arr(key);
        a.push(v);
        a.len() - 1
    }

    fn view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(s) = stride {
            v["byteStride"] = json!(s);
        }
        self.bin.extend_from_slice(bytes);
        self.push("bufferViews", v)
    }

    fn floats<const N: usize>(&mut self, data: &[[f32; N]], ty: &str, bounds: bool) -> usize {
        let view = self.view(&le_bytes(data), None);
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": data.len(), "type": ty});
        if bounds {
            let lo: Vec<f32> = (0..N)
                .map(|c| data.iter().map(|v| v[c]).fold(f32::INFINITY, f32::min))
                .collect();
            let hi: Vec<f32> = (0..N)
                .map(|c| data.iter().map(|v| v[c]).fold(f32::NEG_INFINITY, f32::max))
                .collect();
            let fix = |v: Vec<f32>| -> Vec<f32> {
                v.into_iter()
                    .map(|x| if x.is_finite() { x } else { 0.0 })
                    .collect()
            };
            a["min"] = json!(fix(lo));
            a["max"] = json!(fix(hi));
        }
        self.push("accessors", a)
    }

    fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        self.floats(p, "VEC3", true)
    }

    fn indices(&mut self, idx: &[u32]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| (*i as u16).to_le_bytes()).collect();
        let view = self.view(&bytes, None);
        self.push("accessors", json!({"bufferView": view, "componentType": 5123, "count": idx.len(), "type": "SCALAR"}))
    }

    /// A VEC3 float accessor of 3 elements without a bufferView (zeros) whose elements 1 and 2 are
    /// replaced by (0, 0, 5) and (0, 3, 5) (sparse indices: unsigned bytes in view `indices`; values
    /// in view `values`); `max` its declared bound.
    fn sparse_vec3(&mut self, indices: usize, values: usize, max: [f32; 3]) -> usize {
        self.push(
            "accessors",
            json!({"componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0, 0, 0], "max": max,
            "sparse": {"count": 2, "indices": {"bufferView": indices, "componentType": 5121},
                       "values": {"bufferView": values}}}),
        )
    }

    /// A document of one triangle (with texture coordinates) per image of `images`, each with its
    /// own material whose base colour texture shows that image.
    fn textured(images: Value) -> Doc {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let uv = d.floats(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], "VEC2", false);
        let n = images.as_array().unwrap().len();
        d.json["images"] = images;
        d.json["textures"] = json!((0..n).map(|i| json!({"source": i})).collect::<Vec<_>>());
        d.json["materials"] = json!(
            (0..n)
                .map(|i| json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}))
                .collect::<Vec<_>>()
        );
        for mat in 0..n {
            let m =
                d.mesh(json!({"attributes": {"POSITION": p, "TEXCOORD_0": uv}, "material": mat}));
            d.node(json!({"mesh": m}), true);
        }
        d
    }

    /// The values of `sparse_vec3`'s substitution.
    const SPARSE_VALUES: [[f32; 3]; 2] = [[0.0, 0.0, 5.0], [0.0, 3.0, 5.0]];

    /// A mesh with one primitive (attributes by accessor index).
    fn mesh(&mut self, prim: Value) -> usize {
        self.push("meshes", json!({"primitives": [prim]}))
    }

    /// A node, added to the scene's roots when `root`.
    fn node(&mut self, v: Value, root: bool) -> usize {
        let i = self.push("nodes", v);
        if root {
            self.json["scenes"][0]["nodes"]
                .as_array_mut()
                .unwrap()
                .push(json!(i));
        }
        i
    }

    /// Triangle (0,0,0), (1,0,0), (0,1,0), optionally with +Z normals; returns the mesh.
    fn triangle_mesh(&mut self, normals: bool) -> usize {
        let p = self.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let mut attrs = json!({"POSITION": p});
        if normals {
            attrs["NORMAL"] = json!(self.floats(&[[0.0, 0.0, 1.0]; 3], "VEC3", false));
        }
        self.mesh(json!({"attributes": attrs}))
    }

    fn with_buffer(&self, uri: Option<String>) -> Value {
        let mut j = self.json.clone();
        let mut b = json!({"byteLength": self.bin.len()});
        if let Some(u) = uri {
            b["uri"] = json!(u);
        }
        j["buffers"] = json!([b]);
        j
    }

    /// Writes `NAME.gltf` + `NAME.bin`.
    fn write_gltf(&self, dir: &Path, name: &str) -> PathBuf {
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        let j = self.with_buffer(Some(format!("{name}.bin")));
        std::fs::write(&path, serde_json::to_vec_pretty(&j).unwrap()).unwrap();
        path
    }

    /// A self-contained glTF with the buffer as a data: URI.
    fn embedded(&self) -> Vec<u8> {
        let uri = format!("data:application/octet-stream;base64,{}", b64(&self.bin));
        serde_json::to_vec(&self.with_buffer(Some(uri))).unwrap()
    }

    fn glb(&self) -> Vec<u8> {
        let mut j = serde_json::to_vec(&self.with_buffer(None)).unwrap();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        let mut bin = self.bin.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + j.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(j.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&j);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

fn load_ok(path: &Path) -> Scene {
    gltf_load::load_path(path)
        .unwrap_or_else(|e| panic!("expected {} to load: {e}", path.display()))
}

/// The load's warnings that contain every one of `words`.
fn warnings_with<'a>(s: &'a Scene, words: &[&str]) -> Vec<&'a String> {
    s.report
        .warnings
        .iter()
        .filter(|w| words.iter().all(|x| w.contains(x)))
        .collect()
}

fn load_slice_ok(bytes: &[u8], name: &str) -> Scene {
    gltf_load::load_slice(bytes, name).unwrap_or_else(|e| panic!("expected {name} to load: {e}"))
}

/// Asserts a load failed with a one-line message naming the file and containing `needle`.
fn assert_err(result: Result<Scene, SceneError>, file: &str, needle: &str) -> String {
    let e = match result {
        Ok(s) => panic!(
            "expected {file} to fail, it loaded {} triangles",
            s.triangles.len()
        ),
        Err(e) => e.to_string(),
    };
    assert!(e.contains(file), "error does not name {file}: {e}");
    assert!(
        !e.contains('\n') && !e.contains('\r'),
        "error is not one line: {e:?}"
    );
    assert!(
        e.to_lowercase().contains(&needle.to_lowercase()),
        "error for {file} should mention '{needle}': {e}"
    );
    assert!(!e.contains("internal error"), "loader panicked: {e}");
    e
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// Every triangle's positions and normals are finite.
fn vertices_finite(s: &Scene) -> bool {
    s.triangles
        .iter()
        .all(|t| t.p.iter().chain(&t.n).all(|v| v.is_finite()))
}

// ---------------------------------------------------------------------------------------------
// Malformed files

#[test]
fn bad_json() {
    let dir = temp_dir("bad_json");
    let p = dir.join("broken.gltf");
    std::fs::write(&p, b"{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [ }").unwrap();
    assert_err(gltf_load::load_path(&p), "broken.gltf", "json");
    let p = dir.join("wrongtype.gltf");
    std::fs::write(&p, br#"{"asset": {"version": "2.0"}, "scene": "zero"}"#).unwrap();
    assert_err(gltf_load::load_path(&p), "wrongtype.gltf", "invalid glTF");
    let p = dir.join("empty.gltf");
    std::fs::write(&p, b"").unwrap();
    assert_err(gltf_load::load_path(&p), "empty.gltf", "json");

    // The validation names two errors (nodes of meshes that do not exist); past two, it counts
    // the rest (cargo-mutants: the count's `>` as `==`, `<` or `>=` survived).
    for n in [2, 3] {
        let mut d = Doc::new();
        for k in 0..n {
            d.node(json!({ "mesh": 40 + k }), true);
        }
        let name = format!("errors{n}");
        let e = assert_err(
            gltf_load::load_path(&d.write_gltf(&dir, &name)),
            &format!("{name}.gltf"),
            "invalid glTF: ",
        );
        assert_eq!(e.matches("mesh: Index out of bounds").count(), 2, "{e}");
        assert_eq!(e.contains(" more)"), n == 3, "{e}");
        if n == 3 {
            assert!(e.ends_with(" (and 1 more)"), "{e}");
        }
    }
}

#[test]
fn unreadable_file() {
    let dir = temp_dir("unreadable");
    assert_err(
        gltf_load::load_path(&dir.join("nothing.glb")),
        "nothing.glb",
        "cannot read",
    );
    assert_err(
        scene::load(dir.join("nothing.gltf").to_str().unwrap()),
        "nothing.gltf",
        "cannot read",
    );
}

#[test]
fn truncated_and_wrong_magic_glb() {
    let dir = temp_dir("glb");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    let glb = d.glb();
    let ok = dir.join("ok.glb");
    std::fs::write(&ok, &glb).unwrap();
    assert_eq!(load_ok(&ok).triangles.len(), 1);
    assert_eq!(
        gltf_load::load_slice(&glb, "mem.glb")
            .unwrap()
            .triangles
            .len(),
        1
    );

    let cut = dir.join("half.glb");
    std::fs::write(&cut, &glb[..glb.len() / 2]).unwrap();
    assert_err(gltf_load::load_path(&cut), "half.glb", "truncated");
    let tiny = dir.join("tiny.glb");
    std::fs::write(&tiny, &glb[..7]).unwrap();
    assert_err(
        gltf_load::load_path(&tiny),
        "tiny.glb",
        "truncated GLB: 7 bytes, less than the 12-byte header",
    );

    // The needles below are whole messages, not words of the file names (which hold "glb" and
    // "magic"): the chunk's comes from `glb_error` (cargo-mutants: it returning "" or "xyzzy"
    // survived).
    let mut bad = glb.clone();
    bad[3] = b'X';
    let magic = dir.join("magic.glb");
    std::fs::write(&magic, &bad).unwrap();
    assert_err(
        gltf_load::load_path(&magic),
        "magic.glb",
        "not a binary glTF file: magic is \"glTX\", expected \"glTF\"",
    );

    // A chunk length pointing past the end.
    let mut bad = glb.clone();
    bad[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let chunk = dir.join("chunk.glb");
    std::fs::write(&chunk, &bad).unwrap();
    assert_err(
        gltf_load::load_path(&chunk),
        "chunk.glb",
        "truncated GLB: the JSON chunk declares 4294967295 bytes but only",
    );

    // A whole header that declares itself, and 16 bytes: no room for a chunk (20 bytes at least).
    // The 12-byte file is a header, not a truncated one (cargo-mutants: `< 12` as `<= 12`, and
    // `declared < 20` as `== 20`, survived).
    for n in [12usize, 16] {
        let mut head = glb[..n].to_vec();
        head[8..12].copy_from_slice(&(n as u32).to_le_bytes());
        assert_err(
            gltf_load::load_slice(&head, "head.glb"),
            "head.glb",
            &format!("corrupt GLB: header declares {n} bytes, too few for a JSON chunk"),
        );
    }
    // 20 bytes hold a JSON chunk's header: an empty JSON chunk, refused as JSON (`declared < 20`
    // as `<= 20` survived).
    let mut head = glb[..20].to_vec();
    head[8..12].copy_from_slice(&20u32.to_le_bytes());
    head[12..16].copy_from_slice(&0u32.to_le_bytes());
    assert_err(
        gltf_load::load_slice(&head, "head.glb"),
        "head.glb",
        "bad JSON: EOF while parsing",
    );

    // GLB version 1 is glTF 1.0.
    let mut v1 = glb.clone();
    v1[4] = 1;
    assert_err(
        gltf_load::load_slice(&v1, "old.glb"),
        "old.glb",
        "glTF 1.0 is not supported",
    );
}

#[test]
fn missing_or_short_buffer() {
    let dir = temp_dir("buffers");
    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(json!({"mesh": m}), true);
    let p = d.write_gltf(&dir, "nobin");
    std::fs::remove_file(dir.join("nobin.bin")).unwrap();
    let e = assert_err(gltf_load::load_path(&p), "nobin.gltf", "cannot read");
    assert!(e.contains("nobin.bin"), "{e}");

    // A buffer longer than its byteLength is read: a .bin file (read up to byteLength), a data:
    // URI (cargo-mutants: the length test's `<` as `>` survived).
    let p = d.write_gltf(&dir, "longbin");
    let mut long = d.bin.clone();
    long.extend_from_slice(&[0, 0, 0]);
    std::fs::write(dir.join("longbin.bin"), &long).unwrap();
    assert_eq!(load_ok(&p).triangles.len(), 1);
    let uri = format!("data:application/octet-stream;base64,{}", b64(&long));
    let j = serde_json::to_vec(&d.with_buffer(Some(uri))).unwrap();
    assert_eq!(load_slice_ok(&j, "long.gltf").triangles.len(), 1);

    // The .bin file is shorter than the buffer's byteLength.
    let p = d.write_gltf(&dir, "shortbin");
    std::fs::write(dir.join("shortbin.bin"), &d.bin[..10]).unwrap();
    assert_err(gltf_load::load_path(&p), "shortbin.gltf", "too short");

    // The buffer is long enough for its views, but an accessor reads past its view.
    let mut d = Doc::new();
    let pos = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    d.json["accessors"][pos]["count"] = json!(300);
    let m = d.mesh(json!({"attributes": {"POSITION": pos}}));
    d.node(json!({"mesh": m}), true);
    let p = d.write_gltf(&dir, "shortview");
    assert_err(gltf_load::load_path(&p), "shortview.gltf", "too short");
    // Its last element runs 4 bytes past the view: 4 + 2 · 12 + 12 = 40 bytes of 36 (the element's
    // size is added, not taken off: cargo-mutants' `+` as `-` in check_fits survived).
    d.json["accessors"][pos]["count"] = json!(3);
    d.json["accessors"][pos]["byteOffset"] = json!(4);
    let p = d.write_gltf(&dir, "lastpast");
    let e = assert_err(gltf_load::load_path(&p), "lastpast.gltf", "too short");
    assert!(
        e.contains("needs 40 bytes but its bufferView holds only 36"),
        "{e}"
    );

    // An accessor without a bufferView (zeros, then its sparse values) may declare up to 2^24
    // elements: one more is refused before anything is read.
    let mut d = Doc::new();
    let sidx = d.view(&[1, 2], None);
    let sval = d.view(&le_bytes(&Doc::SPARSE_VALUES), None);
    let pos = d.sparse_vec3(sidx, sval, [0.0, 3.0, 5.0]);
    let m = d.mesh(json!({"attributes": {"POSITION": pos}}));
    d.node(json!({"mesh": m}), true);
    d.json["accessors"][pos]["count"] = json!((1 << 24) + 1);
    let p = d.write_gltf(&dir, "viewless");
    assert_err(
        gltf_load::load_path(&p),
        "viewless.gltf",
        "has no bufferView and an implausible count 16777217",
    );
    // 2^24 itself is read (about a second): the sparse triangle, and the zeros' degenerate ones
    // dropped.
    d.json["accessors"][pos]["count"] = json!(1 << 24);
    let s = load_ok(&d.write_gltf(&dir, "viewless_max"));
    assert_eq!(s.triangles.len(), 1);

    // A bufferView lying outside its buffer (also caught).
    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(json!({"mesh": m}), true);
    d.json["bufferViews"][0]["byteOffset"] = json!(4000);
    let p = d.write_gltf(&dir, "viewout");
    assert_err(gltf_load::load_path(&p), "viewout.gltf", "outside");

    // External references cannot be resolved for in-memory scenes.
    let bytes = std::fs::read(dir.join("viewout.gltf")).unwrap();
    assert_err(
        gltf_load::load_slice(&bytes, "inmem.gltf"),
        "inmem.gltf",
        "in-memory",
    );
}

#[test]
fn index_out_of_range() {
    let dir = temp_dir("index");
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let i = d.indices(&[0, 1, 7]);
    let m = d.mesh(json!({"attributes": {"POSITION": p}, "indices": i}));
    d.node(json!({"mesh": m}), true);
    let path = d.write_gltf(&dir, "oob");
    assert_err(gltf_load::load_path(&path), "oob.gltf", "out of range");

    // Indices that are scalars of floats, or unsigned shorts two to an element, are refused: each is
    // wrong in one of the two respects only (cargo-mutants: the test's `||` as `&&` survived).
    for (name, ty, comp, count, bytes) in [
        (
            "float_indices",
            "SCALAR",
            5126,
            3,
            [0.0f32, 1.0, 2.0].map(f32::to_le_bytes).concat(),
        ),
        (
            "vec2_indices",
            "VEC2",
            5123,
            3,
            [0u16, 1, 2, 0, 1, 2].map(u16::to_le_bytes).concat(),
        ),
    ] {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let view = d.view(&bytes, None);
        let i = d.push(
            "accessors",
            json!({"bufferView": view, "componentType": comp, "count": count, "type": ty}),
        );
        let m = d.mesh(json!({"attributes": {"POSITION": p}, "indices": i}));
        d.node(json!({"mesh": m}), true);
        let path = d.write_gltf(&dir, name);
        assert_err(
            gltf_load::load_path(&path),
            &format!("{name}.gltf"),
            "must be a SCALAR of unsigned byte, short or int",
        );
    }

    // Normals of two components: skipped (normals generated) with a warning naming the type.
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let n = d.floats(&[[0.0, 1.0]; 3], "VEC2", false);
    let m = d.mesh(json!({"attributes": {"POSITION": p, "NORMAL": n}}));
    d.node(json!({"mesh": m}), true);
    let s = load_ok(&d.write_gltf(&dir, "vec2"));
    assert_eq!(s.report.generated_normals, 1);
    assert!(
        s.report
            .warnings
            .iter()
            .any(|w| w.contains("has type VEC2, expected 3 components; normals generated")),
        "{:?}",
        s.report.warnings
    );

    // An accessor index that does not exist (the gltf crate's validation).
    let mut d = Doc::new();
    let m = d.mesh(json!({"attributes": {"POSITION": 42}}));
    d.node(json!({"mesh": m}), true);
    let path = d.write_gltf(&dir, "noacc");
    assert_err(gltf_load::load_path(&path), "noacc.gltf", "invalid glTF");
    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(json!({"mesh": m, "children": [9]}), true);
    let path = d.write_gltf(&dir, "nochild");
    assert_err(
        gltf_load::load_path(&path),
        "nochild.gltf",
        "nodes[0].children",
    );
}

#[test]
fn non_finite_positions() {
    let dir = temp_dir("nonfinite");
    for (name, bad) in [
        ("nan", f32::NAN),
        ("inf", f32::INFINITY),
        ("neginf", f32::NEG_INFINITY),
    ] {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, bad, 0.0], [0.0, 1.0, 0.0]]);
        let m = d.mesh(json!({"attributes": {"POSITION": p}}));
        d.node(json!({"mesh": m}), true);
        let path = d.write_gltf(&dir, name);
        assert_err(
            gltf_load::load_path(&path),
            &format!("{name}.gltf"),
            "non-finite",
        );
    }
    // Finite in the file, infinite after the node transform.
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1e30, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let m = d.mesh(json!({"attributes": {"POSITION": p}}));
    d.node(json!({"mesh": m, "scale": [1e30, 1.0, 1.0]}), true);
    let path = d.write_gltf(&dir, "overflow");
    assert_err(gltf_load::load_path(&path), "overflow.gltf", "not finite");
}

#[test]
fn nothing_to_render() {
    let dir = temp_dir("nothing");
    // Only points.
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let m = d.mesh(json!({"attributes": {"POSITION": p}, "mode": 0}));
    d.node(json!({"mesh": m}), true);
    let path = d.write_gltf(&dir, "points");
    let e = assert_err(gltf_load::load_path(&path), "points.gltf", "no triangles");
    assert!(e.contains("1 non-triangle"), "{e}");

    // An empty scene (the mesh node is not in it).
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), false);
    let path = d.write_gltf(&dir, "emptyscene");
    assert_err(
        gltf_load::load_path(&path),
        "emptyscene.gltf",
        "no triangles",
    );

    // Only degenerate triangles.
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]);
    let m = d.mesh(json!({"attributes": {"POSITION": p}}));
    d.node(json!({"mesh": m}), true);
    let path = d.write_gltf(&dir, "collinear");
    let e = assert_err(
        gltf_load::load_path(&path),
        "collinear.gltf",
        "no triangles",
    );
    assert!(e.contains("1 degenerate"), "{e}");

    // Accessors of count 0 (glTF requires at least 1), as positions and as indices: nothing to
    // render, never a panic. (cargo-mutants: `check`'s `Ok(count > 0)` as `>=` passes this too;
    // the `gltf` crate's iterator reads a count-0 accessor with a view as empty, and one without
    // a view fails its validation.)
    for (name, empty_positions) in [("zero_positions", true), ("zero_indices", false)] {
        let mut d = Doc::new();
        let view = d.view(&[0u8; 12], None);
        let empty = d.push(
            "accessors",
            json!({"bufferView": view, "componentType": 5126, "count": 0, "type": "VEC3",
                   "min": [0, 0, 0], "max": [0, 0, 0]}),
        );
        let prim = if empty_positions {
            json!({"attributes": {"POSITION": empty}})
        } else {
            let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            let view = d.view(&[0u8; 4], None);
            let i = d.push(
                "accessors",
                json!({"bufferView": view, "componentType": 5123, "count": 0, "type": "SCALAR"}),
            );
            json!({"attributes": {"POSITION": p}, "indices": i})
        };
        let m = d.mesh(prim);
        d.node(json!({"mesh": m}), true);
        let path = d.write_gltf(&dir, name);
        assert_err(
            gltf_load::load_path(&path),
            &format!("{name}.gltf"),
            "no triangles",
        );
    }

    // A bare minimum document.
    let p = dir.join("bare.gltf");
    std::fs::write(&p, br#"{"asset": {"version": "2.0"}}"#).unwrap();
    assert_err(gltf_load::load_path(&p), "bare.gltf", "no triangles");
}

#[test]
fn unsupported_required_extension_and_version() {
    let dir = temp_dir("required");
    for ext in [
        "KHR_draco_mesh_compression",
        "EXT_meshopt_compression",
        "KHR_materials_pbrSpecularGlossiness",
    ] {
        let mut d = Doc::new();
        let m = d.triangle_mesh(true);
        d.node(json!({"mesh": m}), true);
        d.json["extensionsUsed"] = json!([ext]);
        d.json["extensionsRequired"] = json!([ext]);
        let path = d.write_gltf(&dir, ext);
        let e = assert_err(gltf_load::load_path(&path), &format!("{ext}.gltf"), ext);
        assert!(e.contains("does not support"), "{e}");
    }
    // Optional unknown extensions are ignored but recorded.
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    d.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression", "MSFT_texture_dds"]);
    let s = load_ok(&d.write_gltf(&dir, "optional"));
    assert_eq!(
        s.report.extensions_used,
        ["KHR_draco_mesh_compression", "MSFT_texture_dds"]
    );

    // glTF 1.0 and unknown versions.
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    d.json["asset"]["version"] = json!("1.0");
    let path = d.write_gltf(&dir, "v1");
    assert_err(
        gltf_load::load_path(&path),
        "v1.gltf",
        "glTF 1.0 is not supported",
    );
    d.json["asset"]["version"] = json!("3.0");
    let path = d.write_gltf(&dir, "v3");
    assert_err(gltf_load::load_path(&path), "v3.gltf", "version");
}

#[test]
fn invalid_node_hierarchy() {
    let dir = temp_dir("hierarchy");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m, "children": [1]}), true);
    d.node(json!({"children": [0]}), false);
    let path = d.write_gltf(&dir, "cycle");
    assert_err(gltf_load::load_path(&path), "cycle.gltf", "hierarchy");

    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m, "children": [0]}), true);
    let path = d.write_gltf(&dir, "selfchild");
    assert_err(gltf_load::load_path(&path), "selfchild.gltf", "hierarchy");

    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    let leaf = d.node(json!({"mesh": m}), false);
    d.node(json!({"children": [leaf]}), true);
    d.node(json!({"children": [leaf]}), true);
    let path = d.write_gltf(&dir, "twoparents");
    assert_err(
        gltf_load::load_path(&path),
        "twoparents.gltf",
        "two parents",
    );

    // A very deep (but valid) chain does not overflow the stack.
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    let n = 20_000;
    for i in 0..n {
        let child = if i + 1 < n {
            json!({"children": [i + 1]})
        } else {
            json!({"mesh": m})
        };
        d.node(child, i == 0);
    }
    assert_eq!(load_ok(&d.write_gltf(&dir, "deep")).triangles.len(), 1);
}

/// Random corruptions of a valid file: every outcome must be a clean `Ok` or one-line `Err`, and the
/// loader itself must not panic (the guard would report "internal error").
#[test]
fn corrupted_files_never_panic() {
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    let p = d.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let i = d.indices(&[0, 1, 2, 2, 1, 3]);
    let m2 = d.mesh(json!({"attributes": {"POSITION": p}, "indices": i, "mode": 5}));
    d.node(json!({"mesh": m, "translation": [1, 2, 3]}), true);
    d.node(json!({"mesh": m2, "scale": [1, -1, 1]}), true);
    let glb = d.glb();
    let text = d.embedded();
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut rnd = move |n: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    let (mut ok, mut err) = (0, 0);
    for round in 0..3000 {
        let src = if round % 2 == 0 { &glb } else { &text };
        let mut bytes = src.clone();
        match rnd(3) {
            0 => bytes.truncate(rnd(bytes.len())),
            1 => {
                for _ in 0..1 + rnd(4) {
                    let at = rnd(bytes.len());
                    bytes[at] = rnd(256) as u8;
                }
            }
            _ => {
                // Replace a digit, to make plausible-but-wrong JSON numbers.
                let at = rnd(bytes.len());
                if let Some(k) = bytes[at..].iter().position(u8::is_ascii_digit) {
                    bytes[at + k] = b"0123456789"[rnd(10)];
                    if rnd(2) == 0 {
                        bytes.insert(at + k, b"9"[0]);
                    }
                }
            }
        }
        let name = if round % 2 == 0 {
            "fuzz.glb"
        } else {
            "fuzz.gltf"
        };
        match gltf_load::load_slice(&bytes, name) {
            Ok(s) => {
                ok += 1;
                assert!(
                    s.triangles
                        .iter()
                        .all(|t| t.p.iter().all(|p| p.is_finite()))
                );
            }
            Err(e) => {
                err += 1;
                let e = e.to_string();
                assert!(e.starts_with(name) && !e.contains('\n'), "{e}");
                assert!(!e.contains("internal error"), "round {round}: {e}");
            }
        }
    }
    println!("corruption rounds: {ok} loaded, {err} refused");
    assert!(err > 0);
}

// ---------------------------------------------------------------------------------------------
// Valid files

#[test]
fn nested_trs_and_matrix_nodes() {
    let dir = temp_dir("nested");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    // Child: a matrix translating by (0,0,1). Parent: T(1,2,3) · R(90° about Y) · S(2).
    let child = d.node(
        json!({"mesh": m, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]}),
        false,
    );
    let h = std::f32::consts::FRAC_1_SQRT_2;
    d.node(
        json!({"children": [child], "translation": [1, 2, 3], "rotation": [0, h, 0, h], "scale": [2, 2, 2]}),
        true,
    );
    for s in [
        load_ok(&d.write_gltf(&dir, "nested")),
        gltf_load::load_slice(&d.glb(), "n.glb").unwrap(),
    ] {
        assert_eq!(s.triangles.len(), 1);
        let t = s.triangles[0];
        let want = [
            Vec3::new(3.0, 2.0, 3.0),
            Vec3::new(3.0, 2.0, 1.0),
            Vec3::new(3.0, 4.0, 3.0),
        ];
        for (k, (p, n)) in t.p.iter().zip(t.n).enumerate() {
            assert!(close(*p, want[k]), "vertex {k}: {p} vs {}", want[k]);
            assert!(close(n, Vec3::X), "normal {k}: {n}");
        }
        assert!(close(t.geometric_normal(), Vec3::X));
        assert_eq!(s.report.generated_normals, 0);
        // A node with both a mesh and children: the mesh uses the node's own transform.
        assert_eq!(s.materials.len(), 1);
        assert_eq!(s.materials[0], scene::Material::default());
    }
}

#[test]
fn missing_normals_are_generated() {
    let dir = temp_dir("normals");
    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(
        json!({"mesh": m, "rotation": [0.38268343, 0, 0, 0.9238795]}),
        true,
    );
    // Zero and NaN normals are replaced too.
    let p = d.positions(&[[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [0.0, 1.0, 2.0]]);
    let n = d.floats(
        &[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 1.0], [0.0, 0.0, 1.0]],
        "VEC3",
        false,
    );
    let m2 = d.mesh(json!({"attributes": {"POSITION": p, "NORMAL": n}}));
    d.node(json!({"mesh": m2}), true);
    let s = load_ok(&d.write_gltf(&dir, "normals"));
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.report.generated_normals, 2);
    for t in &s.triangles {
        for n in t.n {
            assert!((n.length() - 1.0).abs() < 1e-5, "{n}");
            assert!(n.dot(t.geometric_normal()) > 0.999, "{n}");
        }
    }
    assert!(s.features().contains(&"generated-normals"));
}

#[test]
fn negative_scale_keeps_front_faces() {
    let dir = temp_dir("mirror");
    let mut d = Doc::new();
    let with_n = d.triangle_mesh(true);
    let without_n = d.triangle_mesh(false);
    d.node(json!({"mesh": with_n, "scale": [-1, 1, 1]}), true);
    d.node(
        json!({"mesh": without_n, "matrix": [1,0,0,0, 0,1,0,0, 0,0,-1,0, 5,0,0,1]}),
        true,
    );
    d.node(json!({"mesh": with_n, "translation": [0, 0, 3]}), true);
    // Flattened along Z (determinant 0, no mirror): the triangle in the XY plane keeps its
    // winding (cargo-mutants: `det < 0` as `<=` survived).
    d.node(
        json!({"mesh": without_n, "scale": [1, 1, 0], "translation": [0, 0, 6]}),
        true,
    );
    let s = load_ok(&d.write_gltf(&dir, "mirror"));
    assert_eq!(s.triangles.len(), 4);
    for t in &s.triangles {
        let g = t.geometric_normal();
        for n in t.n {
            assert!(
                n.dot(g) > 0.999,
                "shading normal {n} disagrees with face normal {g}"
            );
        }
    }
    // Mirrored in X: positions mirrored, the front face still +Z.
    let t = s.triangles[0];
    assert!(t.p.contains(&Vec3::new(-1.0, 0.0, 0.0)));
    assert!(close(t.geometric_normal(), Vec3::Z));
    // Mirrored in Z: the front face flips to -Z along with the geometry.
    assert!(close(s.triangles[1].geometric_normal(), Vec3::NEG_Z));
    let flat = s.triangles[3];
    assert!(flat.p.iter().all(|p| p.z == 6.0), "{:?}", flat.p);
    assert!(close(flat.geometric_normal(), Vec3::Z));
}

#[test]
fn degenerate_triangles_are_dropped() {
    let dir = temp_dir("degenerate");
    let mut d = Doc::new();
    let p = d.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [2.0, 2.0, 0.0],  // collinear with 0 and 3
        [1.0, 1e-8, 0.0], // with 0 and 1: a numerical sliver (height 1e-8 × its length)
        [1e-7, 1e-7, 0.0],
        [0.0, 1e-7, 0.0], // tiny (area 5e-15) triangle with 0
    ]);
    let i = d.indices(&[0, 1, 2, 2, 1, 3, 0, 0, 1, 0, 3, 4, 0, 1, 5, 0, 6, 7]);
    let m = d.mesh(json!({"attributes": {"POSITION": p}, "indices": i}));
    d.node(json!({"mesh": m}), true);
    let s = load_ok(&d.write_gltf(&dir, "degenerate"));
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.report.dropped_degenerate, 4);
    assert!(s.triangles.iter().all(|t| t.area() > 0.4));
}

/// Indices of each unsigned type glTF allows (byte, short, int) give the same triangles: a quad
/// (0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0) as 0 1 2, 0 2 3 (cargo-mutants: `read_indices`
/// without its unsigned-byte arm, so bytes read as ints, survived).
#[test]
fn byte_short_and_int_indices() {
    let dir = temp_dir("index_types");
    let quad = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let idx = [0u32, 1, 2, 0, 2, 3];
    for (name, comp, bytes) in [
        ("u8", 5121, idx.map(|i| i as u8).to_vec()),
        (
            "u16",
            5123,
            idx.map(|i| i as u16).map(u16::to_le_bytes).concat(),
        ),
        ("u32", 5125, idx.map(u32::to_le_bytes).concat()),
    ] {
        let mut d = Doc::new();
        let p = d.positions(&quad);
        let view = d.view(&bytes, None);
        let i = d.push(
            "accessors",
            json!({"bufferView": view, "componentType": comp, "count": 6, "type": "SCALAR"}),
        );
        let m = d.mesh(json!({"attributes": {"POSITION": p}, "indices": i}));
        d.node(json!({"mesh": m}), true);
        let s = load_ok(&d.write_gltf(&dir, name));
        let got: Vec<[Vec3; 3]> = s.triangles.iter().map(|t| t.p).collect();
        let v = |k: usize| Vec3::from(quad[k]);
        assert_eq!(got, [[v(0), v(1), v(2)], [v(0), v(2), v(3)]], "{name}");
    }
}

#[test]
fn non_indexed_strip_and_fan() {
    let dir = temp_dir("modes");
    let mut d = Doc::new();
    let soup = d.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ]);
    let m = d.mesh(json!({"attributes": {"POSITION": soup}}));
    d.node(json!({"mesh": m}), true);
    let strip = d.positions(&[
        [0.0, 0.0, 2.0],
        [1.0, 0.0, 2.0],
        [0.0, 1.0, 2.0],
        [1.0, 1.0, 2.0],
        [0.0, 2.0, 2.0],
    ]);
    let m = d.mesh(json!({"attributes": {"POSITION": strip}, "mode": 5}));
    d.node(json!({"mesh": m}), true);
    let fan = d.positions(&[
        [0.0, 0.0, 3.0],
        [1.0, 0.0, 3.0],
        [1.0, 1.0, 3.0],
        [0.0, 1.0, 3.0],
    ]);
    let fi = d.indices(&[0, 1, 2, 3]);
    let m = d.mesh(json!({"attributes": {"POSITION": fan}, "indices": fi, "mode": 6}));
    d.node(json!({"mesh": m}), true);
    let lines = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    let m = d.mesh(json!({"attributes": {"POSITION": lines}, "mode": 1}));
    d.node(json!({"mesh": m}), true);

    let s = load_ok(&d.write_gltf(&dir, "modes"));
    assert_eq!(s.triangles.len(), 2 + 3 + 2);
    assert_eq!(s.report.skipped_primitives, 1);
    for t in &s.triangles {
        assert!(close(t.geometric_normal(), Vec3::Z), "winding: {:?}", t.p);
        assert!((t.area() - 0.5).abs() < 1e-6);
    }
    // The strip covers the unit squares [0,1]² and the triangle up to y = 2.
    let strip_area: f32 = s
        .triangles
        .iter()
        .filter(|t| t.p[0].z == 2.0)
        .map(|t| t.area())
        .sum();
    assert!((strip_area - 1.5).abs() < 1e-6);
}

#[test]
fn punctual_lights() {
    let dir = temp_dir("lights");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    d.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    d.json["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 40.0},
        {"type": "spot", "intensity": 10.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"type": "directional", "intensity": 3.0},
        {"type": "spot", "spot": {"innerConeAngle": 1.0, "outerConeAngle": 0.5}}
    ]}});
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let parent = d.node(json!({"translation": [10, 0, 0]}), true);
    let point = d.node(
        json!({"translation": [1, 2, 3], "extensions": {"KHR_lights_punctual": {"light": 0}}}),
        false,
    );
    d.json["nodes"][parent]["children"] = json!([point]);
    d.node(
        json!({"translation": [0, 3, 0], "rotation": [-h, 0, 0, h],
                  "extensions": {"KHR_lights_punctual": {"light": 1}}}),
        true,
    );
    d.node(
        json!({"extensions": {"KHR_lights_punctual": {"light": 2}}}),
        true,
    );
    d.node(
        json!({"extensions": {"KHR_lights_punctual": {"light": 3}}}),
        true,
    );
    let s = load_ok(&d.write_gltf(&dir, "lights"));
    assert_eq!(s.lights.len(), 4);
    let l = &s.lights[0];
    assert_eq!(l.kind, LightKind::Point);
    assert!(close(l.position, Vec3::new(11.0, 2.0, 3.0)));
    assert_eq!(l.color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(l.intensity, 40.0);
    let l = &s.lights[1];
    assert_eq!(
        l.kind,
        LightKind::Spot {
            inner_cone: 0.2,
            outer_cone: 0.6
        }
    );
    assert!(close(l.position, Vec3::new(0.0, 3.0, 0.0)));
    assert!(close(l.direction, Vec3::NEG_Y), "{}", l.direction);
    assert_eq!((l.color, l.intensity), (Vec3::ONE, 10.0));
    let l = &s.lights[2];
    assert_eq!(l.kind, LightKind::Directional);
    assert!(close(l.direction, Vec3::NEG_Z));
    assert_eq!(l.intensity, 3.0);
    // Invalid cone angles are repaired with a warning.
    match s.lights[3].kind {
        LightKind::Spot {
            inner_cone,
            outer_cone,
        } => assert!(inner_cone < outer_cone && outer_cone == 0.5),
        k => panic!("{k:?}"),
    }
    assert!(
        s.report.warnings.iter().any(|w| w.contains("cone")),
        "{:?}",
        s.report.warnings
    );
    assert!(s.has_light() && s.features().contains(&"punctual-lights"));
}

#[test]
fn cameras() {
    let dir = temp_dir("cameras");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    d.json["cameras"] = json!([
        {"type": "perspective", "name": "main", "perspective": {"yfov": 0.8, "znear": 0.1}},
        {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}}
    ]);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    // Scaled and rotated 90° about Y: looks down -X.
    d.node(json!({"camera": 0, "translation": [0, 1, 5], "rotation": [0, h, 0, h], "scale": [3, 3, 3]}), true);
    d.node(json!({"camera": 1}), true);
    let s = load_ok(&d.write_gltf(&dir, "cameras"));
    assert_eq!(s.cameras.len(), 1);
    let c = &s.cameras[0];
    assert_eq!(c.name, "main");
    assert_eq!(c.yfov, 0.8);
    assert!(close(c.eye(), Vec3::new(0.0, 1.0, 5.0)));
    assert!(close(c.forward(), Vec3::NEG_X), "{}", c.forward());
    assert!(close(c.up(), Vec3::Y));
    for axis in [c.transform.x_axis, c.transform.y_axis, c.transform.z_axis] {
        assert!(
            (axis.truncate().length() - 1.0).abs() < 1e-5,
            "scale not removed"
        );
    }
    assert!(s.report.warnings.iter().any(|w| w.contains("orthographic")));
    assert_eq!(s.default_camera(), *c);
}

#[test]
fn emissive_strength_and_default_material() {
    let dir = temp_dir("emissive");
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let lamp = d.mesh(json!({"attributes": {"POSITION": p}, "material": 0}));
    let plain = d.mesh(json!({"attributes": {"POSITION": p}}));
    let weak = d.mesh(json!({"attributes": {"POSITION": p}, "material": 1}));
    d.json["extensionsUsed"] = json!(["KHR_materials_emissive_strength"]);
    d.json["materials"] = json!([
        {"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.25],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
         "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0]}},
        {"name": "weak", "emissiveFactor": [1.0, 1.0, 1.0]}
    ]);
    d.node(json!({"mesh": lamp}), true);
    d.node(json!({"mesh": plain, "translation": [0, 0, 1]}), true);
    d.node(json!({"mesh": weak, "translation": [0, 0, 2]}), true);
    let s = load_ok(&d.write_gltf(&dir, "emissive"));
    assert_eq!(s.materials.len(), 3);
    assert_eq!(s.materials[0].name, "lamp");
    assert_eq!(s.materials[0].emissive, Vec3::new(4.0, 2.0, 1.0));
    assert_eq!(
        s.materials[0].base_color,
        glam::Vec4::new(0.5, 0.25, 1.0, 1.0)
    );
    assert_eq!(s.materials[1].emissive, Vec3::ONE);
    assert_eq!(s.materials[2], scene::Material::default());
    assert_eq!(s.triangles[0].material, 0);
    assert_eq!(s.triangles[1].material, 2);
    assert_eq!(s.triangles[2].material, 1);
    assert_eq!(s.emissive_triangle_count(), 2);
    assert_eq!(
        s.report.extensions_used,
        ["KHR_materials_emissive_strength"]
    );
}

/// The same grid scene scaled by 1e-4, 1 and 1e4 keeps every triangle.
#[test]
fn scale_invariance() {
    let dir = temp_dir("scale");
    let mut counts = Vec::new();
    for scale in [1e-4f32, 1.0, 1e4] {
        let mut d = Doc::new();
        let n = 40;
        let mut pos = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                // A gently curved grid with fine detail: cells are 1/40 of the extent.
                let (u, v) = (x as f32 / n as f32, y as f32 / n as f32);
                pos.push([u, v, 0.1 * (6.0 * u).sin() * (4.0 * v).cos()]);
            }
        }
        let mut idx = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let a = y * (n + 1) + x;
                idx.extend([a, a + 1, a + n + 1, a + n + 1, a + 1, a + n + 2]);
            }
        }
        let p = d.positions(&pos);
        let i = d.indices(&idx);
        let m = d.mesh(json!({"attributes": {"POSITION": p}, "indices": i}));
        // A small but real detail: a triangle 1e-3 of the extent.
        let tiny = d.positions(&[[0.5, 0.5, 0.5], [0.501, 0.5, 0.5], [0.5, 0.501, 0.5]]);
        let mt = d.mesh(json!({"attributes": {"POSITION": tiny}}));
        let root = d.node(
            json!({"scale": [scale, scale, scale], "translation": [scale * 3.0, 0, 0]}),
            true,
        );
        let a = d.node(json!({"mesh": m}), false);
        let b = d.node(json!({"mesh": mt}), false);
        d.json["nodes"][root]["children"] = json!([a, b]);
        let s = load_ok(&d.write_gltf(&dir, &format!("scale{scale}")));
        assert_eq!(s.report.dropped_degenerate, 0, "scale {scale}");
        assert!((s.extent() / scale - (1.0f32 + 1.0 + 0.5f32.powi(2)).sqrt()).abs() < 0.3);
        counts.push(s.triangles.len());
    }
    assert_eq!(counts, [2 * 40 * 40 + 1; 3]);
}

fn png_bytes(w: u32, h: u32, rgba: [u8; 4]) -> Vec<u8> {
    let img = image::RgbaImage::from_pixel(w, h, image::Rgba(rgba));
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

#[test]
fn textures_and_uvs() {
    let dir = temp_dir("textures");
    std::fs::write(dir.join("red.png"), png_bytes(4, 2, [255, 0, 0, 255])).unwrap();
    std::fs::write(dir.join("fake.dds"), b"DDS not really").unwrap();
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let uv = d.floats(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], "VEC2", false);
    let green = png_bytes(3, 3, [0, 255, 0, 255]);
    let gview = d.view(&green, None);
    d.json["images"] = json!([
        {"uri": "red.png"},
        {"uri": "fake.dds"},
        {"uri": "missing.jpg"},
        {"bufferView": gview, "mimeType": "image/png", "name": "green"},
        {"uri": format!("data:image/png;base64,{}", b64(&png_bytes(5000, 1000, [0, 0, 255, 255])))}
    ]);
    d.json["textures"] =
        json!([{"source": 0}, {"source": 1}, {"source": 2}, {"source": 3}, {"source": 4}]);
    d.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    d.json["materials"] = json!([
        {"name": "red", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": {"offset": [0.5, 0.25], "scale": [2, 2]}}}}},
        {"name": "red again", "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0}},
        {"name": "dds", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
        {"name": "missing", "pbrMetallicRoughness": {"baseColorTexture": {"index": 2}}},
        {"name": "uv1", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1}}},
        {"name": "green", "pbrMetallicRoughness": {"baseColorTexture": {"index": 3}}},
        {"name": "big", "pbrMetallicRoughness": {"baseColorTexture": {"index": 4}}}
    ]);
    for mat in 0..7 {
        let m = d.mesh(json!({"attributes": {"POSITION": p, "TEXCOORD_0": uv}, "material": mat}));
        d.node(json!({"mesh": m, "translation": [0, 0, mat]}), true);
    }
    let s = load_ok(&d.write_gltf(&dir, "textures"));
    assert_eq!(s.triangles.len(), 7);
    // red.png decoded once for two materials; the DDS and missing images fall back to factors.
    assert_eq!(
        s.textures.len(),
        3,
        "{:?}",
        s.textures.iter().map(|t| &t.name).collect::<Vec<_>>()
    );
    let red = &s.textures[0];
    assert_eq!((red.width, red.height), (4, 2));
    assert_eq!(red.rgba8.len(), 8);
    assert_eq!(red.rgba8[0], [255, 0, 0, 255]);
    assert_eq!(s.materials[0].base_color_texture, Some(0));
    assert_eq!(s.materials[1].emissive_texture, Some(0));
    assert_eq!(s.materials[2].base_color_texture, None);
    assert_eq!(s.materials[3].base_color_texture, None);
    assert_eq!(s.materials[4].base_color_texture, None);
    assert_eq!(s.materials[5].base_color_texture, Some(1));
    assert_eq!(s.textures[1].rgba8[4], [0, 255, 0, 255]);
    assert_eq!(s.materials[6].base_color_texture, Some(2));
    assert_eq!((s.textures[2].width, s.textures[2].height), (2048, 410));
    let w = &s.report.warnings;
    assert!(w.iter().any(|w| w.contains("fake.dds")), "{w:?}");
    assert!(w.iter().any(|w| w.contains("missing.jpg")), "{w:?}");
    assert!(w.iter().any(|w| w.contains("TEXCOORD_1")), "{w:?}");
    // UVs: KHR_texture_transform applied for material 0 only.
    let t0 = s.triangles.iter().find(|t| t.material == 0).unwrap();
    assert_eq!(
        t0.uv,
        [
            Vec2::new(0.5, 0.25),
            Vec2::new(2.5, 0.25),
            Vec2::new(0.5, 2.25)
        ]
    );
    let t1 = s.triangles.iter().find(|t| t.material == 1).unwrap();
    assert_eq!(t1.uv, [Vec2::ZERO, Vec2::X, Vec2::Y]);
    assert!(s.uses_textures());
}

#[test]
fn quantized_sparse_and_sceneless() {
    let dir = temp_dir("quantized");
    let mut d = Doc::new();
    // Positions as unsigned shorts (KHR_mesh_quantization), 8-byte stride.
    let mut bytes = Vec::new();
    for p in [[0u16, 0, 0], [2, 0, 0], [0, 2, 0]] {
        for c in p {
            bytes.extend(c.to_le_bytes());
        }
        bytes.extend([0, 0]);
    }
    let view = d.view(&bytes, Some(8));
    let pos = d.push(
        "accessors",
        json!({"bufferView": view, "componentType": 5123, "count": 3,
        "type": "VEC3", "min": [0, 0, 0], "max": [2, 2, 0]}),
    );
    // Normalised signed-byte normals, 4-byte stride.
    let nview = d.view(&[0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0], Some(4));
    let nrm = d.push(
        "accessors",
        json!({"bufferView": nview, "componentType": 5120, "normalized": true,
        "count": 3, "type": "VEC3"}),
    );
    let m = d.mesh(json!({"attributes": {"POSITION": pos, "NORMAL": nrm}}));
    d.node(json!({"mesh": m}), true);
    // A sparse accessor with no bufferView: zeros, then vertices 1 and 2 substituted.
    let sidx = d.view(&[1, 2], None);
    let sval = d.view(&le_bytes(&Doc::SPARSE_VALUES), None);
    let sp = d.sparse_vec3(sidx, sval, [0.0, 3.0, 5.0]);
    let m = d.mesh(json!({"attributes": {"POSITION": sp}}));
    d.node(json!({"mesh": m}), true);
    d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    d.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let s = load_ok(&d.write_gltf(&dir, "quantized"));
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(
        s.triangles[0].p,
        [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0)
        ]
    );
    assert_eq!(s.triangles[0].n, [Vec3::Z; 3]);
    assert_eq!(
        s.triangles[1].p,
        [
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::new(0.0, 3.0, 5.0)
        ]
    );

    // Without scenes, every root node is used.
    d.json.as_object_mut().unwrap().remove("scenes");
    d.json.as_object_mut().unwrap().remove("scene");
    let s = gltf_load::load_slice(&d.embedded(), "sceneless.gltf").unwrap();
    assert_eq!(s.triangles.len(), 2);
    assert_eq!(s.name, "sceneless.gltf");
    assert!(s.path.is_none());
}

/// A sparse accessor wrong in one respect is refused with one line naming it: a byteStride on the
/// indices' view only, or on the values' view only (glTF forbids both; cargo-mutants: the test's
/// `||` as `&&` survived), an index past the count, indices out of order.
#[test]
fn bad_sparse_accessors_are_refused() {
    let dir = temp_dir("bad_sparse");
    // (name, the two sparse indices, the indices' and the values' byteStride, the error).
    let cases = [
        ("good", [1u8, 2], None, None, ""),
        (
            "index_stride",
            [1, 2],
            Some(4),
            None,
            "byteStride, which glTF forbids",
        ),
        (
            "value_stride",
            [1, 2],
            None,
            Some(12),
            "byteStride, which glTF forbids",
        ),
        (
            "index_past_count",
            [1, 3],
            None,
            None,
            "sparse index 3 out of range (count 3)",
        ),
        (
            "unordered",
            [2, 1],
            None,
            None,
            "has sparse index 1 after 2",
        ),
    ];
    for (name, idx, idx_stride, val_stride, needle) in cases {
        let mut d = Doc::new();
        let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let sidx = d.view(&idx, idx_stride);
        let sval = d.view(&le_bytes(&Doc::SPARSE_VALUES), val_stride);
        let sp = d.sparse_vec3(sidx, sval, [0.0, 3.0, 5.0]);
        let m = d.mesh(json!({"attributes": {"POSITION": p}}));
        let m2 = d.mesh(json!({"attributes": {"POSITION": sp}}));
        d.node(json!({"mesh": m}), true);
        d.node(json!({"mesh": m2}), true);
        let path = d.write_gltf(&dir, name);
        if needle.is_empty() {
            assert_eq!(load_ok(&path).triangles.len(), 2, "{name}");
        } else {
            assert_err(gltf_load::load_path(&path), &format!("{name}.gltf"), needle);
        }
    }
}

/// Quantized positions (KHR_mesh_quantization) of each integer component type, plain and
/// normalised, read per glTF's rules: a signed value c over its type's max, at least -1; an unsigned
/// one over its max (cargo-mutants: `to_f32` of i8, i16 and u32 as constants, `/` as `*` or `%`,
/// and the -1 bound's `-` deleted, survived).
#[test]
fn quantized_positions_of_each_component_type() {
    let dir = temp_dir("quantized_types");
    // (name, componentType, bytes a component, the vertices' raw components (x, y; z = 0), max).
    type Case = (&'static str, u32, usize, [[i64; 2]; 3], f32);
    let cases: [Case; 5] = [
        ("i8", 5120, 1, [[0, 0], [127, 0], [-128, 64]], 127.0),
        ("u8", 5121, 1, [[0, 0], [255, 0], [3, 128]], 255.0),
        (
            "i16",
            5122,
            2,
            [[0, 0], [32767, 0], [-32768, 16384]],
            32767.0,
        ),
        ("u16", 5123, 2, [[0, 0], [65535, 0], [3, 32768]], 65535.0),
        // Not a glTF vertex type, but read alike (through f64).
        (
            "u32",
            5125,
            4,
            [[0, 0], [4294967295, 0], [3, 2147483648]],
            4294967295.0,
        ),
    ];
    for (name, comp, size, raw, max) in cases {
        for normalized in [false, true] {
            // Each vertex padded to 4-byte alignment, as glTF requires of vertex attributes.
            let stride = (3 * size).next_multiple_of(4);
            let mut bytes = Vec::new();
            for v in raw {
                for c in [v[0], v[1], 0] {
                    bytes.extend_from_slice(&c.to_le_bytes()[..size]);
                }
                bytes.resize(bytes.len().next_multiple_of(4), 0);
            }
            let mut d = Doc::new();
            let view = d.view(&bytes, Some(stride));
            let lo = [0, 1].map(|c| raw.iter().map(|v| v[c]).min().unwrap());
            let hi = [0, 1].map(|c| raw.iter().map(|v| v[c]).max().unwrap());
            let pos = d.push(
                "accessors",
                json!({"bufferView": view, "componentType": comp, "normalized": normalized,
                "count": 3, "type": "VEC3", "min": [lo[0], lo[1], 0], "max": [hi[0], hi[1], 0]}),
            );
            let m = d.mesh(json!({"attributes": {"POSITION": pos}}));
            d.node(json!({"mesh": m}), true);
            d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
            d.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
            let file = format!("{name}_{normalized}");
            let s = load_ok(&d.write_gltf(&dir, &file));
            assert_eq!(s.triangles.len(), 1, "{file}");
            let want = raw.map(|v| {
                let f = |c: i64| {
                    if normalized {
                        (c as f32 / max).max(-1.0)
                    } else {
                        c as f32
                    }
                };
                Vec3::new(f(v[0]), f(v[1]), 0.0)
            });
            assert_eq!(s.triangles[0].p, want, "{file}");
        }
    }
}

/// A sparse accessor's indices read alike as unsigned bytes, shorts and ints (cargo-mutants: with
/// byte indices only, the short arm deleted and the k-th index's offset `k * size` as `k / size`
/// survived).
#[test]
fn sparse_indices_of_each_width() {
    let dir = temp_dir("sparse_widths");
    for (name, comp, bytes) in [
        ("u8", 5121, vec![1u8, 2]),
        ("u16", 5123, [1u16, 2].map(u16::to_le_bytes).concat()),
        ("u32", 5125, [1u32, 2].map(u32::to_le_bytes).concat()),
    ] {
        let mut d = Doc::new();
        let sidx = d.view(&bytes, None);
        let sval = d.view(&le_bytes(&Doc::SPARSE_VALUES), None);
        let sp = d.sparse_vec3(sidx, sval, [0.0, 3.0, 5.0]);
        d.json["accessors"][sp]["sparse"]["indices"]["componentType"] = json!(comp);
        let m = d.mesh(json!({"attributes": {"POSITION": sp}}));
        d.node(json!({"mesh": m}), true);
        let s = load_ok(&d.write_gltf(&dir, name));
        assert_eq!(s.triangles.len(), 1, "{name}");
        assert_eq!(
            s.triangles[0].p,
            [
                Vec3::ZERO,
                Vec3::new(0.0, 0.0, 5.0),
                Vec3::new(0.0, 3.0, 5.0)
            ],
            "{name}"
        );
    }
}

#[test]
fn load_dispatches_builtin_and_paths() {
    let s = scene::load("builtin:cornell").unwrap();
    assert_eq!(s.name, "builtin:cornell");
    assert!(!s.triangles.is_empty());
    let e = scene::load("builtin:nope").unwrap_err().to_string();
    assert!(e.contains("builtin:nope") && e.contains("cornell"), "{e}");
    assert_eq!(
        builtin::NAMES,
        ["cornell", "conference", "dense-3m", "dense-8m"]
    );

    let dir = temp_dir("dispatch");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    let p = d.write_gltf(&dir, "plain");
    let s = scene::load(p.to_str().unwrap()).unwrap();
    assert_eq!(s.name, p.display().to_string());
    assert_eq!(s.path.as_deref(), Some(p.as_path()));
}

// ---------------------------------------------------------------------------------------------
// Alpha modes, vertex colours, extensions a diffuse renderer can ignore

/// A one-triangle mesh with TEXCOORD_0 and material `mat`, instanced by a root node.
fn textured_triangle(d: &mut Doc, mat: usize) {
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let uv = d.floats(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], "VEC2", false);
    let m = d.mesh(json!({"attributes": {"POSITION": p, "TEXCOORD_0": uv}, "material": mat}));
    d.node(json!({"mesh": m}), true);
}

#[test]
fn alpha_modes_and_cutoffs() {
    let dir = temp_dir("alpha_modes");
    // Texture alpha: 0 in one texel, 255 in the others; and one fully opaque texture.
    let mut holes = image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 255, 255, 255]));
    holes.put_pixel(1, 1, image::Rgba([255, 255, 255, 0]));
    let mut png = Vec::new();
    holes
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    std::fs::write(dir.join("holes.png"), png).unwrap();
    std::fs::write(dir.join("solid.png"), png_bytes(2, 2, [9, 9, 9, 255])).unwrap();
    let mut d = Doc::new();
    d.json["images"] = json!([{"uri": "holes.png"}, {"uri": "solid.png"}]);
    d.json["textures"] = json!([{"source": 0}, {"source": 1}]);
    d.json["materials"] = json!([
        {"name": "opaque", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
        {"name": "mask", "alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
        {"name": "mask 0.3", "alphaMode": "MASK", "alphaCutoff": 0.3,
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}},
        {"name": "mask by factor", "alphaMode": "MASK", "alphaCutoff": 0.3,
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "baseColorFactor": [1, 1, 1, 0.25]}},
        {"name": "blend", "alphaMode": "BLEND", "alphaCutoff": 0.9},
        {"name": "blend too", "alphaMode": "BLEND"}
    ]);
    for mat in 0..6 {
        textured_triangle(&mut d, mat);
    }
    let s = load_ok(&d.write_gltf(&dir, "alpha"));
    let cutoffs: Vec<Option<f32>> = s.materials.iter().map(|m| m.alpha_cutoff).collect();
    // BLEND is MASK at 0.5 whatever alphaCutoff says (the spec ignores it outside MASK).
    assert_eq!(
        cutoffs,
        [None, Some(0.5), Some(0.3), Some(0.3), Some(0.5), Some(0.5)]
    );
    // Tested: MASK over a texture with a clear texel, MASK with factor alpha 0.25 < 0.3, and the
    // BLEND materials whose alpha is 1 everywhere are not (nothing can fall below 0.5), nor is
    // the opaque texture under MASK 0.3, nor the OPAQUE material.
    assert_eq!(
        s.alpha_test_flags(),
        [false, true, false, true, false, false]
    );
    assert!(s.features().contains(&"alpha-test"));
    let blend = warnings_with(&s, &["BLEND"]);
    assert_eq!(blend.len(), 1, "{:?}", s.report.warnings);
    assert!(blend[0].contains("2 materials") && blend[0].contains("cutoff 0.5"));

    // A file without alpha modes tests nothing.
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    let s = load_ok(&d.write_gltf(&dir, "plain"));
    assert!(!s.uses_alpha_test() && !s.features().contains(&"alpha-test"));
}

#[test]
fn vertex_colours_in_every_format() {
    let dir = temp_dir("colors");
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    // RGB float.
    let rgb = d.floats(
        &[[1.0, 0.5, 0.0], [0.0, 1.0, 0.25], [0.2, 0.2, 0.2]],
        "VEC3",
        false,
    );
    // RGBA normalised unsigned byte.
    let v = d.view(&[255, 0, 0, 255, 0, 51, 0, 128, 0, 0, 255, 0], None);
    let u8s = d.push(
        "accessors",
        json!({"bufferView": v, "componentType": 5121,
        "normalized": true, "count": 3, "type": "VEC4"}),
    );
    // RGB normalised unsigned short.
    let shorts: Vec<u8> = [65535u16, 0, 0, 0, 65535, 0, 13107, 13107, 65535]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let v = d.view(&shorts, None);
    let u16s = d.push(
        "accessors",
        json!({"bufferView": v, "componentType": 5123,
        "normalized": true, "count": 3, "type": "VEC3"}),
    );
    // Not normalised: not a colour glTF allows; ignored with a warning.
    let v = d.view(&[1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 0, 0], None);
    let raw = d.push(
        "accessors",
        json!({"bufferView": v, "componentType": 5121,
        "count": 3, "type": "VEC4"}),
    );
    // Out of [0, 1]: clamped with a warning.
    let hot = d.floats(&[[2.0, 0.5, -1.0]; 3], "VEC3", false);
    // Each way out alone: above 1, below 0, not finite (a colour with one becomes white).
    let over = d.floats(&[[2.0, 0.5, 0.0]; 3], "VEC3", false);
    let under = d.floats(&[[0.5, -1.0, 0.0]; 3], "VEC3", false);
    let nan = d.floats(&[[f32::NAN, 0.5, 0.0]; 3], "VEC3", false);
    for (i, c) in [rgb, u8s, u16s, raw, hot, over, under, nan]
        .into_iter()
        .enumerate()
    {
        let m = d.mesh(json!({"attributes": {"POSITION": p, "COLOR_0": c}}));
        d.node(json!({"mesh": m, "translation": [0, 0, i]}), true);
    }
    let s = load_ok(&d.write_gltf(&dir, "colors"));
    assert_eq!(s.triangles.len(), 8);
    let by_z = |z: f32| s.triangles.iter().find(|t| t.p[0].z == z).unwrap().color;
    let close4 = |a: Vec4, b: Vec4| (a - b).abs().max_element() < 1e-6;
    let c = by_z(0.0);
    assert!(
        close4(c[0], Vec4::new(1.0, 0.5, 0.0, 1.0)) && close4(c[1], Vec4::new(0.0, 1.0, 0.25, 1.0))
    );
    let c = by_z(1.0);
    assert!(close4(c[0], Vec4::new(1.0, 0.0, 0.0, 1.0)), "{c:?}");
    assert!(
        close4(c[1], Vec4::new(0.0, 0.2, 0.0, 128.0 / 255.0)),
        "{c:?}"
    );
    assert!(close4(c[2], Vec4::new(0.0, 0.0, 1.0, 0.0)), "{c:?}");
    let c = by_z(2.0);
    assert!(close4(c[2], Vec4::new(0.2, 0.2, 1.0, 1.0)), "{c:?}");
    assert_eq!(by_z(3.0), [Vec4::ONE; 3]);
    assert_eq!(by_z(4.0), [Vec4::new(1.0, 0.5, 0.0, 1.0); 3]);
    assert_eq!(by_z(5.0), [Vec4::new(1.0, 0.5, 0.0, 1.0); 3]);
    assert_eq!(by_z(6.0), [Vec4::new(0.5, 0.0, 0.0, 1.0); 3]);
    assert_eq!(by_z(7.0), [Vec4::ONE; 3]);
    let w = &s.report.warnings;
    assert!(
        w.iter()
            .any(|w| w.contains("COLOR_0") && w.contains("normalised")),
        "{w:?}"
    );
    // One warning for each of the four meshes out of [0, 1], none for the others (cargo-mutants:
    // the test's `||`s as `&&` and its `!` deleted survived a mesh out on every side at once).
    let clamped = warnings_with(&s, &["COLOR_0", "clamped"]);
    assert_eq!(clamped.len(), 4, "{w:?}");
    assert!(s.uses_vertex_colors() && s.features().contains(&"vertex-colors"));
    // Without COLOR_0 the vertices are white and the feature is off.
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    let s = load_ok(&d.write_gltf(&dir, "white"));
    assert_eq!(s.triangles[0].color, [Vec4::ONE; 3]);
    assert!(!s.uses_vertex_colors());
}

#[test]
fn required_extensions_a_diffuse_renderer_can_ignore() {
    let dir = temp_dir("ignorable");
    let doc = |required: &[&str]| {
        let mut d = Doc::new();
        let m = d.triangle_mesh(true);
        d.node(json!({"mesh": m}), true);
        d.json["extensionsUsed"] = json!(required);
        d.json["extensionsRequired"] = json!(required);
        d
    };
    // Specular, clearcoat, sheen, roughness packing: one warning naming them all.
    let ignorable = [
        "AMD_split_roughnessMetallic",
        "KHR_materials_specular",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
    ];
    let mut d = doc(&ignorable);
    d.json["materials"] = json!([{"name": "shiny", "extensions": {
        "KHR_materials_clearcoat": {"clearcoatFactor": 1.0},
        "AMD_split_roughnessMetallic": {"roughnessTexture": {"index": 0}}}}]);
    d.json["meshes"][0]["primitives"][0]["material"] = json!(0);
    let s = load_ok(&d.write_gltf(&dir, "shiny"));
    let named = warnings_with(&s, &["AMD_split_roughnessMetallic"]);
    assert_eq!(named.len(), 1, "{:?}", s.report.warnings);
    for e in ignorable {
        assert!(named[0].contains(e), "{}", named[0]);
    }
    assert_eq!(s.report.warnings.len(), 1, "{:?}", s.report.warnings);

    // An extension the loader does not know is refused, naming it and the way to allow it…
    let path = doc(&["VENDOR_fancy_paint"]).write_gltf(&dir, "vendor");
    let e = assert_err(
        gltf_load::load_path(&path),
        "vendor.gltf",
        "VENDOR_fancy_paint",
    );
    assert!(e.contains("--allow-extension VENDOR_fancy_paint"), "{e}");
    // …and loads with --allow-extension, with one warning.
    let opts = scene::LoadOptions {
        allow_extensions: vec!["VENDOR_fancy_paint".into()],
        ..Default::default()
    };
    let s = gltf_load::load_path_with(&path, &opts).unwrap();
    assert_eq!(s.report.warnings.len(), 1, "{:?}", s.report.warnings);
    assert!(s.report.warnings[0].contains("VENDOR_fancy_paint"));
    assert!(scene::load_with(path.to_str().unwrap(), &opts).is_ok());

    // What changes geometry or diffuse colour stays refused, allowed or not.
    for ext in [
        "KHR_draco_mesh_compression",
        "EXT_meshopt_compression",
        "EXT_mesh_gpu_instancing",
        "KHR_materials_pbrSpecularGlossiness",
    ] {
        let path = doc(&[ext]).write_gltf(&dir, ext);
        let opts = scene::LoadOptions {
            allow_extensions: vec![ext.into()],
            ..Default::default()
        };
        let e = assert_err(
            gltf_load::load_path_with(&path, &opts),
            &format!("{ext}.gltf"),
            ext,
        );
        assert!(e.contains("does not support"), "{e}");
    }
}

#[test]
fn textures_only_in_formats_the_loader_cannot_read() {
    let dir = temp_dir("dds_only");
    std::fs::write(dir.join("white.png"), png_bytes(2, 2, [255, 255, 255, 255])).unwrap();
    let doc = |base_dds: bool, emissive_dds: bool| {
        let mut d = Doc::new();
        d.json["extensionsUsed"] = json!(["MSFT_texture_dds"]);
        d.json["extensionsRequired"] = json!(["MSFT_texture_dds"]);
        d.json["images"] = json!([{"uri": "white.png"}, {"uri": "rough.dds"}]);
        // Texture 0: PNG with a DDS alternative; 1 and 2: DDS only.
        d.json["textures"] = json!([
            {"source": 0, "extensions": {"MSFT_texture_dds": {"source": 1}}},
            {"extensions": {"MSFT_texture_dds": {"source": 1}}},
            {"extensions": {"MSFT_texture_dds": {"source": 1}}}
        ]);
        let mut m = json!({"name": "wall",
            "pbrMetallicRoughness": {"baseColorTexture": {"index": if base_dds { 1 } else { 0 }}},
            "normalTexture": {"index": 2}});
        if emissive_dds {
            m["emissiveFactor"] = json!([1, 1, 1]);
            m["emissiveTexture"] = json!({"index": 1});
        }
        d.json["materials"] = json!([m]);
        textured_triangle(&mut d, 0);
        d
    };
    // DDS-only textures used as normal maps only: skipped with one warning naming the extension.
    let s = load_ok(&doc(false, false).write_gltf(&dir, "normals"));
    assert_eq!(s.materials[0].base_color_texture, Some(0));
    assert_eq!(s.textures.len(), 1);
    let w = warnings_with(&s, &["MSFT_texture_dds"]);
    assert_eq!(w.len(), 1, "{:?}", s.report.warnings);
    assert!(
        w[0].contains("2 textures") && w[0].contains("skipped"),
        "{}",
        w[0]
    );
    // As the only base colour (or emissive) source: refused, naming the file and the extension.
    let p = doc(true, false).write_gltf(&dir, "base");
    let e = assert_err(gltf_load::load_path(&p), "base.gltf", "MSFT_texture_dds");
    assert!(e.contains("base colour"), "{e}");
    let p = doc(false, true).write_gltf(&dir, "emissive");
    let e = assert_err(
        gltf_load::load_path(&p),
        "emissive.gltf",
        "MSFT_texture_dds",
    );
    assert!(e.contains("emissive"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// The assimp glTF corpus

/// Whether a file declares glTF 1.x (JSON `asset.version` or GLB container version 1).
fn is_gltf1(path: &Path) -> bool {
    let Ok(bytes) = std::fs::read(path) else {
        return false;
    };
    if bytes.starts_with(b"glTF") {
        return bytes.len() >= 8 && bytes[4] == 1;
    }
    serde_json::from_slice::<Value>(&bytes)
        .ok()
        .and_then(|v| {
            v.pointer("/asset/version")
                .and_then(|v| v.as_str().map(str::to_string))
        })
        .is_some_and(|v| v.starts_with('1'))
}

fn gltf_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            gltf_files(&p, out);
        } else if p
            .extension()
            .is_some_and(|x| x.eq_ignore_ascii_case("gltf") || x.eq_ignore_ascii_case("glb"))
        {
            out.push(p);
        }
    }
}

#[test]
fn assimp_gltf_corpus() {
    let root = Path::new("/usr/share/assimp");
    assert!(
        root.join("models").is_dir(),
        "the assimp glTF test corpus is missing: run `apt-get install assimp-testmodels`"
    );
    let mut files = Vec::new();
    for base in ["models", "models-nonbsd"] {
        for e in std::fs::read_dir(root.join(base))
            .into_iter()
            .flatten()
            .flatten()
        {
            if e.file_name().to_string_lossy().starts_with("glTF") {
                gltf_files(&e.path(), &mut files);
            }
        }
    }
    files.sort();
    assert!(
        files.len() >= 20,
        "only {} glTF files found under {}",
        files.len(),
        root.display()
    );
    let (mut loaded, mut refused, mut v1) = (0, 0, 0);
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        match gltf_load::load_path(f) {
            Ok(s) => {
                assert!(!is_gltf1(f), "{} is glTF 1.0 but loaded", f.display());
                assert!(!s.triangles.is_empty());
                assert!(vertices_finite(&s), "{}", f.display());
                assert!(
                    s.triangles
                        .iter()
                        .all(|t| (s.materials.len() as u32) > t.material)
                );
                println!(
                    "loaded  {}: {} triangles, {} warnings",
                    f.display(),
                    s.triangles.len(),
                    s.report.warnings.len()
                );
                loaded += 1;
            }
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.contains(&name), "error does not name the file: {msg}");
                assert!(!msg.contains('\n'), "multi-line error: {msg:?}");
                assert!(!msg.contains("internal error"), "loader panicked: {msg}");
                if is_gltf1(f) {
                    assert!(msg.contains("glTF 1.0 is not supported"), "{msg}");
                    v1 += 1;
                }
                println!("refused {msg}");
                refused += 1;
            }
        }
    }
    println!("assimp glTF corpus: loaded {loaded}, refused {refused} ({v1} of them glTF 1.0)");
    assert!(
        v1 >= 5 && loaded >= 10,
        "loaded {loaded}, refused {refused}, glTF 1.0 {v1}"
    );
}

// ---------------------------------------------------------------------------------------------
// Real scenes (outside the repository)

/// Sponza's triangles as loaded (`fuzzy-vpl info ../shared/scenes/sponza/Sponza.gltf`).
const SPONZA_TRIANGLES: usize = 262_087;

/// The real scenes beside the clone (`../shared/scenes`; `.ci/run` requires them): each loads with
/// its instanced triangle count, finite unit normals, and what it is known to hold.
#[test]
fn real_scenes() {
    let Some(dir) = common::shared_scenes("scene_load::real_scenes") else {
        return;
    };
    // (file, instanced triangle count from SOURCES.md)
    let scenes = [
        ("cornell_wgpu/cornell-box.glb", 1_040),
        ("breakfast_room/BreakfastRoom.gltf", 262_687),
        ("livingroom_lowpoly/livingroom.glb", 3_344),
        ("conference_table/scene.gltf", 640),
        ("sponza/Sponza.gltf", SPONZA_TRIANGLES),
    ];
    for (file, expected) in scenes {
        let path = dir.join(file);
        let s = load_ok(&path);
        let n = s.triangles.len();
        println!(
            "{file}: {n} triangles (+{} degenerate dropped), {} materials, {} textures, {} lights, {} cameras; warnings: {:?}",
            s.report.dropped_degenerate,
            s.materials.len(),
            s.textures.len(),
            s.lights.len(),
            s.cameras.len(),
            s.report.warnings
        );
        assert_eq!(n + s.report.dropped_degenerate, expected, "{file}");
        assert!(
            s.report.dropped_degenerate * 100 <= expected,
            "{file}: too many degenerate"
        );
        assert!(vertices_finite(&s), "{file}");
        assert!(
            s.triangles
                .iter()
                .all(|t| t.n.iter().all(|n| (n.length() - 1.0).abs() < 1e-3))
        );
        match file {
            f if f.starts_with("cornell") => {
                assert!(s.emissive_triangle_count() > 0, "cornell has no emitter")
            }
            f if f.starts_with("breakfast") => {
                assert!(s.textures.len() >= 2, "breakfast room textures not decoded");
                assert!(s.textures.iter().all(|t| t.width.max(t.height) <= 2048));
                assert!(!s.has_light());
            }
            f if f.starts_with("conference") => assert!(s.uses_textures()),
            f if f.starts_with("sponza") => {
                assert!(s.textures.len() >= 2, "sponza textures not decoded");
                assert_eq!(s.cameras.len(), 4, "sponza's cameras");
            }
            _ => {}
        }
    }
}

/// A file of `len` bytes, all a hole (sparse: nothing is written to disk).
fn sparse_file(path: &Path, len: u64) {
    std::fs::File::create(path).unwrap().set_len(len).unwrap();
}

/// Bytes this thread has read through read(2) (`rchar` of `/proc/thread-self/io`), holes of a
/// sparse file included.
fn thread_read_bytes() -> u64 {
    let io = std::fs::read_to_string("/proc/thread-self/io").expect("/proc/thread-self/io");
    io.lines()
        .find_map(|l| l.strip_prefix("rchar: "))
        .and_then(|v| v.trim().parse().ok())
        .expect("rchar in /proc/thread-self/io")
}

/// Files are read without trusting their size: a 1 TiB sparse file as the scene (.glb, .gltf) or as
/// a buffer is refused at once (it used to abort, reserving 1 TiB), naming the size and the cap; a
/// buffer file or a GLB longer than declared is read only as far as declared; a 1 TiB texture
/// image refuses the scene. Each reads at most 1 MiB of its files (bytes this thread read, from
/// `/proc/thread-self/io`, not a clock; the loader reads on the calling thread; measured: 93 to
/// 1,455 bytes).
#[test]
fn huge_sparse_files_are_refused_or_read_only_as_declared() {
    let dir = temp_dir("sparse");
    let tib = 1u64 << 40;
    let read = |what: &str, before: u64, most: u64| {
        let n = thread_read_bytes() - before;
        println!("{what}: {n} bytes read");
        assert!(n <= most, "{what}: {n} bytes read, at most {most}");
    };
    const MIB: u64 = 1 << 20;
    for name in ["huge.glb", "huge.gltf"] {
        let p = dir.join(name);
        sparse_file(&p, tib);
        let t = thread_read_bytes();
        let e = assert_err(gltf_load::load_path(&p), name, "larger than");
        read(name, t, MIB);
        assert!(e.contains("1.0 TiB") && e.contains("4.0 GiB"), "{e}");
        std::fs::remove_file(&p).unwrap();
    }

    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(json!({"mesh": m}), true);
    // The buffer's file is 1 TiB and the buffer declares all of it.
    let p = d.write_gltf(&dir, "tbbuf");
    sparse_file(&dir.join("tbbuf.bin"), tib);
    let mut j: Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
    j["buffers"][0]["byteLength"] = json!(tib);
    std::fs::write(&p, serde_json::to_vec(&j).unwrap()).unwrap();
    let t = thread_read_bytes();
    assert_err(gltf_load::load_path(&p), "tbbuf.gltf", "larger than");
    read("1 TiB buffer", t, MIB);
    // The buffer declares its real length but its file goes on for 6 GiB: only the declared bytes
    // are read.
    let p = d.write_gltf(&dir, "longbin");
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(dir.join("longbin.bin"))
        .unwrap();
    f.set_len(6 << 30).unwrap();
    let t = thread_read_bytes();
    assert_eq!(load_ok(&p).triangles.len(), 1);
    read("6 GiB buffer file", t, MIB);
    // A GLB followed by 3 GiB of zeros: read as far as its header declares.
    let glb = dir.join("tail.glb");
    std::fs::write(&glb, d.glb()).unwrap();
    let f = std::fs::OpenOptions::new().write(true).open(&glb).unwrap();
    f.set_len(3 << 30).unwrap();
    let t = thread_read_bytes();
    assert_eq!(load_ok(&glb).triangles.len(), 1);
    read("GLB with a 3 GiB tail", t, MIB);

    // A 256 MiB texture of zeros (under the cap, not an image: refused from its first bytes) is
    // skipped with a warning, as an image that does not decode; a 1 TiB one refuses the scene from
    // its size alone.
    sparse_file(&dir.join("tb.png"), tib);
    sparse_file(&dir.join("zeros.png"), 256 << 20);
    let t = thread_read_bytes();
    let s = load_ok(&Doc::textured(json!([{"uri": "zeros.png"}])).write_gltf(&dir, "zeroimage"));
    read("256 MiB of zeros as an image", t, MIB);
    assert!(s.textures.is_empty());
    let w = &s.report.warnings;
    assert!(
        w.iter()
            .any(|w| w.contains("zeros.png") && w.contains("unrecognised image format")),
        "{w:?}"
    );
    let t = thread_read_bytes();
    let p = Doc::textured(json!([{"uri": "tb.png"}])).write_gltf(&dir, "tbimage");
    let e = assert_err(gltf_load::load_path(&p), "tbimage.gltf", "tb.png");
    read("1 TiB image", t, MIB);
    assert!(e.contains("1.0 TiB") && e.contains("512.0 MiB"), "{e}");
    // At the cap exactly (512 MiB of zeros), an image is read, not refused (cargo-mutants: the
    // size test's `>` as `>=` survived): a texture that does not decode.
    sparse_file(&dir.join("cap.png"), 512 << 20);
    let t = thread_read_bytes();
    let s = load_ok(&Doc::textured(json!([{"uri": "cap.png"}])).write_gltf(&dir, "capimage"));
    read("512 MiB of zeros as an image", t, MIB);
    let w = &s.report.warnings;
    assert!(
        w.iter()
            .any(|w| w.contains("cap.png") && w.contains("unrecognised image format")),
        "{w:?}"
    );
}

/// A texture image that does not decode is named in its warning by its name, else its file's name,
/// else `image N` (a data: URI), and the scene loads without it (cargo-mutants: the name's test
/// `!` deleted and the URI's guard as `true` survived).
#[test]
fn undecodable_images_are_named_in_their_warnings() {
    let dir = temp_dir("image_names");
    std::fs::write(dir.join("zeros.png"), [0u8; 64]).unwrap();
    std::fs::write(dir.join("plain.png"), [0u8; 64]).unwrap();
    let d = Doc::textured(json!([
        {"uri": "zeros.png", "name": "wall"},
        {"uri": "plain.png", "name": ""},
        {"uri": format!("data:image/png;base64,{}", b64(&[0u8; 12]))},
    ]));
    let s = load_ok(&d.write_gltf(&dir, "names"));
    assert!(s.textures.is_empty());
    let w = warnings_with(&s, &["not usable"]);
    assert_eq!(w.len(), 3, "{w:?}");
    for name in ["'wall'", "'plain.png'", "'image 2'"] {
        assert!(w.iter().any(|w| w.contains(name)), "{name}: {w:?}");
    }
}

/// A file of another format named .gltf or .glb says what it is instead of "bad JSON at line 1".
#[test]
fn other_formats_named_gltf_say_what_they_are() {
    let dir = temp_dir("foreign");
    let p = dir.join("picture.gltf");
    std::fs::write(&p, png_bytes(2, 2, [1, 2, 3, 255])).unwrap();
    let e = assert_err(gltf_load::load_path(&p), "picture.gltf", "PNG image");
    assert!(!e.contains("JSON"), "{e}");
    let p = dir.join("archive.gltf");
    std::fs::write(&p, b"PK\x03\x04 some zip").unwrap();
    assert_err(gltf_load::load_path(&p), "archive.gltf", "ZIP archive");
    let p = dir.join("picture.glb");
    std::fs::write(&p, png_bytes(2, 2, [1, 2, 3, 255])).unwrap();
    assert_err(gltf_load::load_path(&p), "picture.glb", "PNG image");
}

/// A mesh translated to 1e38 collapses in f32 (1e38 + 1 == 1e38): the error names the node and its
/// distance instead of only "no triangles … degenerate"; one far node among others is a warning.
#[test]
fn a_node_too_far_for_f32_is_named() {
    let dir = temp_dir("far");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m, "translation": [1e38, 0, 0]}), true);
    let p = d.write_gltf(&dir, "far");
    let e = assert_err(
        gltf_load::load_path(&p),
        "far.gltf",
        "node 0 lies 1.000e38 from the origin",
    );
    assert!(e.contains("no triangles"), "{e}");
    // The same mesh also at the origin: the scene is then 1e38 across and the near triangle is
    // degenerate relative to it too; the error still names the far node.
    d.node(json!({"mesh": m}), true);
    let p = d.write_gltf(&dir, "farandnear");
    assert_err(
        gltf_load::load_path(&p),
        "farandnear.gltf",
        "node 0 lies 1.000e38",
    );
    // 1e5 away and 1 across: the mesh spans 1.41 / (1e5 x 1.19e-7) = 119 f32 spacings: no warning;
    // at 3e6: 4 spacings, a warning naming it (the triangle, exact at spacing 0.25, is kept).
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m, "translation": [1e5, 0, 0]}), true);
    let s = load_ok(&d.write_gltf(&dir, "near"));
    assert!(s.report.warnings.is_empty(), "{:?}", s.report.warnings);
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m, "translation": [3e6, 0, 0]}), true);
    let s = load_ok(&d.write_gltf(&dir, "quantised"));
    assert_eq!(s.triangles.len(), 1);
    assert!(
        s.report
            .warnings
            .iter()
            .any(|w| w.contains("node 0 lies 3.000e6") && w.contains("quantised")),
        "{:?}",
        s.report.warnings
    );
}

/// A zero quaternion on a camera's or a light's node is no rotation: the identity is used and a
/// warning names the node and what it carries.
#[test]
fn zero_quaternions_on_cameras_and_lights_warn() {
    let dir = temp_dir("zeroquat");
    let mut d = Doc::new();
    let m = d.triangle_mesh(true);
    d.node(json!({"mesh": m}), true);
    d.json["cameras"] = json!([
        {"type": "perspective", "name": "cam", "perspective": {"yfov": 0.8, "znear": 0.1}}
    ]);
    d.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    d.json["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "spot", "name": "spot", "intensity": 10.0, "spot": {"outerConeAngle": 0.6}}
    ]}});
    d.node(
        json!({"camera": 0, "translation": [0, 0, 5], "rotation": [0, 0, 0, 0]}),
        true,
    );
    d.node(
        json!({"rotation": [0, 0, 0, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}}),
        true,
    );
    let s = load_ok(&d.write_gltf(&dir, "zeroquat"));
    let w = &s.report.warnings;
    assert!(
        w.iter()
            .any(|w| w.contains("node 1 (camera 'cam')") && w.contains("zero")),
        "{w:?}"
    );
    assert!(
        w.iter()
            .any(|w| w.contains("node 2 (light 'spot')") && w.contains("zero")),
        "{w:?}"
    );
    // The identity: the camera looks down -Z, the spot points down -Z.
    assert_eq!(s.cameras.len(), 1);
    assert!((s.cameras[0].forward() - Vec3::NEG_Z).length() < 1e-6);
    assert_eq!(s.lights.len(), 1);
    assert!((s.lights[0].direction - Vec3::NEG_Z).length() < 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Hostile input (issue 46): URIs outside the scene's folder, indices past u32, misaligned data

/// Buffer and image URIs resolve inside the scene file's folder: `..` (also percent-encoded, also
/// after a subfolder), absolute paths, `file:` URIs and symbolic links that lead out are refused
/// with one line naming the URI and the option that allows them, before any file is read; with
/// `allow_outside_uris` (`--allow-outside-uris`) each loads. URIs that stay inside load, and the
/// report lists the files they name.
#[test]
fn uris_outside_the_scene_folder_are_refused() {
    let dir = temp_dir("uri-policy");
    let scene_dir = dir.join("scene");
    std::fs::create_dir_all(scene_dir.join("sub")).unwrap();
    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(json!({"mesh": m}), true);
    for p in [
        dir.join("outside.bin"),
        scene_dir.join("sub").join("in.bin"),
    ] {
        std::fs::write(p, &d.bin).unwrap();
    }
    let outside = dir.join("outside.bin");
    let abs = outside.display().to_string();
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&outside, scene_dir.join("link.bin")).unwrap();
        std::os::unix::fs::symlink(&*dir, scene_dir.join("up")).unwrap();
    }
    let write = |name: &str, doc: &Value| {
        let path = scene_dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec(doc).unwrap()).unwrap();
        path
    };
    let refused = [
        "../outside.bin".to_string(),
        "%2e%2e/outside.bin".into(),
        "..%2Foutside.bin".into(),
        "sub/../../outside.bin".into(),
        "./sub/./../../outside.bin".into(),
        abs.clone(),
        format!("file://{abs}"),
        format!("file:{abs}"),
        "link.bin".into(),
        "up/outside.bin".into(),
    ];
    let allow = scene::LoadOptions {
        allow_outside_uris: true,
        ..Default::default()
    };
    for (i, uri) in refused.iter().enumerate() {
        let path = write(&format!("out{i}"), &d.with_buffer(Some(uri.clone())));
        let e = assert_err(gltf_load::load_path(&path), &format!("out{i}.gltf"), uri);
        assert!(
            e.contains("buffer 0") && e.contains("--allow-outside-uris"),
            "{e}"
        );
        let s = gltf_load::load_path_with(&path, &allow).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(s.triangles.len(), 1, "{uri}");
    }
    for (i, uri) in [
        "sub/in.bin",
        "sub/../sub/in.bin",
        "./sub/in.bin",
        "sub%2Fin.bin",
    ]
    .iter()
    .enumerate()
    {
        let path = write(&format!("in{i}"), &d.with_buffer(Some(uri.to_string())));
        let s = load_ok(&path);
        assert_eq!(
            s.report.files,
            vec![scene_dir.join(uri.replace("%2F", "/"))]
        );
    }
    // An image URI is refused even in a slot whose texture would only be skipped.
    let mut img = Doc::textured(json!([{"uri": "../../etc/passwd"}]));
    let pbr = img.json["materials"][0]
        .as_object_mut()
        .unwrap()
        .remove("pbrMetallicRoughness")
        .unwrap();
    img.json["materials"][0]["normalTexture"] = pbr["baseColorTexture"].clone();
    std::fs::write(scene_dir.join("img.bin"), &img.bin).unwrap();
    let path = write("img", &img.with_buffer(Some("img.bin".into())));
    let e = assert_err(gltf_load::load_path(&path), "img.gltf", "../../etc/passwd");
    assert!(e.contains("image 0"), "{e}");
}

/// glTF indices are u32: `gltf` keeps the low 32 bits of a larger one (`"scene": 4294967297` loaded
/// scene 1). Each kind of index past u32 is refused with its JSON path; a large integer in `extras`
/// (application data) is not an index and loads.
#[test]
fn indices_beyond_u32_are_refused_not_wrapped() {
    let dir = temp_dir("index-u32");
    let mut d = Doc::new();
    let m = d.triangle_mesh(false);
    d.node(json!({"mesh": m}), true);
    d.json["scenes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"nodes": [0]}));
    d.json["materials"] = json!([{}]);
    d.json["cameras"] =
        json!([{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}}]);
    d.json["samplers"] = json!([{}]);
    let big = 4_294_967_297u64;
    type Set = fn(&mut Value, u64);
    let cases: Vec<(&str, Set)> = vec![
        ("scene", |j, v| j["scene"] = json!(v)),
        ("scenes[0].nodes[0]", |j, v| {
            j["scenes"][0]["nodes"][0] = json!(v)
        }),
        ("nodes[0].mesh", |j, v| j["nodes"][0]["mesh"] = json!(v)),
        ("nodes[0].camera", |j, v| j["nodes"][0]["camera"] = json!(v)),
        ("attributes.POSITION", |j, v| {
            j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(v)
        }),
        ("primitives[0].material", |j, v| {
            j["meshes"][0]["primitives"][0]["material"] = json!(v)
        }),
        ("accessors[0].bufferView", |j, v| {
            j["accessors"][0]["bufferView"] = json!(v)
        }),
        ("baseColorTexture.index", |j, v| {
            j["materials"][0]["pbrMetallicRoughness"] = json!({"baseColorTexture": {"index": v}})
        }),
        ("textures[0].sampler", |j, v| {
            j["textures"] = json!([{"sampler": v, "source": 0}])
        }),
    ];
    for (i, (at, set)) in cases.iter().enumerate() {
        let mut doc = d.with_buffer(Some(format!("big{i}.bin")));
        set(&mut doc, big);
        let path = dir.join(format!("big{i}.gltf"));
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        std::fs::write(dir.join(format!("big{i}.bin")), &d.bin).unwrap();
        let e = assert_err(gltf_load::load_path(&path), &format!("big{i}.gltf"), at);
        assert!(e.contains("4294967297") && e.contains("2^32"), "{e}");
    }
    let mut doc = d.with_buffer(Some("extras.bin".into()));
    doc["extras"] = json!({"id": big, "list": [99_999_999_999u64]});
    doc["nodes"][0]["extras"] = json!(big);
    std::fs::write(dir.join("extras.bin"), &d.bin).unwrap();
    let path = dir.join("extras.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    assert_eq!(load_ok(&path).triangles.len(), 1);
}

/// The glTF specification's alignment rule: an accessor's byteOffset, its bufferView's byteOffset
/// plus it, and its byteStride are multiples of its component size (the sparse indices' and
/// values' offsets too); each broken one is refused, naming the accessor, not read as garbage.
#[test]
fn misaligned_accessors_are_refused() {
    let dir = temp_dir("misaligned");
    let tri = le_bytes(&[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let cases: [(&str, usize, usize, Option<usize>, &str); 4] = [
        // (name, view offset, accessor offset, stride, expected)
        ("acc2", 0, 2, None, "byteOffset 2"),
        ("view1", 1, 0, None, "bufferView at byteOffset 1"),
        ("both", 2, 2, None, "byteOffset 2"),
        ("stride", 0, 0, Some(14), "byteStride 14"),
    ];
    for (name, view_off, acc_off, stride, needle) in cases {
        let mut bin = vec![0u8; view_off + acc_off];
        bin.extend(&tri);
        bin.extend([0u8; 64]);
        let mut view =
            json!({"buffer": 0, "byteOffset": view_off, "byteLength": bin.len() - view_off});
        if let Some(s) = stride {
            view["byteStride"] = json!(s);
        }
        let doc = json!({"asset": {"version": "2.0"},
            "buffers": [{"uri": format!("{name}.bin"), "byteLength": bin.len()}],
            "bufferViews": [view],
            "accessors": [{"bufferView": 0, "byteOffset": acc_off, "componentType": 5126,
                           "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0});
        std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
        let e = assert_err(gltf_load::load_path(&path), &format!("{name}.gltf"), needle);
        assert!(
            e.contains("accessor 0") && e.contains("component size 4"),
            "{e}"
        );
    }
    // Aligned, the same layout loads (offsets and stride multiples of 4).
    let mut d = Doc::new();
    let mut bin = vec![0u8; 4];
    bin.extend(&tri);
    let v = d.view(&bin, Some(12));
    let a = d.push(
        "accessors",
        json!({"bufferView": v, "byteOffset": 4, "componentType": 5126,
        "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}),
    );
    let m = d.mesh(json!({"attributes": {"POSITION": a}}));
    d.node(json!({"mesh": m}), true);
    assert_eq!(load_ok(&d.write_gltf(&dir, "aligned")).triangles.len(), 1);
    // Sparse indices (u16) at an odd offset.
    let mut d = Doc::new();
    let p = d.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let idx = d.view(&[0, 1, 0, 2, 0], None);
    let vals = d.view(&le_bytes(&Doc::SPARSE_VALUES), None);
    d.json["accessors"][p]["sparse"] = json!({"count": 2,
        "indices": {"bufferView": idx, "byteOffset": 1, "componentType": 5123},
        "values": {"bufferView": vals}});
    d.json["accessors"][p]["max"] = json!([1, 3, 5]);
    let m = d.mesh(json!({"attributes": {"POSITION": p}}));
    d.node(json!({"mesh": m}), true);
    let e = assert_err(
        gltf_load::load_path(&d.write_gltf(&dir, "sparse")),
        "sparse.gltf",
        "sparse indices",
    );
    assert!(e.contains("component size 2"), "{e}");
}
