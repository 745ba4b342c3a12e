//! Screenshots, the `Viewer`'s file output: the current view's linear radiance as EXR, and what the
//! window shows (UI included) as PNG, read back from an offscreen copy of the window's last egui
//! render. File names carry the scene and the settings and never overwrite an existing file (a
//! counter is added).

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::Viewer;
use super::views::{self, View};

/// `DIR/STEM_SETTINGS_NNN.EXT`, the first NNN (from 1) that names no existing file.
pub fn unique_path(dir: &Path, scene: &str, settings: &str, ext: &str) -> PathBuf {
    let stem = sanitize(scene);
    let settings = sanitize(settings);
    (1..)
        .map(|i| dir.join(format!("{stem}_{settings}_{i:03}.{ext}")))
        .find(|p| !p.exists())
        .expect("an unused counter")
}

/// A scene spec reduced to a short file-name part: `builtin:cornell` → `cornell`, `a/b/room.glb` →
/// `room`.
pub fn scene_stem(spec: &str) -> String {
    if let Some(n) = spec.strip_prefix("builtin:") {
        return n.to_string();
    }
    Path::new(spec)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into())
}

fn sanitize(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-.=".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// `img` (`w` × `h`, row-major) resampled to `to_w` × `to_h` bilinearly between pixel centres
/// (edges clamped), as a texture is magnified.
pub fn resample_bilinear(img: &[[f32; 3]], w: u32, h: u32, to_w: u32, to_h: u32) -> Vec<[f32; 3]> {
    let (w, h) = (w.max(1) as usize, h.max(1) as usize);
    let at = |x: usize, y: usize| img[y.min(h - 1) * w + x.min(w - 1)];
    let mut out = Vec::with_capacity(to_w as usize * to_h as usize);
    for ty in 0..to_h {
        let fy = ((ty as f32 + 0.5) * h as f32 / to_h as f32 - 0.5).max(0.0);
        let (y0, wy) = (fy.floor() as usize, fy.fract());
        for tx in 0..to_w {
            let fx = ((tx as f32 + 0.5) * w as f32 / to_w as f32 - 0.5).max(0.0);
            let (x0, wx) = (fx.floor() as usize, fx.fract());
            let (a, b, c, d) = (
                at(x0, y0),
                at(x0 + 1, y0),
                at(x0, y0 + 1),
                at(x0 + 1, y0 + 1),
            );
            out.push([0, 1, 2].map(|k| {
                let top = a[k] + (b[k] - a[k]) * wx;
                let bottom = c[k] + (d[k] - c[k]) * wx;
                top + (bottom - top) * wy
            }));
        }
    }
    out
}

/// Reads an RGBA8 / BGRA8 texture (COPY_SRC) back as RGB8.
pub fn read_texture_rgb8(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<(u32, u32, Vec<u8>)> {
    let (w, h) = (texture.width(), texture.height());
    let bgra = matches!(
        texture.format(),
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let texels = crate::gpu::read_texture(device, queue, texture)?;
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for p in texels.chunks(4) {
        if bgra {
            rgb.extend_from_slice(&[p[2], p[1], p[0]]);
        } else {
            rgb.extend_from_slice(&p[..3]);
        }
    }
    Ok((w, h, rgb))
}

/// The viewer's file output: the current view as EXR (panel, F11; `--screenshot S.exr`) and the
/// window as PNG (F12; `--screenshot S.png`, written by `window.rs`).
impl Viewer {
    /// The current view's linear radiance (as displayed: direct toggle applied) at the frame's size,
    /// or why there is none.
    fn view_radiance(&self) -> std::result::Result<(u32, u32, Vec<[f32; 3]>), String> {
        let Some(r) = &self.latest else {
            return Err("no frame yet".into());
        };
        let frame = self.cpu_frame(r);
        let img = match self.view {
            View::Direct => frame.direct.clone(),
            View::Indirect => frame.indirect.clone(),
            // Without a reference these views show the clustered frame: saving that under a
            // `_reference_` / `_error_` name would mislabel it.
            View::Reference | View::Error | View::Flip if self.reference_for(r).is_none() => {
                return Err(
                    "no reference for this view yet: nothing saved (press \"compute reference\")"
                        .into(),
                );
            }
            View::Reference => self.reference_for(r).expect("checked").to_vec(),
            _ => views::final_image(&frame.direct, &frame.indirect, self.s.direct_on),
        };
        Ok((r.frame.width, r.frame.height, img))
    }

    /// Writes the current view's linear radiance (as displayed: direct toggle applied) as EXR.
    pub fn save_exr(&mut self) {
        let (w, h, img) = match self.view_radiance() {
            Ok(v) => v,
            Err(e) => {
                self.last_shot = e;
                return;
            }
        };
        let path = unique_path(
            &self.shot_dir,
            &scene_stem(&self.spec),
            &format!("{}_{}", self.s.short(), self.view.slug()),
            "exr",
        );
        self.last_shot = match crate::export::write_exr(&path, w, h, &img) {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => format!("{e:#}"),
        };
    }

    /// `view --screenshot S.exr`: the image as displayed, linear radiance at the image area's
    /// resolution (the frame resampled bilinearly, as the display magnifies it), no UI.
    pub(super) fn write_displayed_exr(&self, path: &std::path::Path) -> Result<()> {
        let (w, h, img) = self.view_radiance().map_err(anyhow::Error::msg)?;
        let [aw, ah] = self.area_px;
        let (aw, ah) = (aw.max(1), ah.max(1));
        let out = resample_bilinear(&img, w, h, aw, ah);
        crate::export::write_exr(path, aw, ah, &out)
    }

    pub fn request_png(&mut self) {
        self.png_request = Some(unique_path(
            &self.shot_dir,
            &scene_stem(&self.spec),
            &format!("{}_{}", self.s.short(), self.view.slug()),
            "png",
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Same size: the image itself. Doubled: pixel centres of the small image at 0.5, 1.5 fall
    /// between the large one's, so a 2 × 1 ramp 0, 1 becomes 0, 0.25, 0.75, 1 (edges clamped).
    #[test]
    fn bilinear_resampling_by_hand() {
        let img = [[0.0; 3], [1.0; 3]];
        assert_eq!(resample_bilinear(&img, 2, 1, 2, 1), img.to_vec());
        let big = resample_bilinear(&img, 2, 1, 4, 2);
        let row: Vec<f32> = big[..4].iter().map(|p| p[0]).collect();
        assert_eq!(row, [0.0, 0.25, 0.75, 1.0]);
        assert_eq!(big[4..].to_vec(), big[..4].to_vec());
    }

    #[test]
    fn names_never_overwrite() {
        let dir = std::env::temp_dir().join(format!("fuzzy-vpl-shots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let a = unique_path(
            &dir,
            &scene_stem("builtin:cornell"),
            "weighted K=3072",
            "png",
        );
        assert_eq!(
            a.file_name().unwrap().to_str().unwrap(),
            "cornell_weighted_K=3072_001.png"
        );
        std::fs::write(&a, b"x").unwrap();
        let b = unique_path(&dir, "cornell", "weighted K=3072", "png");
        assert_ne!(a, b);
        assert_eq!(scene_stem("/x/y/room.glb"), "room");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
