//! glTF 2.0 (`.gltf` / `.glb`) loader: flattens the default scene into world-space triangles,
//! materials, textures, `KHR_lights_punctual` lights and perspective cameras.
//!
//! Errors are one line naming the file and the problem; malformed input never panics (a
//! `catch_unwind` guard turns any remaining panic into a `SceneError`). Recoverable oddities
//! (undecodable textures, orthographic cameras, bad light parameters…) become warnings in
//! `LoadReport::warnings`.
//!
//! Units: light colours and intensities are kept exactly as the file gives them (glTF: candela for
//! point/spot lights, lux for directional lights); no photometric→radiometric conversion is done.
//! Light `range` is ignored (inverse-square falloff).

mod accessor;
mod images;
pub mod read;
mod uri;

use super::{
    Camera, LightKind, LoadOptions, LoadReport, Material, PunctualLight, Scene, SceneError,
    Texture, Triangle,
};
use crate::panic_guard::one_line;
use glam::{Affine2, DMat3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json::validation::Validate;
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::path::Path;

pub use images::MAX_TEXTURE_SIDE;

/// Extensions that may appear in `extensionsRequired`: the ones this loader fully honours.
pub const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
];

/// Required extensions that change only what a diffuse renderer does not model (specular lobes,
/// clearcoat, sheen, transmission, refraction, how roughness and metallic are packed…) or that
/// only add data it does not read: a file requiring them loads, with one warning naming them.
/// Each keeps the core material's base colour as the diffuse colour (their specifications say a
/// viewer without them falls back to the core material).
pub const IGNORABLE_REQUIRED_EXTENSIONS: &[&str] = &[
    "AMD_split_roughnessMetallic",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_animation_pointer",
    "KHR_xmp_json_ld",
    "EXT_lights_image_based",
    "MSFT_lod",
    "MSFT_packing_normalRoughnessMetallic",
    "MSFT_packing_occlusionRoughnessMetallic",
];

/// Required extensions that give a texture a source in a format the loader cannot decode. A file
/// requiring them loads; each texture is judged where it is used: a base colour or emissive
/// texture with no readable source refuses the file, any other one is skipped with a warning.
pub const TEXTURE_FORMAT_EXTENSIONS: &[&str] = &[
    "MSFT_texture_dds",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
];

/// Required extensions that change geometry or the diffuse colour and that the loader does not
/// decode: always refused, with the reason.
pub const REFUSED_REQUIRED_EXTENSIONS: &[(&str, &str)] = &[
    (
        "KHR_draco_mesh_compression",
        "its geometry is Draco-compressed",
    ),
    (
        "EXT_meshopt_compression",
        "its geometry is meshopt-compressed",
    ),
    (
        "KHR_meshopt_compression",
        "its geometry is meshopt-compressed",
    ),
    (
        "EXT_mesh_gpu_instancing",
        "it places meshes by GPU instancing",
    ),
    (
        "KHR_materials_pbrSpecularGlossiness",
        "it replaces the base colour with a diffuse colour",
    ),
];

/// A triangle is degenerate when its area is at most this fraction of the squared scene extent
/// (bounding-box diagonal), which keeps the test scale-free.
const DEGENERATE_AREA_REL: f64 = 1e-12;
/// …or when twice its area is at most this fraction of its longest edge squared (numerically
/// collinear vertices: its height is below f32 precision relative to its length).
const DEGENERATE_SLIVER_REL: f64 = 1e-7;

/// Loads a `.gltf` (external files resolved relative to it, or `data:` URIs) or `.glb` file.
pub fn load_path(path: &Path) -> Result<Scene, SceneError> {
    load_path_with(path, &LoadOptions::default())
}

/// `load_path` with options (extensions the user allows).
pub fn load_path_with(path: &Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    guarded(&file, || {
        let bytes = read::read_scene_file(path).map_err(|e| format!("cannot read file: {e}"))?;
        let base = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let glb_name = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        let mut scene = load_bytes(&bytes, Some(base), glb_name, opts)?;
        scene.name = file.clone();
        scene.path = Some(path.to_path_buf());
        Ok(scene)
    })
}

/// Loads a GLB or self-contained glTF held in memory; `name` labels errors and becomes `Scene::name`.
pub fn load_slice(bytes: &[u8], name: &str) -> Result<Scene, SceneError> {
    load_slice_with(bytes, name, &LoadOptions::default())
}

/// `load_slice` with options (extensions the user allows).
pub fn load_slice_with(bytes: &[u8], name: &str, opts: &LoadOptions) -> Result<Scene, SceneError> {
    guarded(name, || {
        let glb_name = name.to_ascii_lowercase().ends_with(".glb");
        let mut scene = load_bytes(bytes, None, glb_name, opts)?;
        scene.name = name.to_string();
        Ok(scene)
    })
}

// ---------------------------------------------------------------------------------------------
// Panic guard

/// Runs a load, turning `Err(problem)` and any panic into a one-line `SceneError` for `file`.
fn guarded(file: &str, load: impl FnOnce() -> Result<Scene, String>) -> Result<Scene, SceneError> {
    match crate::panic_guard::quietly(load) {
        Ok(Ok(scene)) => Ok(scene),
        Ok(Err(problem)) => Err(SceneError::new(file, one_line(&problem))),
        Err(msg) => Err(SceneError::new(
            file,
            one_line(&format!("internal error while loading ({msg})")),
        )),
    }
}

// ---------------------------------------------------------------------------------------------
// Container and JSON

