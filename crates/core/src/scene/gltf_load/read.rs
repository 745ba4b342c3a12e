//! Reading the files a scene is made of (the glTF/GLB itself, external buffers, external images)
//! without trusting their size: only regular files are read, never more than a fixed cap, a GLB only
//! as far as its header declares, a buffer only its declared `byteLength`, an image only after its
//! first bytes name a known image format. Memory is reserved fallibly, so an oversized request is an
//! error message, not an abort.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use crate::files::open_regular;

/// The most bytes read from one scene file or one buffer: 4 GiB, the most a GLB can declare (its
/// length field is a u32).
pub const MAX_FILE_BYTES: u64 = u32::MAX as u64;
/// The most bytes read from one encoded image file (the `image` crate's default decoding
/// allocation limit is the same 512 MiB; textures are downscaled to `MAX_TEXTURE_SIDE` anyway).
pub const MAX_IMAGE_BYTES: u64 = 512 << 20;

/// Bytes in a human unit for messages ("1.0 TiB").
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} bytes")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

/// Appends at most `n` more bytes of `f` to `out` (memory reserved fallibly first).
fn read_up_to(f: &mut File, n: u64, out: &mut Vec<u8>) -> Result<(), String> {
    out.try_reserve_exact(n as usize)
        .map_err(|_| format!("cannot allocate {} to read it", human_bytes(n)))?;
    f.take(n).read_to_end(out).map_err(|e| e.to_string())?;
    Ok(())
}

/// Refuses a file over `cap` bytes, naming `what` it was read as.
fn check_size(size: u64, cap: u64, what: &str) -> Result<(), String> {
    if size > cap {
        return Err(format!(
            "{} ({size} bytes) is larger than the {} a {what} may have",
            human_bytes(size),
            human_bytes(cap)
        ));
    }
    Ok(())
}

/// What a file's first bytes say it is when they are not glTF: "a PNG image" and the like.
pub fn sniff_foreign(head: &[u8]) -> Option<String> {
    let body = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    if body.is_empty() || body[0] == b'{' || body[0].is_ascii_whitespace() {
        return None;
    }
    if let Ok(f) = image::guess_format(head) {
        let name = format!("{f:?}").to_ascii_uppercase();
        return Some(format!("a {name} image"));
    }
    let known: &[(&[u8], &str)] = &[
        (b"PK\x03\x04", "a ZIP archive"),
        (b"\x1F\x8B", "a gzip archive"),
        (b"%PDF", "a PDF document"),
        (b"\x7FELF", "an executable (ELF)"),
        (b"Kaydara FBX Binary", "an FBX file"),
    ];
    for (magic, name) in known {
        if body.starts_with(magic) {
            return Some((*name).to_string());
        }
    }
    if body.iter().all(|&b| b == 0) {
        return Some("all zero bytes at its start".to_string());
    }
    None
}

/// Reads a `.gltf`/`.glb` scene file: a GLB up to the length its header declares, JSON whole; a file
/// whose first bytes name another format is refused before the rest is read.
pub fn read_scene_file(path: &Path) -> Result<Vec<u8>, String> {
    let (mut f, size) = open_regular(path)?;
    check_size(size, MAX_FILE_BYTES, "scene file")?;
    let mut head = Vec::new();
    read_up_to(&mut f, 16, &mut head)?;
    if head.starts_with(b"glTF") && head.len() >= 12 {
        // Read as far as declared (at most the file); the GLB parser reports a wrong version or a
        // truncated file from what it gets.
        let declared = u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as u64;
        let want = declared.clamp(12, size.max(12));
        read_up_to(&mut f, want.saturating_sub(head.len() as u64), &mut head)?;
        head.truncate(want as usize);
        return Ok(head);
    }
    if let Some(what) = sniff_foreign(&head) {
        return Err(format!("not a glTF or GLB file: it is {what}"));
    }
    read_up_to(&mut f, size.saturating_sub(head.len() as u64), &mut head)?;
    Ok(head)
}

/// Reads the first `len` bytes of an external buffer file (its declared `byteLength`): a longer
/// file is not read past them, a shorter one is refused.
pub fn read_buffer_file(path: &Path, len: u64) -> Result<Vec<u8>, String> {
    let (mut f, size) = open_regular(path)?;
    check_size(len, MAX_FILE_BYTES, "buffer")?;
    if size < len {
        return Err(format!(
            "has {size} bytes but the buffer declares byteLength {len} (buffer too short)"
        ));
    }
    let mut out = Vec::new();
    read_up_to(&mut f, len, &mut out)?;
    if (out.len() as u64) < len {
        return Err(format!(
            "has {} bytes but the buffer declares byteLength {len} (buffer too short)",
            out.len()
        ));
    }
    Ok(out)
}

/// Reads an external image file: its first bytes must name a known image format (checked before the
/// rest is read), and it may hold at most `MAX_IMAGE_BYTES`.
pub fn read_image_file(path: &Path) -> Result<Vec<u8>, String> {
    let (mut f, size) = open_regular(path)?;
    check_size(size, MAX_IMAGE_BYTES, "texture image")?;
    let mut out = Vec::new();
    read_up_to(&mut f, 64, &mut out)?;
    if image::guess_format(&out).is_err() {
        return Err("unrecognised image format".into());
    }
    read_up_to(&mut f, size.saturating_sub(out.len() as u64), &mut out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sniffs_foreign_formats_but_not_json() {
        assert_eq!(sniff_foreign(b"{\"asset\":"), None);
        assert_eq!(sniff_foreign(b"  \n{"), None);
        assert_eq!(sniff_foreign(b""), None);
        assert_eq!(
            sniff_foreign(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR").as_deref(),
            Some("a PNG image")
        );
        assert_eq!(
            sniff_foreign(b"\xFF\xD8\xFF\xE0\0\x10JFIF\0").as_deref(),
            Some("a JPEG image")
        );
        assert_eq!(
            sniff_foreign(b"PK\x03\x04rest").as_deref(),
            Some("a ZIP archive")
        );
        assert_eq!(
            sniff_foreign(&[0u8; 16]).as_deref(),
            Some("all zero bytes at its start")
        );
    }

    #[test]
    fn human_bytes_units() {
        assert_eq!(human_bytes(1728), "1.7 KiB");
        assert_eq!(human_bytes(1 << 40), "1.0 TiB");
        assert_eq!(human_bytes(12), "12 bytes");
        // TiB is the last unit: a PiB and more stay in it (cargo-mutants: the bound `u + 1 <` as
        // `<=` or `u * 1 <` survived; they index past the units).
        assert_eq!(human_bytes(1 << 50), "1024.0 TiB");
        assert_eq!(human_bytes(u64::MAX), "16777216.0 TiB");
    }
}
