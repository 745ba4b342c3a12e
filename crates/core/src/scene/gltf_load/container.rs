//! The container and the JSON: GLB chunks, the document's version, its required extensions and
//! its validation, and the buffers it names.

use super::{
    IGNORABLE_REQUIRED_EXTENSIONS, REFUSED_REQUIRED_EXTENSIONS, SUPPORTED_REQUIRED_EXTENSIONS,
    TEXTURE_FORMAT_EXTENSIONS, read, uri,
};
use crate::scene::LoadOptions;
use gltf::json::validation::Validate;
use std::borrow::Cow;

/// A GLB's JSON chunk and optional BIN chunk.
pub(super) type GlbChunks<'a> = (Cow<'a, [u8]>, Option<Cow<'a, [u8]>>);

/// Splits a GLB into its JSON chunk and optional BIN chunk with `gltf::binary::Glb::from_slice`,
/// after the header checks it lacks (it subtracts the header's 12 bytes from the declared length
/// unchecked, and reads past the declared length), its errors given as messages. Chunks after the
/// BIN chunk are ignored; a chunk of an unknown type right after the JSON chunk is refused.
pub(super) fn parse_glb(bytes: &[u8]) -> Result<GlbChunks<'_>, String> {
    if bytes.len() < 12 {
        return Err(format!(
            "truncated GLB: {} bytes, less than the 12-byte header",
            bytes.len()
        ));
    }
    let u32_at =
        |i: usize| u32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
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
    if declared < 20 {
        return Err(format!(
            "corrupt GLB: header declares {declared} bytes, too few for a JSON chunk"
        ));
    }
    let glb = gltf::binary::Glb::from_slice(&bytes[..declared]).map_err(|e| match e {
        gltf::Error::Binary(e) => glb_error(e),
        e => format!("corrupt GLB: {e}"),
    })?;
    Ok((glb.json, glb.bin))
}

/// A GLB container error as a message.
fn glb_error(e: gltf::binary::Error) -> String {
    use gltf::binary::{ChunkType, Error};
    let name = |ty: ChunkType| match ty {
        ChunkType::Json => "JSON",
        ChunkType::Bin => "BIN",
    };
    match e {
        Error::Io(_) => "corrupt GLB: truncated chunk header".into(),
        Error::Version(v) => format!("unsupported GLB container version {v}"),
        Error::Magic(_) => "not a binary glTF file: wrong magic".into(),
        Error::Length {
            length,
            length_read,
        } => format!(
            "truncated GLB: header declares {} bytes but the file has {}",
            length as usize + 12,
            length_read + 12
        ),
        Error::ChunkLength {
            ty,
            length,
            length_read,
        } => format!(
            "truncated GLB: the {} chunk declares {length} bytes but only {length_read} remain",
            name(ty)
        ),
        Error::ChunkType(ChunkType::Bin) => "corrupt GLB: the first chunk is not JSON".into(),
        Error::ChunkType(ty) => format!("corrupt GLB: unexpected {} chunk", name(ty)),
        Error::UnknownChunkType(ty) => format!(
            "corrupt GLB: a chunk of unknown type \"{}\" where a JSON or BIN chunk belongs",
            ty.map(|b| if b.is_ascii_graphic() { b as char } else { '?' })
                .iter()
                .collect::<String>()
        ),
    }
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

pub(super) fn check_version(version: &str) -> Result<(), String> {
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
pub(super) fn parse_document(
    json: &[u8],
    opts: &LoadOptions,
) -> Result<(gltf::Document, Ignored), String> {
    let json = json.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(json);
    check_index_range(json)?;
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

/// Fields that hold a byte count or offset, not an index: `gltf` reads them as u64, and the loader
/// checks them against the buffers.
const BYTE_FIELDS: &[&str] = &["byteLength", "byteOffset", "count"];

/// Refuses an integer of 2^32 or more where `gltf` reads an index (scene, node, mesh, accessor,
/// camera, texture, sampler, material, …): it would keep the low 32 bits, so `"scene": 4294967297`
/// would load scene 1. Every integer of the document is looked at but those under `extras`
/// (application data) and the byte counts (`BYTE_FIELDS`); only a document with a run of ten digits
/// (2^32 has ten) is walked at all.
fn check_index_range(json: &[u8]) -> Result<(), String> {
    let mut run = 0;
    if !json.iter().any(|b| {
        run = if b.is_ascii_digit() { run + 1 } else { 0 };
        run >= 10
    }) {
        return Ok(());
    }
    let mut path = Vec::new();
    let mut found = None;
    let mut de = serde_json::Deserializer::from_slice(json);
    // A malformed document is the parser's to report, after this.
    let _ = serde::de::DeserializeSeed::deserialize(
        IndexScan {
            path: &mut path,
            found: &mut found,
        },
        &mut de,
    );
    match found {
        Some((at, v)) => Err(format!(
            "invalid glTF: {at}: {v} is out of range (an index must be below 2^32 = 4294967296)"
        )),
        None => Ok(()),
    }
}

/// A walk of a JSON value that notes the first too-large integer (`check_index_range`) with its
/// path (`nodes[3].mesh`).
struct IndexScan<'a> {
    path: &'a mut Vec<String>,
    found: &'a mut Option<(String, u64)>,
}

impl<'de> serde::de::DeserializeSeed<'de> for IndexScan<'_> {
    type Value = ();
    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for IndexScan<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_u64<E>(self, v: u64) -> Result<(), E> {
        let field = self.path.last().map_or("", String::as_str);
        if v > u32::MAX as u64 && self.found.is_none() && !BYTE_FIELDS.contains(&field) {
            let at = self.path.iter().fold(String::new(), |mut s, p| {
                if !p.starts_with('[') && !s.is_empty() {
                    s.push('.');
                }
                s.push_str(p);
                s
            });
            *self.found = Some((at, v));
        }
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        let mut i = 0usize;
        loop {
            self.path.push(format!("[{i}]"));
            let more = seq.next_element_seed(IndexScan {
                path: self.path,
                found: self.found,
            })?;
            self.path.pop();
            if more.is_none() {
                return Ok(());
            }
            i += 1;
        }
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        while let Some(key) = map.next_key::<std::borrow::Cow<str>>()? {
            if key == "extras" {
                map.next_value::<serde::de::IgnoredAny>()?;
                continue;
            }
            self.path.push(key.into_owned());
            map.next_value_seed(IndexScan {
                path: self.path,
                found: self.found,
            })?;
            self.path.pop();
        }
        Ok(())
    }
}

/// Loads every buffer: the GLB BIN chunk, `data:` URIs or files next to the glTF.
pub(super) fn load_buffers(
    doc: &gltf::Document,
    base: Option<&uri::Folder>,
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