/// Splits a GLB into its JSON chunk and optional BIN chunk, with precise errors.
fn parse_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let u32_at =
        |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    if bytes.len() < 12 {
        return Err(format!(
            "truncated GLB: {} bytes, less than the 12-byte header",
            bytes.len()
        ));
    }
    match u32_at(4) {
        2 => {}
        1 => {
            return Err(
                "glTF 1.0 is not supported (binary glTF version 1); convert the file to glTF 2.0"
                    .into(),
            );
        }
        v => return Err(format!("unsupported GLB container version {v}")),
    }
    let declared = u32_at(8) as usize;
    if declared > bytes.len() {
        return Err(format!(
            "truncated GLB: header declares {declared} bytes but the file has {}",
            bytes.len()
        ));
    }
    let bytes = &bytes[..declared];
    let mut at = 12;
    let mut json = None;
    let mut bin = None;
    while at < bytes.len() {
        if at + 8 > bytes.len() {
            return Err(format!("corrupt GLB: truncated chunk header at byte {at}"));
        }
        let len = u32_at(at) as usize;
        let ty = &bytes[at + 4..at + 8];
        let start = at + 8;
        let end = start
            .checked_add(len)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                format!(
                    "truncated GLB: chunk at byte {at} declares {len} bytes but only {} remain",
                    bytes.len() - start
                )
            })?;
        let data = &bytes[start..end];
        match ty {
            b"JSON" if json.is_none() && at == 12 => json = Some(data),
            b"BIN\0" if json.is_some() && bin.is_none() => bin = Some(data),
            b"JSON" | b"BIN\0" => {
                return Err(format!("corrupt GLB: unexpected chunk at byte {at}"));
            }
            _ if json.is_none() => return Err("corrupt GLB: the first chunk is not JSON".into()),
            _ => {} // unknown chunk types are skipped, per the spec
        }
        at = end.next_multiple_of(4);
    }
    let json = json.ok_or("corrupt GLB: no JSON chunk")?;
    Ok((json, bin))
}

/// Why a JSON document that failed to deserialize was refused: a glTF 1.0 file, an unsupported
/// required extension, or the deserialization error itself.
fn explain_bad_json(json: &[u8], err: &serde_json::Error, opts: &LoadOptions) -> String {
    if let Ok(v) = serde_json::from_slice::<serde_json::Value>(json) {
        if let Some(ver) = v.pointer("/asset/version") {
            let ver = ver
                .as_str()
                .map(str::to_string)
                .unwrap_or_else(|| ver.to_string());
            if let Err(e) = check_version(&ver) {
                return e;
            }
        }
        if let Some(req) = v.get("extensionsRequired").and_then(|r| r.as_array()) {
            let names: Vec<String> = req
                .iter()
                .filter_map(|x| x.as_str().map(str::to_string))
                .collect();
            if let Err(e) = check_required(&names, opts) {
                return e;
            }
        }
        return format!("invalid glTF: {err}");
    }
    format!("bad JSON: {err}")
}

fn check_version(version: &str) -> Result<(), String> {
    match version.trim().split('.').next() {
        Some("2") => Ok(()),
        Some("1") | Some("0") => Err(format!(
            "glTF 1.0 is not supported (asset.version \"{}\"); convert the file to glTF 2.0",
            uri::short(version)
        )),
        _ => Err(format!(
            "unsupported glTF version \"{}\" (only 2.x is supported)",
            uri::short(version)
        )),
    }
}

/// Checks `extensionsRequired`: supported ones pass, refused ones fail with their reason, unknown
/// ones fail unless allowed (`--allow-extension`). Returns the ignored ones: (known to be
/// ignorable, allowed by the user), for a warning each.
fn check_required(
    required: &[String],
    opts: &LoadOptions,
) -> Result<(Vec<String>, Vec<String>), String> {
    let mut ignored = Vec::new();
    let mut allowed = Vec::new();
    for e in required {
        let name = e.as_str();
        if SUPPORTED_REQUIRED_EXTENSIONS.contains(&name)
            || TEXTURE_FORMAT_EXTENSIONS.contains(&name)
        {
            continue;
        }
        if let Some((_, why)) = REFUSED_REQUIRED_EXTENSIONS.iter().find(|(n, _)| *n == name) {
            return Err(format!(
                "requires extension {name}, which fuzzy-vpl does not support ({why})"
            ));
        }
        let list = if IGNORABLE_REQUIRED_EXTENSIONS.contains(&name) {
            &mut ignored
        } else if opts.allow_extensions.iter().any(|a| a == name) {
            &mut allowed
        } else {
            let e = uri::short(e);
            return Err(format!(
                "requires extension {e}, which fuzzy-vpl does not know; if it changes neither geometry nor diffuse colour, load the file with --allow-extension {e}"
            ));
        };
        if !list.contains(e) {
            list.push(e.clone());
        }
    }
    Ok((ignored, allowed))
}

/// Required extensions a loaded file declares and the loader ignores: (known to be ignorable,
/// allowed with `--allow-extension`).
type Ignored = (Vec<String>, Vec<String>);

/// Parses, version-checks and validates the JSON document; also returns the required extensions
/// it ignores.
fn parse_document(json: &[u8], opts: &LoadOptions) -> Result<(gltf::Document, Ignored), String> {
    let json = json.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(json);
    let root = gltf::json::Root::from_slice(json).map_err(|e| explain_bad_json(json, &e, opts))?;
    check_version(&root.asset.version)?;
    let ignored = check_required(&root.extensions_required, opts)?;

    // gltf-json's primitive hook indexes `accessors` with the POSITION index unchecked.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&pos)
                && i.value() >= root.accessors.len()
            {
                return Err(format!(
                    "invalid glTF: meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist",
                    i.value()
                ));
            }
        }
    }

    let mut errors = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |path, err| {
        let path = path();
        // Required extensions were checked above against what this loader honours.
        if !path.as_str().starts_with("extensionsRequired") {
            errors.push(format!("{}: {}", path.as_str(), err));
        }
    });
    if !errors.is_empty() {
        let more = if errors.len() > 2 {
            format!(" (and {} more)", errors.len() - 2)
        } else {
            String::new()
        };
        return Err(format!(
            "invalid glTF: {}{more}",
            errors[..errors.len().min(2)].join("; ")
        ));
    }
    Ok((gltf::Document::from_json_without_validation(root), ignored))
}

