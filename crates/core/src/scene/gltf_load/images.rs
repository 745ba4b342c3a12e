//! Decoding glTF images into RGBA8 `Texture`s.

use super::uri::{self, Resolved};
use crate::scene::Texture;

/// Largest texture side kept; bigger images are downscaled (aspect ratio preserved).
pub const MAX_TEXTURE_SIDE: u32 = 2048;

/// The encoded bytes of glTF image `image`, from a bufferView or a URI.
pub(super) fn encoded_bytes(
    image: &gltf::Image,
    buffers: &[Vec<u8>],
    base: Option<&uri::Folder>,
) -> Result<Vec<u8>, String> {
    match image.source() {
        gltf::image::Source::View { view, .. } => {
            let data = buffers
                .get(view.buffer().index())
                .ok_or("its buffer was not loaded")?;
            let start = view.offset();
            let end = start.saturating_add(view.length());
            data.get(start..end).map(<[u8]>::to_vec).ok_or_else(|| {
                format!(
                    "bufferView {} lies outside buffer {}",
                    view.index(),
                    view.buffer().index()
                )
            })
        }
        gltf::image::Source::Uri { uri, .. } => match uri::resolve(uri, base)? {
            Resolved::Data(bytes) => Ok(bytes),
            Resolved::File(path) => super::read::read_image_file(&path)
                .map_err(|e| format!("cannot read '{}': {e}", uri::short(uri))),
        },
    }
}

/// Why an external image file is refused outright (it is larger than any texture fuzzy-vpl reads:
/// a 1 TB sparse file, say), or `None`. Unlike an image that does not decode, which costs only its
/// texture, such a file is an error in the scene, found from its size without reading it.
pub(super) fn refused_file(image: &gltf::Image, base: Option<&uri::Folder>) -> Option<String> {
    let gltf::image::Source::Uri { uri, .. } = image.source() else {
        return None;
    };
    if uri.starts_with("data:") {
        return None;
    }
    let Ok(Resolved::File(path)) = uri::resolve(uri, base) else {
        return None;
    };
    let size = std::fs::metadata(&path).ok()?.len();
    (size > super::read::MAX_IMAGE_BYTES).then(|| {
        format!(
            "texture image '{}' is {}, more than the {} a texture image may have",
            uri::short(uri),
            super::read::human_bytes(size),
            super::read::human_bytes(super::read::MAX_IMAGE_BYTES)
        )
    })
}

/// A short name for an image: its name, else its URI's file name, else `image N`.
pub(super) fn image_name(image: &gltf::Image) -> String {
    if let Some(n) = image.name().filter(|n| !n.is_empty()) {
        return n.to_string();
    }
    match image.source() {
        gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
            uri::short(uri.rsplit('/').next().unwrap_or(uri))
        }
        _ => format!("image {}", image.index()),
    }
}

/// Decodes encoded image bytes (format sniffed from the content) into an RGBA8 texture no larger
/// than `MAX_TEXTURE_SIDE` on either side.
pub(super) fn decode(bytes: &[u8], name: &str) -> Result<Texture, String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    if reader.format().is_none() {
        return Err("unrecognised image format".into());
    }
    let img = reader.decode().map_err(|e| e.to_string())?;
    let mut rgba = img.to_rgba8();
    let (w, h) = rgba.dimensions();
    if w == 0 || h == 0 {
        return Err("image has zero size".into());
    }
    if w.max(h) > MAX_TEXTURE_SIDE {
        let (nw, nh) = fit(w, h, MAX_TEXTURE_SIDE);
        rgba = image::imageops::resize(&rgba, nw, nh, image::imageops::FilterType::Triangle);
    }
    let (width, height) = rgba.dimensions();
    let rgba8 = rgba
        .into_raw()
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    Ok(Texture {
        name: name.to_string(),
        width,
        height,
        rgba8,
    })
}

/// Size of a `w`×`h` image scaled so its longer side is `max` (each side at least 1).
fn fit(w: u32, h: u32, max: u32) -> (u32, u32) {
    let s = max as f64 / w.max(h) as f64;
    let scale = |v: u32| ((v as f64 * s).round() as u32).clamp(1, max);
    (scale(w), scale(h))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_keeps_aspect() {
        assert_eq!(fit(4096, 4096, 2048), (2048, 2048));
        assert_eq!(fit(4096, 1024, 2048), (2048, 512));
        assert_eq!(fit(1000, 5000, 2048), (410, 2048));
        assert_eq!(fit(100_000, 1, 2048), (2048, 1));
    }

    #[test]
    fn decodes_png_and_downscales() {
        let img = image::RgbaImage::from_pixel(4100, 10, image::Rgba([10, 20, 30, 255]));
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let t = decode(&png, "x").unwrap();
        assert_eq!((t.width, t.height), (2048, 5));
        assert_eq!(t.rgba8.len(), 2048 * 5);
        assert_eq!(t.rgba8[7], [10, 20, 30, 255]);
        assert!(decode(b"DDS garbage", "y").is_err());
    }

    /// An image whose longer side is the cap keeps its size and its pixels. The cap's `>` as `>=`
    /// passes it too: `image`'s resize to the same size returns the image unchanged (equivalent).
    #[test]
    fn an_image_at_the_side_cap_is_kept_as_it_is() {
        let img = image::RgbaImage::from_fn(MAX_TEXTURE_SIDE, 2, |x, y| {
            image::Rgba([(x % 256) as u8, (x * 7 % 256) as u8, (y * 255) as u8, 255])
        });
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let t = decode(&png, "x").unwrap();
        assert_eq!((t.width, t.height), (MAX_TEXTURE_SIDE, 2));
        let want: Vec<[u8; 4]> = img.pixels().map(|p| p.0).collect();
        assert!(t.rgba8 == want);
    }
}
