//! Image output: EXR (linear HDR radiance) and PNG (exposure, clamp, sRGB). Files are written to a
//! temporary file in the same directory and renamed, so a reader never sees a half-written file.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

use anyhow::{Context, Result, bail};
use image::{ImageBuffer, ImageFormat, Rgb};

/// The folder `path` is written in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Checks, before any work, that `path` can be written the way `write_atomic` writes it: the path
/// is not an existing folder, FIFO, device, socket or symbolic link (only a regular file is
/// replaced), its name is one the file system takes, and its folder exists and takes a new file.
/// The error names `path` and the reason.
///
/// A symbolic link is refused rather than written through: the rename that makes a write atomic
/// would replace the link itself, and following it would let a link planted where an output is
/// expected (a shared folder such as /tmp) redirect the write onto any file the user may write.
/// Naming the link's target writes it.
pub fn check_writable(path: &Path) -> std::result::Result<(), String> {
    refuse_non_regular(path)?;
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(format!(
            "{}: cannot write: no directory {}",
            path.display(),
            dir.display()
        ));
    }
    // A fresh name: a probe left by a killed run, or another run's, only means another name.
    let mut last = None;
    for _ in 0..8 {
        let probe = temp_name(dir, "probe");
        let _pending = on_signal::remove_on_signal(&probe);
        match create_new(&probe) {
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

/// Refuses a `path` that exists and is not a regular file (or cannot be looked at: a name too
/// long, a folder in the way), naming it and what it is.
fn refuse_non_regular(path: &Path) -> std::result::Result<(), String> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(m) if m.file_type().is_symlink() => Err(format!(
            "{}: cannot write: it is a symbolic link (to {}); fuzzy-vpl does not write through links, name the target itself",
            path.display(),
            std::fs::read_link(path).map_or_else(|_| "?".into(), |t| t.display().to_string())
        )),
        Ok(m) => Err(format!(
            "{}: cannot write: it is {}, and only a regular file is replaced",
            path.display(),
            crate::files::kind(m.file_type())
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(format!("{}: cannot write: {e}", path.display())),
    }
}

/// A temporary file's name in `dir`: short (at most 40 bytes, so any output name the file system
/// takes has one), unique to this process and call.
fn temp_name(dir: &Path, what: &str) -> PathBuf {
    static COUNT: AtomicU32 = AtomicU32::new(0);
    let n = COUNT.fetch_add(1, Ordering::Relaxed);
    dir.join(format!(".fvpl-{what}-{}-{n}", std::process::id()))
}

/// Creates `path`, which must not exist yet, for writing.
fn create_new(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
}

/// Writes `value` as pretty JSON to `path` atomically.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<()> {
    let json = serde_json::to_string_pretty(value)?;
    write_atomic(path, |w| {
        w.write_all(json.as_bytes())?;
        Ok(())
    })
}

/// A writer that keeps the first I/O error its file gave, so that an encoder's error ("EXR encoding
/// failed") is reported as the OS's reason ("No space left on device").
pub struct Recording<W> {
    inner: W,
    error: Option<String>,
}

impl<W: Write> Write for Recording<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.write(buf).inspect_err(|e| {
            self.error.get_or_insert_with(|| e.to_string());
        })
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush().inspect_err(|e| {
            self.error.get_or_insert_with(|| e.to_string());
        })
    }
}

impl<W: std::io::Seek> std::io::Seek for Recording<W> {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.inner.seek(pos)
    }
}

/// Writes `write`'s output to `path` atomically (a temporary file beside it, then a rename). Every
/// error is one line naming `path` and the reason (exit code 2: the disk, the folder or the name
/// the user gave).
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<Recording<std::fs::File>>) -> Result<()>,
) -> Result<()> {
    atomically(path, |_, file| {
        let mut w = BufWriter::new(Recording {
            inner: file,
            error: None,
        });
        let result = write(&mut w).and_then(|()| Ok(w.flush()?));
        let os = w.get_mut().error.take();
        match (result, os) {
            (Ok(()), _) => Ok(w.get_ref().inner.sync_all()?),
            (Err(_), Some(os)) => Err(anyhow::anyhow!(os)),
            (Err(e), None) => Err(e),
        }
    })
}

/// Has `write` write `path`'s temporary file by its path (for writers that open the file
/// themselves), then renames it into place; as `write_atomic`.
pub fn write_atomic_by_path(
    path: &Path,
    write: impl FnOnce(&Path) -> std::io::Result<()>,
) -> Result<()> {
    atomically(path, |tmp, file| {
        drop(file);
        write(tmp)?;
        Ok(std::fs::File::open(tmp)?.sync_all()?)
    })
}