/// Loads every buffer: the GLB BIN chunk, `data:` URIs or files next to the glTF.
fn load_buffers(
    doc: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let i = buffer.index();
        let (data, label) = match buffer.source() {
            gltf::buffer::Source::Bin => (
                blob.take()
                    .ok_or_else(|| format!("buffer {i} refers to a GLB BIN chunk that is missing"))?
                    .to_vec(),
                "the BIN chunk".to_string(),
            ),
            gltf::buffer::Source::Uri(u) => {
                let label = if u.starts_with("data:") {
                    "its data: URI".to_string()
                } else {
                    format!("'{}'", uri::short(u))
                };
                let data = match uri::resolve(u, base).map_err(|e| format!("buffer {i}: {e}"))? {
                    uri::Resolved::Data(d) => d,
                    uri::Resolved::File(p) => read::read_buffer_file(&p, buffer.length() as u64)
                        .map_err(|e| format!("buffer {i}: cannot read '{}': {e}", p.display()))?,
                };
                (data, label)
            }
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} ({label}) has {} bytes but declares byteLength {} (buffer too short)",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Materials and textures

/// Materials plus what triangle emission needs to know about them.
struct MaterialTable {
    materials: Vec<Material>,
    /// Per material: the `KHR_texture_transform` applied to its TEXCOORD_0.
    uv_transform: Vec<Option<Affine2>>,
    /// Index of the glTF default material once a primitive needed it.
    default: Option<u32>,
}

impl MaterialTable {
    fn index_for(&mut self, gltf_material: Option<usize>) -> u32 {
        match gltf_material {
            Some(i) => i as u32,
            None => *self.default.get_or_insert_with(|| {
                self.materials.push(Material::default());
                self.uv_transform.push(None);
                (self.materials.len() - 1) as u32
            }),
        }
    }
}

/// The uv transform of a `KHR_texture_transform`: translation × rotation × scale.
fn texture_transform(info: &gltf::texture::Info) -> Option<Affine2> {
    let t = info.texture_transform()?;
    let (s, c) = t.rotation().sin_cos();
    let [sx, sy] = t.scale();
    // uv' = T * R * S * uv with R = [[cos, sin], [-sin, cos]] (row-major), the convention of the
    // Khronos sample viewer and three.js.
    Some(Affine2::from_cols_array(&[
        c * sx,
        -s * sx,
        s * sy,
        c * sy,
        t.offset()[0],
        t.offset()[1],
    ]))
}

fn finite_or(v: Vec4, fallback: Vec4) -> Vec4 {
    if v.is_finite() { v } else { fallback }
}

/// Texture decoding state: each glTF image is decoded at most once.
struct TextureCache<'a> {
    buffers: &'a [Vec<u8>],
    base: Option<&'a Path>,
    /// glTF image index → `textures` index (`None` when it could not be decoded).
    decoded: HashMap<usize, Option<u32>>,
    textures: Vec<Texture>,
}

impl TextureCache<'_> {
    /// The scene texture and uv transform for a material's texture slot, or `None` (with a warning
    /// when the slot is set but unusable) so the material falls back to its factor. A texture
    /// whose only source is in a format extension the loader cannot decode (DDS, KTX2, WebP…)
    /// refuses the file: the slots resolved here are the colours fuzzy-vpl renders.
    fn resolve(
        &mut self,
        info: Option<gltf::texture::Info>,
        what: &str,
        report: &mut LoadReport,
    ) -> Result<Option<(u32, Option<Affine2>)>, String> {
        let Some(info) = info else { return Ok(None) };
        let set = info
            .texture_transform()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord());
        if set != 0 {
            report.warnings.push(format!(
                "{what} uses TEXCOORD_{set}; only TEXCOORD_0 is supported, texture ignored"
            ));
            return Ok(None);
        }
        let texture = info.texture();
        let Some(image) = texture.source() else {
            return Err(format!(
                "{what} (texture {}) has no source fuzzy-vpl can read, only {}",
                texture.index(),
                source_extensions(&texture)
            ));
        };
        if let Some(why) = images::refused_file(&image, self.base) {
            return Err(format!("{what}: {why}"));
        }
        let index = *self.decoded.entry(image.index()).or_insert_with(|| {
            let label = images::image_name(&image);
            // A decoder crash on a hostile image costs the texture, not the scene.
            let decoded = crate::panic_guard::quietly(|| {
                images::encoded_bytes(&image, self.buffers, self.base)
                    .and_then(|bytes| images::decode(&bytes, &label))
            })
            .unwrap_or_else(|msg| Err(format!("the image decoder crashed: {msg}")));
            match decoded {
                Ok(t) => {
                    self.textures.push(t);
                    Some((self.textures.len() - 1) as u32)
                }
                Err(e) => {
                    report.warnings.push(format!(
                        "texture image '{label}' not usable ({e}); materials using it fall back to their factors"
                    ));
                    None
                }
            }
        });
        Ok(index.map(|i| (i, texture_transform(&info))))
    }
}

/// The extensions that give a texture without a core `source` its image (e.g. `MSFT_texture_dds`).
fn source_extensions(texture: &gltf::Texture) -> String {
    let names: Vec<String> = texture
        .extensions()
        .map(|m| m.keys().map(|k| uri::short(k)).collect())
        .unwrap_or_default();
    if names.is_empty() {
        "no source at all".into()
    } else {
        names.join(", ")
    }
}

