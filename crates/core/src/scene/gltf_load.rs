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
mod container;
mod geometry;
mod images;
mod materials;
mod nodes;
pub mod read;
mod uri;

use super::{Camera, LoadOptions, LoadReport, PunctualLight, Scene, SceneError, Triangle};
use crate::panic_guard::one_line;
use geometry::{FarNode, Primitive};
use glam::Vec3;
use materials::MaterialTable;
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
// The whole load

fn load_bytes(
    bytes: &[u8],
    base: Option<&Path>,
    glb_name: bool,
    opts: &LoadOptions,
) -> Result<Scene, String> {
    let (json, blob) = split_container(bytes, glb_name)?;
    let (doc, (ignored, allowed)) = container::parse_document(&json, opts)?;
    let folder = base.map(|dir| uri::Folder::new(dir, opts.allow_outside_uris));
    let base = folder.as_ref();
    let files = match base {
        Some(f) => uri::external_files(&doc, f)?,
        None => Vec::new(),
    };
    let buffers = container::load_buffers(&doc, base, blob.as_deref())?;

    let mut report = LoadReport {
        extensions_used: doc.extensions_used().map(str::to_string).collect(),
        files,
        ..LoadReport::default()
    };
    warn_ignored_extensions(&ignored, &allowed, &mut report);
    let (mut table, textures) = materials::load_materials(&doc, &buffers, base, &mut report)?;
    let Instances {
        mut triangles,
        lights,
        cameras,
        far_nodes,
    } = instance_nodes(&doc, &buffers, &mut table, &mut report)?;
    drop_degenerate(&mut triangles, &mut report);
    fill_normals(&mut triangles, &mut report);
    check_renderable(&triangles, &far_nodes, &mut report)?;

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

/// The JSON and the optional BIN chunk: a GLB's (by its magic), else the whole file as JSON, unless
/// the file is named `.glb` (`glb_name`): then a wrong magic is an error.
fn split_container(bytes: &[u8], glb_name: bool) -> Result<container::GlbChunks<'_>, String> {
    if bytes.starts_with(b"glTF") {
        container::parse_glb(bytes)
    } else if glb_name {
        let magic: String = bytes
            .iter()
            .take(4)
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
            .collect();
        Err(format!(
            "not a binary glTF file: magic is \"{magic}\", expected \"glTF\""
        ))
    } else {
        Ok((std::borrow::Cow::Borrowed(bytes), None))
    }
}

/// Warnings for the required extensions the load ignores: `ignored`, those that change only what a
/// diffuse renderer does not model, and `allowed`, those `--allow-extension` lets through.
fn warn_ignored_extensions(ignored: &[String], allowed: &[String], report: &mut LoadReport) {
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
}

/// What the default scene's nodes place in the world.
struct Instances {
    triangles: Vec<Triangle>,
    lights: Vec<PunctualLight>,
    cameras: Vec<Camera>,
    /// Mesh instances too far from the origin for f32 to resolve their shape.
    far_nodes: Vec<FarNode>,
}

/// Walks the default scene's nodes in world space: each mesh primitive decoded once and emitted
/// per instance, the lights and the cameras.
fn instance_nodes(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    table: &mut MaterialTable,
    report: &mut LoadReport,
) -> Result<Instances, String> {
    let mut primitives: HashMap<(usize, usize), Primitive> = HashMap::new();
    let mut triangles = Vec::new();
    let mut lights = Vec::new();
    let mut cameras = Vec::new();
    let mut warned_skin = false;
    let mut far_nodes: Vec<FarNode> = Vec::new();
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    for (i, world) in nodes::flatten_nodes(doc)? {
        let node = &nodes[i];
        if let Some(w) = nodes::zero_rotation_warning(node) {
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
                    Entry::Vacant(e) => e.insert(geometry::decode_primitive(
                        &prim, &mesh, buffers, table, report,
                    )?),
                };
                geometry::emit(decoded, &world, i, &table.uv_transform, &mut triangles)?;
                if let Some(far) = geometry::too_far_for_f32(decoded, &world, i) {
                    far_nodes.push(far);
                }
            }
        }
        if let Some(light) = node.light()
            && let Some(l) = nodes::light_from_node(&light, &world, report)
        {
            lights.push(l);
        }
        if let Some(c) = nodes::camera_from_node(doc, node, &world, report) {
            cameras.push(c);
        }
    }
    Ok(Instances {
        triangles,
        lights,
        cameras,
        far_nodes,
    })
}

/// Drops degenerate triangles (scale-free tolerance: relative to the scene's extent).
fn drop_degenerate(triangles: &mut Vec<Triangle>, report: &mut LoadReport) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in triangles.iter() {
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
    triangles.retain(|t| !geometry::is_degenerate(t, extent_sq));
    report.dropped_degenerate = before - triangles.len();
}

/// Fills in missing (zero) vertex normals with the face normal.
fn fill_normals(triangles: &mut [Triangle], report: &mut LoadReport) {
    for t in triangles {
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
}

/// An error when no triangle is left to render; else a warning per instance too far for f32.
fn check_renderable(
    triangles: &[Triangle],
    far_nodes: &[FarNode],
    report: &mut LoadReport,
) -> Result<(), String> {
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
    for f in far_nodes {
        report.warnings.push(format!(
            "{}: its shape is quantised to that spacing",
            f.describe()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::container::check_version;
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