/// The temporary file (created new, removed on an error or on SIGINT, SIGTERM or SIGHUP), `fill`
/// given its path and handle, then the rename, if `path` is still absent or a regular file.
fn atomically(path: &Path, fill: impl FnOnce(&Path, std::fs::File) -> Result<()>) -> Result<()> {
    let fail = |why: String| crate::input::bad(format!("{}: cannot write: {why}", path.display()));
    let dir = folder_of(path);
    if path.file_name().is_none() {
        return Err(fail("not a file name".into()));
    }
    refuse_non_regular(path).map_err(crate::input::bad)?;
    if let Some(input) = crate::files::input_at(path) {
        return Err(fail(format!("it is {input}, an input of this run")));
    }
    // Registered before it is created: a signal between the two only removes nothing.
    let (mut tmp, file) = loop {
        let path = temp_name(dir, "tmp");
        let pending = on_signal::remove_on_signal(&path);
        match create_new(&path) {
            Ok(f) => {
                let tmp = Temp {
                    path,
                    renamed: false,
                    _pending: pending,
                };
                break (tmp, f);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => {
                return Err(fail(format!(
                    "{e} (creating a temporary file in {})",
                    dir.display()
                )));
            }
        }
    };
    fill(&tmp.path, file).map_err(|e| fail(crate::panic_guard::one_line(&format!("{e:#}"))))?;
    refuse_non_regular(path).map_err(crate::input::bad)?;
    std::fs::rename(&tmp.path, path).map_err(|e| fail(e.to_string()))?;
    tmp.renamed = true;
    Ok(())
}

/// A temporary file, removed when dropped unless renamed into place: on an error, and on a panic
/// in the writer too. Registered for removal on a signal while it lives.
struct Temp {
    path: PathBuf,
    renamed: bool,
    _pending: on_signal::Pending,
}

impl Drop for Temp {
    fn drop(&mut self) {
        if !self.renamed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
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
            .context("EXR encoding failed")
    })
}

pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: Vec<u8>) -> Result<()> {
    let img: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_raw(width, height, rgb)
        .context("image size does not match its pixels")?;
    write_atomic(path, |w| {
        img.write_to(w, ImageFormat::Png)
            .context("PNG encoding failed")
    })
}

/// Why an 8-bit image `rgb` of `radiance` at `exposure` hides the radiance, or `None`: all black
/// though some radiance is not 0, or all white though the radiance varies (an exposure out of
/// scale, or radiance beyond what the automatic exposure reaches).
pub fn display_warning(radiance: &[[f32; 3]], rgb: &[u8], exposure: f32) -> Option<String> {
    let finite = || radiance.iter().flatten().filter(|c| c.is_finite());
    let max = finite().fold(0.0f32, |m, &c| m.max(c));
    let min = finite().fold(f32::INFINITY, |m, &c| m.min(c));
    if max > 0.0 && rgb.iter().all(|&b| b == 0) {
        return Some(format!(
            "the PNG is black at exposure {exposure:e}, though the radiance reaches {max:e}; the .exr output keeps the values (or set --exposure)"
        ));
    }
    if min < max && rgb.iter().all(|&b| b == 255) {
        return Some(format!(
            "the PNG is white at exposure {exposure:e}, though the radiance ranges over {min:e}..{max:e}; the .exr output keeps the values (or set --exposure)"
        ));
    }
    None
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
        Some("png") => {
            let rgb = to_srgb8(radiance, exposure);
            if let Some(w) = display_warning(radiance, &rgb, exposure) {
                eprintln!("warning: {}: {w}", path.display());
            }
            write_png_rgb8(path, width, height, rgb)
        }
        _ => bail!("{}: output must end in .exr or .png", path.display()),
    }
}

/// The most bytes read from one image file (a `--compare` reference, a viewer's reference): 2 GiB,
/// a 16k × 8k float RGBA EXR.
pub const MAX_IMAGE_FILE_BYTES: u64 = 2 << 30;

/// The bytes of image file `path`: a regular file of at most `MAX_IMAGE_FILE_BYTES`.
fn image_bytes(path: &Path) -> Result<Vec<u8>> {
    crate::files::read_regular(path, MAX_IMAGE_FILE_BYTES, "an image file")
        .map_err(|e| crate::input::bad(format!("{}: cannot read: {e}", path.display())))
}