/// One warning for the textures without a readable source that no base colour or emissive slot
/// uses (normal, roughness… maps in DDS or KTX2 only): they are skipped.
fn warn_unreadable_textures(doc: &gltf::Document, report: &mut LoadReport) {
    let used: std::collections::HashSet<usize> = doc
        .materials()
        .flat_map(|m| {
            [
                m.pbr_metallic_roughness().base_color_texture(),
                m.emissive_texture(),
            ]
        })
        .flatten()
        .map(|i| i.texture().index())
        .collect();
    let skipped: Vec<gltf::Texture> = doc
        .textures()
        .filter(|t| t.source().is_none() && !used.contains(&t.index()))
        .collect();
    let Some(first) = skipped.first() else {
        return;
    };
    let list = if skipped.len() <= 4 {
        skipped
            .iter()
            .map(|t| t.index().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    } else {
        format!(
            "{}, {} … {}",
            skipped[0].index(),
            skipped[1].index(),
            skipped[skipped.len() - 1].index()
        )
    };
    report.warnings.push(format!(
        "{} texture{} ({list}) {} no source fuzzy-vpl can read (only {}); not a base colour or emissive texture, skipped",
        skipped.len(),
        if skipped.len() > 1 { "s" } else { "" },
        if skipped.len() > 1 { "have" } else { "has" },
        source_extensions(first),
    ));
}

/// Builds the material table; textures are decoded once per glTF image actually used.
fn load_materials(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    base: Option<&Path>,
    report: &mut LoadReport,
) -> Result<(MaterialTable, Vec<Texture>), String> {
    warn_unreadable_textures(doc, report);
    let mut cache = TextureCache {
        buffers,
        base,
        decoded: HashMap::new(),
        textures: Vec::new(),
    };
    let mut table = MaterialTable {
        materials: Vec::new(),
        uv_transform: Vec::new(),
        default: None,
    };
    let mut blend = Vec::new();

    for m in doc.materials() {
        let i = m.index().unwrap_or(0);
        let name = m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material {i}"));
        let pbr = m.pbr_metallic_roughness();

        let base_color = Vec4::from(pbr.base_color_factor());
        let base_color = finite_or(base_color, Vec4::ONE);
        let clamped = base_color.clamp(Vec4::ZERO, Vec4::ONE);
        if clamped != base_color {
            report.warnings.push(format!(
                "material '{name}': baseColorFactor outside [0, 1], clamped"
            ));
        }

        let strength = m.emissive_strength().unwrap_or(1.0);
        let emissive = Vec3::from(m.emissive_factor()) * strength;
        let emissive = if emissive.is_finite() && emissive.min_element() >= 0.0 {
            emissive
        } else {
            report.warnings.push(format!(
                "material '{name}': invalid emissive factor or strength, ignored"
            ));
            Vec3::ZERO
        };

        let base_tex = cache.resolve(
            pbr.base_color_texture(),
            &format!("material '{name}': the base colour texture"),
            report,
        )?;
        let emissive_tex = cache.resolve(
            m.emissive_texture(),
            &format!("material '{name}': the emissive texture"),
            report,
        )?;

        use gltf::material::AlphaMode;
        let alpha_cutoff = match m.alpha_mode() {
            AlphaMode::Opaque => None,
            AlphaMode::Mask => Some(match m.alpha_cutoff() {
                None => 0.5,
                Some(c) if c.is_finite() && c >= 0.0 => c,
                Some(c) => {
                    report.warnings.push(format!(
                        "material '{name}': invalid alphaCutoff {c}, 0.5 used"
                    ));
                    0.5
                }
            }),
            AlphaMode::Blend => {
                blend.push(name.clone());
                Some(0.5)
            }
        };
        // Triangles carry one uv set, so one KHR_texture_transform per material: the base colour
        // texture's when there is one.
        let uv_transform = match (base_tex, emissive_tex) {
            (Some((_, a)), Some((_, b))) => {
                let same = match (a, b) {
                    (Some(a), Some(b)) => a.abs_diff_eq(b, 1e-6),
                    (a, b) => a.is_none() && b.is_none(),
                };
                if !same {
                    report.warnings.push(format!(
                        "material '{name}': base colour and emissive textures have different KHR_texture_transform; the base colour one is used for both"
                    ));
                }
                a
            }
            (Some((_, a)), None) | (None, Some((_, a))) => a,
            (None, None) => None,
        };

        table.materials.push(Material {
            name,
            base_color: clamped,
            base_color_texture: base_tex.map(|t| t.0),
            alpha_cutoff,
            emissive,
            emissive_texture: emissive_tex.map(|t| t.0),
        });
        table.uv_transform.push(uv_transform);
    }
    if let Some(first) = blend.first() {
        report.warnings.push(format!(
            "{} material{} ('{first}'{}) with alphaMode BLEND rendered as MASK with cutoff 0.5",
            blend.len(),
            if blend.len() > 1 { "s" } else { "" },
            if blend.len() > 1 { ", …" } else { "" },
        ));
    }
    Ok((table, cache.textures))
}

// ---------------------------------------------------------------------------------------------
// Geometry

/// A mesh primitive decoded once, in its local space, shared by every node that instances it.
enum Primitive {
    Triangles {
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
        /// COLOR_0 as linear RGBA (alpha 1 for RGB).
        colors: Option<Vec<Vec4>>,
        /// Vertex index triples, in glTF winding order.
        tris: Vec<[u32; 3]>,
        material: u32,
    },
    /// Points or lines: not rendered.
    Skipped,
}

fn decode_primitive(
    prim: &gltf::Primitive,
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
    table: &mut MaterialTable,
    report: &mut LoadReport,
) -> Result<Primitive, String> {
    use gltf::mesh::Mode;
    let label = match mesh.name() {
        Some(n) => format!(
            "mesh {} ('{}') primitive {}",
            mesh.index(),
            uri::short(n),
            prim.index()
        ),
        None => format!("mesh {} primitive {}", mesh.index(), prim.index()),
    };
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        report.skipped_primitives += 1;
        return Ok(Primitive::Skipped);
    }

    let pos_acc = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| format!("{label} has no POSITION attribute"))?;
    let positions: Vec<Vec3> =
        accessor::read_floats::<3>(&pos_acc, buffers, &format!("{label} POSITION"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
    if let Some(v) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "{label} POSITION has a non-finite value ({}) at vertex {v}",
            positions[v]
        ));
    }
    let n = positions.len();

    let normals = match prim.get(&gltf::Semantic::Normals) {
        None => None,
        Some(acc) => match accessor::read_floats::<3>(&acc, buffers, &format!("{label} NORMAL")) {
            Ok(v) if v.len() == n => Some(v.into_iter().map(Vec3::from).collect()),
            Ok(v) => {
                report.warnings.push(format!(
                    "{label}: NORMAL has {} entries for {n} vertices, normals generated",
                    v.len()
                ));
                None
            }
            Err(e) => {
                report.warnings.push(format!("{e}; normals generated"));
                None
            }
        },
    };
    let uvs = match prim.get(&gltf::Semantic::TexCoords(0)) {
        None => None,
        Some(acc) => {
            match accessor::read_floats::<2>(&acc, buffers, &format!("{label} TEXCOORD_0")) {
                Ok(v) if v.len() == n => Some(v.into_iter().map(Vec2::from).collect()),
                Ok(v) => {
                    report.warnings.push(format!(
                        "{label}: TEXCOORD_0 has {} entries for {n} vertices, ignored",
                        v.len()
                    ));
                    None
                }
                Err(e) => {
                    report
                        .warnings
                        .push(format!("{e}; texture coordinates ignored"));
                    None
                }
            }
        }
    };

    let colors = match prim.get(&gltf::Semantic::Colors(0)) {
        None => None,
        Some(acc) => match read_colors(&acc, buffers, &format!("{label} COLOR_0")) {
            Ok(v) if v.len() == n => {
                if v.iter().any(|c| {
                    !c.is_finite() || c.cmplt(Vec4::ZERO).any() || c.cmpgt(Vec4::ONE).any()
                }) {
                    report.warnings.push(format!(
                        "{label}: COLOR_0 has values outside [0, 1], clamped"
                    ));
                }
                Some(
                    v.into_iter()
                        .map(|c| finite_or(c, Vec4::ONE).clamp(Vec4::ZERO, Vec4::ONE))
                        .collect(),
                )
            }
            Ok(v) => {
                report.warnings.push(format!(
                    "{label}: COLOR_0 has {} entries for {n} vertices, ignored",
                    v.len()
                ));
                None
            }
            Err(e) => {
                report.warnings.push(format!("{e}; vertex colours ignored"));
                None
            }
        },
    };

    let indices: Vec<u32> = match prim.indices() {
        Some(acc) => {
            let idx = accessor::read_indices(&acc, buffers, &format!("{label} indices"))?;
            if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "{label}: index {bad} out of range (the primitive has {n} vertices)"
                ));
            }
            idx
        }
        None => (0..n as u32).collect(),
    };

    let tris: Vec<[u32; 3]> = match mode {
        Mode::Triangles => {
            if !indices.len().is_multiple_of(3) {
                report.warnings.push(format!(
                    "{label}: {} indices is not a multiple of 3, the last {} ignored",
                    indices.len(),
                    indices.len() % 3
                ));
            }
            indices
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect()
        }
        // glTF: triangle i = (v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]).
        Mode::TriangleStrip => (0..indices.len().saturating_sub(2))
            .map(|i| {
                let odd = i % 2;
                [indices[i], indices[i + 1 + odd], indices[i + 2 - odd]]
            })
            .collect(),
        // glTF: triangle i = (v[i + 1], v[i + 2], v[0]).
        _ => (0..indices.len().saturating_sub(2))
            .map(|i| [indices[i + 1], indices[i + 2], indices[0]])
            .collect(),
    };

    Ok(Primitive::Triangles {
        positions,
        normals,
        uvs,
        colors,
        tris,
        material: table.index_for(prim.material().index()),
    })
}

