//! Image output: EXR (linear HDR radiance) and PNG (exposure, clamp, sRGB). Files are written to a
//! temporary file in the same directory and renamed, so a reader never sees a half-written file.

use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result, bail};
use image::{ImageBuffer, ImageFormat, Rgb};

/// The folder `path` is written in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Checks, before any work, that `path` can be written the way `write_atomic` writes it: its folder
/// exists and takes a new file, and the path is not a folder. The error names `path` and the reason.
pub fn check_writable(path: &Path) -> std::result::Result<(), String> {
    let dir = folder_of(path);
    if path.is_dir() {
        return Err(format!(
            "{}: cannot write: it is a directory",
            path.display()
        ));
    }
    if !dir.is_dir() {
        return Err(format!(
            "{}: cannot write: no directory {}",
            path.display(),
            dir.display()
        ));
    }
    // A fresh name (process, clock, attempt): a probe left by a killed run, or another run's, only
    // means another name.
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos());
    let mut last = None;
    for attempt in 0..8 {
        let probe = dir.join(format!(
            ".fuzzy-vpl-probe-{}-{nanos}-{attempt}",
            std::process::id()
        ));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&probe)
        {
            Ok(_) => {
                let _ = std::fs::remove_file(&probe);
                return Ok(());
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(format!("{}: cannot write: {e}", path.display())),
        }
    }
    Err(format!(
        "{}: cannot write: {}",
        path.display(),
        last.map_or_else(String::new, |e| e.to_string())
    ))
}

/// Writes `value` as pretty JSON to `path` atomically.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let json = serde_json::to_string_pretty(value)?;
    write_atomic(path, |w| {
        w.write_all(json.as_bytes())?;
        Ok(())
    })
}

/// Writes `bytes_fn`'s output to `path` atomically (temp file + rename).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<std::fs::File>) -> Result<()>,
) -> Result<()> {
    let dir = folder_of(path);
    let name = path
        .file_name()
        .with_context(|| format!("{}: not a file name", path.display()))?
        .to_string_lossy();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| -> Result<()> {
        let f = std::fs::File::create(&tmp).with_context(|| {
            format!(
                "{}: cannot write (temporary file {})",
                path.display(),
                tmp.display()
            )
        })?;
        let mut w = BufWriter::new(f);
        write(&mut w)?;
        w.flush()?;
        w.get_ref().sync_all()?;
        Ok(())
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    if let Err(e) = std::fs::rename(&tmp, path) {
        let _ = std::fs::remove_file(&tmp);
        return Err(anyhow::anyhow!("{}: cannot write: {e}", path.display()));
    }
    Ok(())
}

/// Linear → sRGB transfer for one channel in [0, 1].
pub fn linear_to_srgb(c: f32) -> f32 {
    let c = if c.is_finite() {
        c.clamp(0.0, 1.0)
    } else {
        0.0
    };
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// 8-bit sRGB display of linear radiance × exposure (clamped; the product in f64, so a bright pixel
/// times a large exposure is white, not an overflow to black).
pub fn to_srgb8(radiance: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    radiance
        .iter()
        .flat_map(|p| {
            p.map(|c| {
                let v = (c as f64 * exposure as f64).min(1.0) as f32;
                (linear_to_srgb(if c.is_nan() { 0.0 } else { v }) * 255.0 + 0.5) as u8
            })
        })
        .collect()
}

pub fn write_exr(path: &Path, width: u32, height: u32, radiance: &[[f32; 3]]) -> Result<()> {
    let data: Vec<f32> = radiance.iter().flatten().copied().collect();
    let img: ImageBuffer<Rgb<f32>, Vec<f32>> = ImageBuffer::from_raw(width, height, data)
        .context("image size does not match its pixels")?;
    write_atomic(path, |w| {
        img.write_to(w, ImageFormat::OpenExr)
            .with_context(|| format!("{}: EXR encoding failed", path.display()))
    })
}

pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: Vec<u8>) -> Result<()> {
    let img: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_raw(width, height, rgb)
        .context("image size does not match its pixels")?;
    write_atomic(path, |w| {
        img.write_to(w, ImageFormat::Png)
            .with_context(|| format!("{}: PNG encoding failed", path.display()))
    })
}

/// Writes radiance as EXR or tone-mapped PNG, by the file's extension.
pub fn write_image(
    path: &Path,
    width: u32,
    height: u32,
    radiance: &[[f32; 3]],
    exposure: f32,
) -> Result<()> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("exr") => write_exr(path, width, height, radiance),
        Some("png") => write_png_rgb8(path, width, height, to_srgb8(radiance, exposure)),
        _ => bail!("{}: output must end in .exr or .png", path.display()),
    }
}

/// Reads an EXR as linear RGB.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let img = image::ImageReader::open(path)
        .with_context(|| format!("{}: cannot open", path.display()))?
        .with_guessed_format()?
        .decode()
        .with_context(|| format!("{}: not a readable image", path.display()))?
        .into_rgb32f();
    let (w, h) = img.dimensions();
    let px = img.pixels().map(|p| p.0).collect();
    Ok((w, h, px))
}