/// Decodes an image's bytes as linear RGB (8-bit formats as stored, without the sRGB transfer).
fn decode_rgb32f(path: &Path, bytes: &[u8]) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let img = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()?
        .decode()
        .map_err(|e| crate::input::bad(format!("{}: not a readable image: {e}", path.display())))?
        .into_rgb32f();
    let (w, h) = img.dimensions();
    let px = img.pixels().map(|p| p.0).collect();
    Ok((w, h, px))
}

/// Reads an image file (EXR, or PNG/JPEG as stored) as RGB.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    decode_rgb32f(path, &image_bytes(path)?)
}

/// Reads a linear reference (`--compare`): an OpenEXR file only. A PNG or JPEG holds 8-bit sRGB,
/// not radiance, and metrics against it would mean nothing: refused, saying what the file is.
pub fn read_linear_exr(path: &Path) -> Result<(u32, u32, Vec<[f32; 3]>)> {
    let bytes = image_bytes(path)?;
    if !bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        let what = match image::guess_format(&bytes) {
            Ok(f) => format!(
                "a {} image (8-bit, display-encoded)",
                format!("{f:?}").to_ascii_uppercase()
            ),
            Err(_) if bytes.is_empty() => "empty".into(),
            Err(_) => "not an image fuzzy-vpl knows".into(),
        };
        return Err(crate::input::bad(format!(
            "{}: the reference must be an OpenEXR file (linear radiance, as `render -o X.exr` writes); it is {what}",
            path.display()
        )));
    }
    decode_rgb32f(path, &bytes)
}

/// Temporary files removed when the process is ended by SIGINT, SIGTERM or SIGHUP. The handler does
/// only what is async-signal-safe: it `unlink`s the registered paths (C strings that stay valid for
/// the rest of the run, so a handler running on another thread never reads freed memory), restores
/// the default action and raises the signal again, so the run still ends as killed by it. Done in
/// the handler rather than by a flag the writer polls, the file goes even while the writer is
/// blocked in a system call. A signal the process was started ignoring (`nohup`) stays ignored.
#[cfg(unix)]
mod on_signal {
    use std::ffi::{CString, c_char};
    use std::path::Path;
    use std::sync::atomic::{AtomicPtr, Ordering};

    const SIGNALS: [libc::c_int; 3] = [libc::SIGINT, libc::SIGTERM, libc::SIGHUP];
    /// Temporary files alive at once (a run writes its outputs one after another; the viewer's
    /// threads a few); a write past them goes unregistered.
    const SLOTS: usize = 64;
    static PENDING: [AtomicPtr<c_char>; SLOTS] =
        [const { AtomicPtr::new(std::ptr::null_mut()) }; SLOTS];

    extern "C" fn handler(sig: libc::c_int) {
        for slot in &PENDING {
            let p = slot.load(Ordering::SeqCst);
            if !p.is_null() {
                // SAFETY: a leaked, NUL-terminated C string (see `remove_on_signal`).
                unsafe { libc::unlink(p) };
            }
        }
        // SAFETY: signal and raise are async-signal-safe.
        unsafe {
            libc::signal(sig, libc::SIG_DFL);
            libc::raise(sig);
        }
    }

    fn install() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            for sig in SIGNALS {
                // SAFETY: sigaction with a zeroed struct queries; the handler is async-signal-safe.
                unsafe {
                    let mut old: libc::sigaction = std::mem::zeroed();
                    if libc::sigaction(sig, std::ptr::null(), &mut old) != 0
                        || old.sa_sigaction != libc::SIG_DFL
                    {
                        continue;
                    }
                    let mut new: libc::sigaction = std::mem::zeroed();
                    new.sa_sigaction = handler as extern "C" fn(libc::c_int) as libc::sighandler_t;
                    libc::sigemptyset(&mut new.sa_mask);
                    libc::sigaction(sig, &new, std::ptr::null_mut());
                }
            }
        });
    }

    /// Registered while alive: the file at `path` is removed if a signal ends the process.
    pub struct Pending(Option<usize>);

    impl Drop for Pending {
        fn drop(&mut self) {
            if let Some(i) = self.0 {
                // The string is leaked, not freed: a handler on another thread may hold it.
                PENDING[i].store(std::ptr::null_mut(), Ordering::SeqCst);
            }
        }
    }

    pub fn remove_on_signal(path: &Path) -> Pending {
        use std::os::unix::ffi::OsStrExt;
        install();
        let Ok(c) = CString::new(path.as_os_str().as_bytes()) else {
            return Pending(None);
        };
        let p = c.into_raw();
        for (i, slot) in PENDING.iter().enumerate() {
            if slot
                .compare_exchange(std::ptr::null_mut(), p, Ordering::SeqCst, Ordering::SeqCst)
                .is_ok()
            {
                return Pending(Some(i));
            }
        }
        // SAFETY: `p` came from `into_raw` just above and was never shared.
        drop(unsafe { CString::from_raw(p) });
        Pending(None)
    }
}