/// COLOR_0: VEC3 or VEC4 of float or normalised unsigned byte / short, as linear RGBA.
fn read_colors(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<Vec<Vec4>, String> {
    use gltf::accessor::{DataType, Dimensions};
    let ok_type = match acc.data_type() {
        DataType::F32 => true,
        DataType::U8 | DataType::U16 => acc.normalized(),
        _ => false,
    };
    if !ok_type {
        return Err(format!(
            "{what} (accessor {}) must be float or normalised unsigned byte or short",
            acc.index()
        ));
    }
    match acc.dimensions() {
        Dimensions::Vec3 => Ok(accessor::read_floats::<3>(acc, buffers, what)?
            .into_iter()
            .map(|c| Vec3::from(c).extend(1.0))
            .collect()),
        _ => Ok(accessor::read_floats::<4>(acc, buffers, what)?
            .into_iter()
            .map(Vec4::from)
            .collect()),
    }
}

/// A node's local matrix. TRS rotations are normalised (glTF requires unit quaternions; a
/// non-unit one would otherwise shear).
fn local_matrix(node: &gltf::Node) -> Mat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => Mat4::from_cols_array_2d(&matrix),
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = Quat::from_array(rotation);
            let q = if q.length_squared() > 0.0 && q.is_finite() {
                q.normalize()
            } else {
                Quat::IDENTITY
            };
            Mat4::from_scale_rotation_translation(Vec3::from(scale), q, Vec3::from(translation))
        }
    }
}

