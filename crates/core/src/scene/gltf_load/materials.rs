//! Materials and their textures (`KHR_texture_transform`, emissive strength, alpha modes).

use super::{images, uri};
use crate::scene::{LoadReport, Material, Texture};
use glam::{Affine2, Vec3, Vec4};
use std::collections::HashMap;

/// Materials plus what triangle emission needs to know about them.
pub(super) struct MaterialTable {
    pub(super) materials: Vec<Material>,
    /// Per material: the `KHR_texture_transform` applied to its TEXCOORD_0.
    pub(super) uv_transform: Vec<Option<Affine2>>,
    /// Index of the glTF default material once a primitive needed it.
    default: Option<u32>,
}

impl MaterialTable {
    pub(super) fn index_for(&mut self, gltf_material: Option<usize>) -> u32 {
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

pub(super) fn finite_or(v: Vec4, fallback: Vec4) -> Vec4 {
    if v.is_finite() { v } else { fallback }
}

/// Texture decoding state: each glTF image is decoded at most once.
struct TextureCache<'a> {
    buffers: &'a [Vec<u8>],
    base: Option<&'a uri::Folder<'a>>,
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
pub(super) fn load_materials(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    base: Option<&uri::Folder>,
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