#[cfg(not(unix))]
mod on_signal {
    pub struct Pending;
    pub fn remove_on_signal(_: &std::path::Path) -> Pending {
        Pending
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("fuzzy-vpl-export-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// A 255-byte name (NAME_MAX) is written: the temporary name does not grow with it. A failed
    /// write leaves the old file and no temporary file, and says the file and the reason.
    #[test]
    fn atomic_writes_take_any_name_and_leave_nothing_behind() {
        let d = scratch("names");
        let long = d.join("n".repeat(255));
        write_json(&long, &[1, 2]).unwrap();
        assert_eq!(
            std::fs::read_to_string(&long)
                .unwrap()
                .split_whitespace()
                .count(),
            4
        );
        let kept = d.join("kept.json");
        std::fs::write(&kept, "old").unwrap();
        let e = write_atomic(&kept, |w| {
            w.write_all(b"new")?;
            anyhow::bail!("the encoder gave up")
        })
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("kept.json: cannot write: the encoder gave up"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&kept).unwrap(), "old");
        assert_eq!(names(&d), vec!["kept.json".to_string(), "n".repeat(255)]);
    }

    /// A file recorded as an input of the run is never replaced, whatever name reaches it (here a
    /// hard link): the backstop behind `render`'s check before the work, for names made up later.
    #[test]
    fn an_input_of_the_run_is_not_replaced() {
        let d = scratch("input");
        let scene = d.join("scene.gltf");
        std::fs::write(&scene, "{}").unwrap();
        std::fs::hard_link(&scene, d.join("grid.png")).unwrap();
        crate::files::note_inputs(&[("the scene", scene.as_path())]);
        let e = write_json(&d.join("grid.png"), &1).unwrap_err().to_string();
        assert!(e.contains("grid.png: cannot write: it is the scene"), "{e}");
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), "{}");
        assert_eq!(names(&d), vec!["grid.png", "scene.gltf"]);
    }

    /// A writer that panics leaves no temporary file either.
    #[test]
    fn a_panicking_writer_leaves_nothing_behind() {
        let d = scratch("panic");
        let out = d.join("p.json");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic(&out, |w| {
                w.write_all(b"partial")?;
                w.flush()?;
                panic!("the encoder panicked")
            });
        });
        assert!(r.is_err());
        assert!(names(&d).is_empty(), "{:?}", names(&d));
    }

    /// What exists at the output and is not a regular file is refused at the write too (it may
    /// appear after `check_writable`): a symbolic link stays a link to the untouched target.
    #[cfg(unix)]
    #[test]
    fn the_write_refuses_a_link_or_folder_that_appeared() {
        let d = scratch("links");
        let target = d.join("t.json");
        std::fs::write(&target, "target").unwrap();
        let link = d.join("l.json");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write_json(&link, &1).unwrap_err().to_string();
        assert!(e.contains("l.json") && e.contains("symbolic link"), "{e}");
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "target");
        std::fs::create_dir_all(d.join("dir.json")).unwrap();
        let e = write_json(&d.join("dir.json"), &1).unwrap_err().to_string();
        assert!(e.contains("a directory"), "{e}");
        assert_eq!(names(&d), vec!["dir.json", "l.json", "t.json"]);
    }

    /// The PNG's warning: black though the radiance is not, white though it varies, else none.
    #[test]
    fn a_png_that_hides_the_radiance_is_named() {
        let img = [[1e-3f32, 0.0, 0.0], [0.0; 3]];
        let dark = display_warning(&img, &to_srgb8(&img, 1e-6), 1e-6).unwrap();
        assert!(dark.contains("black") && dark.contains("1e-3"), "{dark}");
        let white = display_warning(&img, &[255; 6], 1e9).unwrap();
        assert!(white.contains("white"), "{white}");
        assert_eq!(display_warning(&img, &to_srgb8(&img, 1e3), 1e3), None);
        // A black image is black: nothing hidden.
        assert_eq!(display_warning(&[[0.0; 3]; 2], &[0; 6], 1.0), None);
    }
}