/// `(node index, world matrix)` for every node of the scene to render, parents before children.
fn flatten_nodes(doc: &gltf::Document) -> Result<Vec<(usize, Mat4)>, String> {
    let count = doc.nodes().len();
    let mut parent: Vec<Option<usize>> = vec![None; count];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            if c == node.index() {
                return Err(format!("invalid node hierarchy: node {c} is its own child"));
            }
            if let Some(p) = parent[c] {
                return Err(format!(
                    "invalid node hierarchy: node {c} has two parents (nodes {p} and {})",
                    node.index()
                ));
            }
            parent[c] = Some(node.index());
        }
    }

    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            let roots: Vec<usize> = scene.nodes().map(|n| n.index()).collect();
            if let Some(&r) = roots.iter().find(|&&r| parent[r].is_some()) {
                return Err(format!(
                    "invalid node hierarchy: scene root node {r} is a child of node {}",
                    parent[r].unwrap_or(0)
                ));
            }
            roots
        }
        None => (0..count).filter(|&i| parent[i].is_none()).collect(),
    };

    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut visited = vec![false; count];
    let mut out = Vec::new();
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
    while let Some((i, parent_world)) = stack.pop() {
        if std::mem::replace(&mut visited[i], true) {
            return Err(format!(
                "invalid node hierarchy: node {i} is reached twice (a cycle or a repeated scene root)"
            ));
        }
        let world = parent_world * local_matrix(&nodes[i]);
        out.push((i, world));
        for child in nodes[i].children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child.index(), world));
        }
    }
    Ok(out)
}

/// Appends the world-space triangles of one primitive instance. Invalid normals are left as
/// `Vec3::ZERO` and filled in later with the face normal.
fn emit(
    prim: &Primitive,
    world: &Mat4,
    node: usize,
    uv_transform: &[Option<Affine2>],
    out: &mut Vec<Triangle>,
) -> Result<(), String> {
    let Primitive::Triangles {
        positions,
        normals,
        uvs,
        colors,
        tris,
        material,
    } = prim
    else {
        return Ok(());
    };
    let world_pos: Vec<Vec3> = positions
        .iter()
        .map(|&p| world.transform_point3(p))
        .collect();
    if let Some(p) = world_pos.iter().find(|p| !p.is_finite()) {
        return Err(format!(
            "node {node}: a vertex position is not finite after the node transform ({p})"
        ));
    }
    // In f64 so that tiny (or huge) scales keep a usable determinant sign and inverse.
    let m3 = DMat3::from_mat4(world.as_dmat4());
    let det = m3.determinant();
    let normal_matrix = (det != 0.0 && det.is_finite())
        .then(|| m3.inverse().transpose().as_mat3())
        .filter(|m| m.is_finite());
    let world_n: Option<Vec<Vec3>> = match (normals, normal_matrix) {
        (Some(ns), Some(nm)) => Some(
            ns.iter()
                .map(|&n| {
                    let v = (nm * n).normalize_or_zero();
                    if v.is_finite() { v } else { Vec3::ZERO }
                })
                .collect(),
        ),
        _ => None,
    };
    let xf = uv_transform[*material as usize];
    let world_uv: Option<Vec<Vec2>> = uvs.as_ref().map(|uvs| match xf {
        Some(a) => uvs.iter().map(|&uv| a.transform_point2(uv)).collect(),
        None => uvs.clone(),
    });

    out.reserve(tris.len());
    for &t in tris {
        // A mirroring transform reverses the winding; swap to keep the front face.
        let t = if det < 0.0 { [t[0], t[2], t[1]] } else { t };
        let [a, b, c] = t.map(|i| i as usize);
        out.push(Triangle {
            p: [world_pos[a], world_pos[b], world_pos[c]],
            n: match &world_n {
                Some(n) => [n[a], n[b], n[c]],
                None => [Vec3::ZERO; 3],
            },
            uv: match &world_uv {
                Some(uv) => [uv[a], uv[b], uv[c]],
                None => [Vec2::ZERO; 3],
            },
            color: match colors {
                Some(col) => [col[a], col[b], col[c]],
                None => [Vec4::ONE; 3],
            },
            material: *material,
        });
    }
    Ok(())
}

/// A mesh instance placed so far from the origin, for its size, that f32 positions cannot resolve it.
struct FarNode {
    node: usize,
    /// The largest coordinate magnitude of its vertices (world units, computed in f64).
    far: f64,
    /// Its bounding-box diagonal (world units, f64).
    size: f64,
}

impl FarNode {
    fn describe(&self) -> String {
        format!(
            "node {} lies {:.3e} from the origin, where f32 positions are {:.1e} apart, and its mesh is only {:.3e} across",
            self.node,
            self.far,
            self.far * f32::EPSILON as f64,
            self.size
        )
    }
}

/// `Some` when an instance of `prim` under `world` spans fewer than 10 f32 spacings at its distance
/// from the origin (its shape is then quantised to a few positions or collapses to nothing).
fn too_far_for_f32(prim: &Primitive, world: &Mat4, node: usize) -> Option<FarNode> {
    let Primitive::Triangles { positions, .. } = prim else {
        return None;
    };
    let w = world.as_dmat4();
    let mut lo = glam::DVec3::splat(f64::INFINITY);
    let mut hi = glam::DVec3::splat(f64::NEG_INFINITY);
    for p in positions {
        let q = w.transform_point3(p.as_dvec3());
        lo = lo.min(q);
        hi = hi.max(q);
    }
    let far = lo.abs().max(hi.abs()).max_element();
    let size = (hi - lo).length();
    (size > 0.0 && far * (f32::EPSILON as f64) > 0.1 * size).then_some(FarNode { node, far, size })
}

/// A warning for a node whose TRS rotation is no rotation (a zero or non-finite quaternion; the
/// identity is used, `local_matrix`), naming what the node carries.
fn zero_rotation_warning(node: &gltf::Node) -> Option<String> {
    let gltf::scene::Transform::Decomposed { rotation, .. } = node.transform() else {
        return None;
    };
    let q = Quat::from_array(rotation);
    if q.is_finite() && q.length_squared() > 0.0 {
        return None;
    }
    let mut what = Vec::new();
    if let Some(c) = node.camera() {
        what.push(format!("camera '{}'", c.name().unwrap_or("")));
    }
    if let Some(l) = node.light() {
        what.push(format!("light '{}'", l.name().unwrap_or("")));
    }
    if node.mesh().is_some() {
        what.push("a mesh".to_string());
    }
    let what = if what.is_empty() {
        String::new()
    } else {
        format!(" ({})", what.join(", "))
    };
    Some(format!(
        "node {}{what}: rotation {rotation:?} is a zero or non-finite quaternion, not a rotation; the identity is used for it",
        node.index()
    ))
}

/// Whether a triangle has (numerically) no area, relative to the scene and to its own size.
fn is_degenerate(t: &Triangle, extent_sq: f64) -> bool {
    let p = t.p.map(|v| v.as_dvec3());
    let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let twice_area = e[0].cross(-e[2]).length();
    let longest_sq = e.iter().map(|v| v.length_squared()).fold(0.0, f64::max);
    twice_area <= 2.0 * DEGENERATE_AREA_REL * extent_sq
        || twice_area <= DEGENERATE_SLIVER_REL * longest_sq
}

// ---------------------------------------------------------------------------------------------
// Lights and cameras

fn light_from_node(
    light: &gltf::khr_lights_punctual::Light,
    world: &Mat4,
    report: &mut LoadReport,
) -> Option<PunctualLight> {
    use gltf::khr_lights_punctual::Kind;
    let name = light
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("light {}", light.index()));
    let color = Vec3::from(light.color());
    let intensity = light.intensity();
    if !color.is_finite() || color.min_element() < 0.0 || !intensity.is_finite() || intensity < 0.0
    {
        report.warnings.push(format!(
            "light '{name}': invalid colour or intensity, light skipped"
        ));
        return None;
    }
    let position = world.w_axis.truncate();
    let direction = (world.as_dmat4())
        .transform_vector3(glam::DVec3::NEG_Z)
        .normalize_or_zero()
        .as_vec3();
    if !position.is_finite() || direction == Vec3::ZERO || !direction.is_finite() {
        report.warnings.push(format!(
            "light '{name}': its node transform is degenerate, light skipped"
        ));
        return None;
    }
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let half_pi = std::f32::consts::FRAC_PI_2;
            let ok =
                (0.0..outer_cone_angle).contains(&inner_cone_angle) && outer_cone_angle <= half_pi;
            if ok {
                LightKind::Spot {
                    inner_cone: inner_cone_angle,
                    outer_cone: outer_cone_angle,
                }
            } else {
                let outer = if outer_cone_angle.is_finite() {
                    outer_cone_angle.clamp(1e-3, half_pi)
                } else {
                    std::f32::consts::FRAC_PI_4
                };
                let inner = if inner_cone_angle.is_finite() {
                    inner_cone_angle.clamp(0.0, outer * 0.999)
                } else {
                    0.0
                };
                report.warnings.push(format!(
                    "light '{name}': spot cone angles must satisfy 0 <= inner < outer <= pi/2; using inner {inner:.4}, outer {outer:.4}"
                ));
                LightKind::Spot {
                    inner_cone: inner,
                    outer_cone: outer,
                }
            }
        }
    };
    Some(PunctualLight {
        kind,
        position,
        direction,
        color,
        intensity,
    })
}

fn camera_from_node(
    doc: &gltf::Document,
    node: &gltf::Node,
    world: &Mat4,
    report: &mut LoadReport,
) -> Option<Camera> {
    use gltf::json::camera::Type;
    use gltf::json::validation::Checked;
    let index = node.camera()?.index();
    let json = doc.as_json().cameras.get(index)?;
    let name = json
        .name
        .clone()
        .or_else(|| node.name().map(str::to_string))
        .unwrap_or_else(|| format!("camera {index}"));
    let yfov = match (&json.type_, &json.perspective) {
        (Checked::Valid(Type::Perspective), Some(p)) => p.yfov,
        (Checked::Valid(Type::Orthographic), _) => {
            report.warnings.push(format!(
                "camera '{name}' is orthographic, which is not supported; skipped"
            ));
            return None;
        }
        _ => {
            report
                .warnings
                .push(format!("camera '{name}' has no usable projection; skipped"));
            return None;
        }
    };
    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
        report
            .warnings
            .push(format!("camera '{name}': invalid yfov {yfov}; skipped"));
        return None;
    }
    // In f64: under a node scale of 1e-40 (or 1e30) the f32 decomposition is no longer finite.
    let (_, rotation, translation) = world.as_dmat4().to_scale_rotation_translation();
    let transform = Mat4::from_rotation_translation(
        rotation.normalize().as_quat().normalize(),
        translation.as_vec3(),
    );
    if !transform.is_finite() {
        report.warnings.push(format!(
            "camera '{name}': its node transform is degenerate; skipped"
        ));
        return None;
    }
    Some(Camera {
        name,
        transform,
        yfov,
    })
}

// ---------------------------------------------------------------------------------------------
// The whole load

fn load_bytes(
    bytes: &[u8],
    base: Option<&Path>,
    glb_name: bool,
    opts: &LoadOptions,
) -> Result<Scene, String> {
    let (json, blob) = if bytes.starts_with(b"glTF") {
        parse_glb(bytes)?
    } else if glb_name {
        let magic: String = bytes
            .iter()
            .take(4)
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
            .collect();
        return Err(format!(
            "not a binary glTF file: magic is \"{magic}\", expected \"glTF\""
        ));
    } else {
        (bytes, None)
    };
    let (doc, (ignored, allowed)) = parse_document(json, opts)?;
    let buffers = load_buffers(&doc, base, blob)?;

    let mut report = LoadReport {
        extensions_used: doc.extensions_used().map(str::to_string).collect(),
        ..LoadReport::default()
    };
    if !ignored.is_empty() {
        report.warnings.push(format!(
            "required extension{} {} ignored: {} only what fuzzy-vpl does not model (it renders the base colour as a diffuse surface)",
            if ignored.len() > 1 { "s" } else { "" },
            ignored.join(", "),
            if ignored.len() > 1 { "they change" } else { "it changes" },
        ));
    }
    if !allowed.is_empty() {
        report.warnings.push(format!(
            "required extension{} {} ignored as --allow-extension asks (fuzzy-vpl does not know {})",
            if allowed.len() > 1 { "s" } else { "" },
            allowed.join(", "),
            if allowed.len() > 1 { "them" } else { "it" },
        ));
    }
    let (mut table, textures) = load_materials(&doc, &buffers, base, &mut report)?;

    let mut primitives: HashMap<(usize, usize), Primitive> = HashMap::new();
    let mut triangles = Vec::new();
    let mut lights = Vec::new();
    let mut cameras = Vec::new();
    let mut warned_skin = false;
    let mut far_nodes: Vec<FarNode> = Vec::new();
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    for (i, world) in flatten_nodes(&doc)? {
        let node = &nodes[i];
        if let Some(w) = zero_rotation_warning(node) {
            report.warnings.push(w);
        }
        if let Some(mesh) = node.mesh() {
            if !warned_skin && (node.skin().is_some() || mesh.weights().is_some()) {
                warned_skin = true;
                report.warnings.push(
                    "skins and morph targets are ignored (meshes are used in their rest pose)"
                        .into(),
                );
            }
            for prim in mesh.primitives() {
                let decoded = match primitives.entry((mesh.index(), prim.index())) {
                    Entry::Occupied(e) => e.into_mut(),
                    Entry::Vacant(e) => e.insert(decode_primitive(
                        &prim,
                        &mesh,
                        &buffers,
                        &mut table,
                        &mut report,
                    )?),
                };
                emit(decoded, &world, i, &table.uv_transform, &mut triangles)?;
                if let Some(far) = too_far_for_f32(decoded, &world, i) {
                    far_nodes.push(far);
                }
            }
        }
        if let Some(light) = node.light()
            && let Some(l) = light_from_node(&light, &world, &mut report)
        {
            lights.push(l);
        }
        if let Some(c) = camera_from_node(&doc, node, &world, &mut report) {
            cameras.push(c);
        }
    }

    // Drop degenerate triangles (scale-free tolerance), then fill in missing normals.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in &triangles {
        for p in t.p {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let extent_sq = if triangles.is_empty() {
        0.0
    } else {
        (hi.as_dvec3() - lo.as_dvec3()).length_squared()
    };
    let before = triangles.len();
    triangles.retain(|t| !is_degenerate(t, extent_sq));
    report.dropped_degenerate = before - triangles.len();
    for t in &mut triangles {
        if t.n.contains(&Vec3::ZERO) {
            // In f64: at 1e-20 units the f32 cross product of the edges underflows to zero.
            let p = t.p.map(|v| v.as_dvec3());
            let face = (p[1] - p[0])
                .cross(p[2] - p[0])
                .normalize_or_zero()
                .as_vec3();
            for n in &mut t.n {
                if *n == Vec3::ZERO {
                    *n = face;
                }
            }
            report.generated_normals += 1;
        }
    }

    if triangles.is_empty()
        && let Some(f) = far_nodes.first()
    {
        return Err(format!(
            "the scene has no triangles to render: {} (and {} degenerate triangles dropped)",
            f.describe(),
            report.dropped_degenerate
        ));
    }
    if triangles.is_empty() {
        return Err(format!(
            "the scene has no triangles to render ({} non-triangle primitives skipped, {} degenerate triangles dropped)",
            report.skipped_primitives, report.dropped_degenerate
        ));
    }
    for f in &far_nodes {
        report.warnings.push(format!(
            "{}: its shape is quantised to that spacing",
            f.describe()
        ));
    }

    Ok(Scene {
        name: String::new(),
        path: None,
        triangles,
        materials: table.materials,
        textures,
        lights,
        cameras,
        report,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panics_become_one_line_errors() {
        let e = guarded("boom.glb", || panic!("kaboom\nsecond line")).unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("boom.glb: internal error"), "{msg}");
        assert!(msg.contains("kaboom second line"), "{msg}");
        assert!(!msg.contains('\n'));
        // The guard is released: ordinary panics still propagate to catch_unwind callers.
        assert!(std::panic::catch_unwind(|| panic!("outside")).is_err());
        assert!(!crate::panic_guard::is_quiet());
    }

    #[test]
    fn problems_are_flattened_to_one_line() {
        let e = guarded("x.gltf", || Err("a\n  b\r\nc".into())).unwrap_err();
        assert_eq!(e.to_string(), "x.gltf: a b c");
    }

    #[test]
    fn versions() {
        assert!(check_version("2.0").is_ok());
        assert!(check_version("2.1").is_ok());
        assert!(
            check_version("1.0")
                .unwrap_err()
                .contains("glTF 1.0 is not supported")
        );
        assert!(
            check_version("1")
                .unwrap_err()
                .contains("glTF 1.0 is not supported")
        );
        assert!(
            check_version("3.0")
                .unwrap_err()
                .contains("unsupported glTF version")
        );
    }
}
