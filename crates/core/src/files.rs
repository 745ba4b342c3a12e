//! Files the user names: every reader opens them through [`open_regular`] (a regular file only, so
//! a FIFO, a device or a directory is refused before it can block or never end) and reads at most a
//! fixed cap; every writer's path is checked by `export::check_writable`, and the paths of one run
//! by [`check_distinct`], through [`FileKey`] (one file under two names, a hard link or a symlink
//! included).

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

/// What a non-regular file is, for messages ("a FIFO").
pub fn kind(t: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
    }
    if t.is_dir() {
        "a directory"
    } else if t.is_symlink() {
        "a symbolic link"
    } else {
        "not a file"
    }
}

/// Opens `path` for reading if it is a regular file; returns it with its size. Opened non-blocking
/// so that a FIFO without a writer does not block before the check (the flag has no effect on a
/// regular file's reads).
pub fn open_regular(path: &Path) -> Result<(File, u64), String> {
    let mut opts = std::fs::OpenOptions::new();
    opts.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        opts.custom_flags(libc::O_NONBLOCK);
    }
    let f = opts.open(path).map_err(|e| e.to_string())?;
    let meta = f.metadata().map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err(format!("not a regular file ({})", kind(meta.file_type())));
    }
    Ok((f, meta.len()))
}

/// Reads the whole of regular file `path`, refused (before reading) when it holds more than `cap`
/// bytes; `what` names the file's role in that message ("a results.csv"). The error is the reason
/// alone: the caller names the file.
pub fn read_regular(path: &Path, cap: u64, what: &str) -> Result<Vec<u8>, String> {
    let (f, size) = open_regular(path)?;
    if size > cap {
        return Err(format!("{size} bytes, more than the {cap} {what} may have"));
    }
    let mut out = Vec::new();
    out.try_reserve_exact(size as usize)
        .map_err(|_| format!("cannot allocate {size} bytes to read it"))?;
    // One byte past the cap tells a file that grew after the check.
    f.take(cap + 1)
        .read_to_end(&mut out)
        .map_err(|e| e.to_string())?;
    if out.len() as u64 > cap {
        return Err(format!("grew past {cap} bytes while being read"));
    }
    Ok(out)
}

/// `read_regular` as UTF-8 text.
pub fn read_text(path: &Path, cap: u64, what: &str) -> Result<String, String> {
    String::from_utf8(read_regular(path, cap, what)?).map_err(|_| "not UTF-8 text".to_string())
}

/// Which file a path names, to tell two names of one file apart from two files: an existing file by
/// its device and inode (so a hard link, a symlink or `./a` against `a` are the same file), one yet
/// to be written by its folder's canonical path and its name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum FileKey {
    Inode(u64, u64),
    New(PathBuf),
}

impl FileKey {
    /// The key of `path`, or `None` when neither it nor its folder can be resolved (the write
    /// checks report that themselves).
    pub fn of(path: &Path) -> Option<FileKey> {
        #[cfg(unix)]
        if let Ok(m) = std::fs::metadata(path) {
            use std::os::unix::fs::MetadataExt;
            return Some(FileKey::Inode(m.dev(), m.ino()));
        }
        #[cfg(not(unix))]
        if let Ok(p) = std::fs::canonicalize(path) {
            return Some(FileKey::New(p));
        }
        let dir = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Some(FileKey::New(
            std::fs::canonicalize(dir).ok()?.join(path.file_name()?),
        ))
    }
}

/// Refuses two `outputs` of one run that name one file (the second would replace the first), and
/// an output that names one of the `inputs` (it would replace what the run reads). Each path comes
/// with the option that named it ("-o", "--stats"; for an input, what it is: "the scene").
pub fn check_distinct(outputs: &[(&str, &Path)], inputs: &[(&str, &Path)]) -> Result<(), String> {
    let keyed = |list: &[(&str, &Path)]| -> Vec<(String, FileKey)> {
        list.iter()
            .filter_map(|(what, p)| Some((format!("{what} {}", p.display()), FileKey::of(p)?)))
            .collect()
    };
    let inputs = keyed(inputs);
    let mut seen: Vec<(String, FileKey)> = Vec::new();
    for (out, key) in keyed(outputs) {
        if let Some((input, _)) = inputs.iter().find(|(_, k)| *k == key) {
            return Err(format!(
                "{out}: it is also {input}, an input of this run; refusing to overwrite it"
            ));
        }
        if let Some((first, _)) = seen.iter().find(|(_, k)| *k == key) {
            return Err(format!(
                "{first} and {out} name the same file; give each output its own"
            ));
        }
        seen.push((out, key));
    }
    Ok(())
}

/// The inputs of this run (`note_inputs`): no write may replace one (`export::write_atomic` asks
/// `input_at`), whatever names the output, so a name made up during the run (bench's images) is
/// covered as well as the options `check_distinct` compares before the work.
static INPUTS: std::sync::Mutex<Vec<(String, FileKey)>> = std::sync::Mutex::new(Vec::new());

/// Records `inputs` (each with what it is: "the scene") as files no write of this run may replace.
pub fn note_inputs(inputs: &[(&str, &Path)]) {
    let mut all = INPUTS.lock().unwrap_or_else(|p| p.into_inner());
    for (what, p) in inputs {
        if let Some(key) = FileKey::of(p) {
            all.push((format!("{what} {}", p.display()), key));
        }
    }
}

/// The recorded input that `path` names, as "the scene x.gltf", if it names one.
pub fn input_at(path: &Path) -> Option<String> {
    let all = INPUTS.lock().unwrap_or_else(|p| p.into_inner());
    if all.is_empty() {
        return None;
    }
    let key = FileKey::of(path)?;
    all.iter().find(|(_, k)| *k == key).map(|(w, _)| w.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fuzzy-vpl-files-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn only_regular_files_are_read_and_only_up_to_the_cap() {
        let d = scratch("read");
        let f = d.join("a.txt");
        std::fs::write(&f, "hello").unwrap();
        assert_eq!(read_text(&f, 5, "a test file").unwrap(), "hello");
        let e = read_text(&f, 4, "a test file").unwrap_err();
        assert!(e.contains("5 bytes, more than the 4 a test file"), "{e}");
        let e = read_regular(&d, 10, "x").unwrap_err();
        assert!(e.contains("a directory"), "{e}");
        let e = read_regular(Path::new("/dev/zero"), 10, "x").unwrap_err();
        assert!(e.contains("a device"), "{e}");
        std::fs::write(d.join("bad.txt"), [0xff, 0xfe]).unwrap();
        assert_eq!(
            read_text(&d.join("bad.txt"), 10, "x").unwrap_err(),
            "not UTF-8 text"
        );
    }

    #[test]
    fn two_names_of_one_file_are_the_same_file() {
        let d = scratch("same");
        let a = d.join("a.png");
        std::fs::write(&a, "x").unwrap();
        let dot = d.join(".").join("a.png");
        let new1 = d.join("n.json");
        let new2 = d.join("sub").join("..").join("n.json");
        std::fs::create_dir_all(d.join("sub")).unwrap();
        assert_eq!(FileKey::of(&a), FileKey::of(&dot));
        assert_eq!(FileKey::of(&new1), FileKey::of(&new2));
        assert_ne!(FileKey::of(&a), FileKey::of(&new1));
        let (o, st, tr) = (
            ("-o", a.as_path()),
            ("--stats", new1.as_path()),
            ("--trace", dot.as_path()),
        );
        let m = check_distinct(&[o, st, tr], &[]).unwrap_err();
        assert!(m.starts_with("-o ") && m.contains("and --trace"), "{m}");
        assert!(check_distinct(&[o, st], &[]).is_ok());
        let m = check_distinct(&[st, tr], &[("the scene", a.as_path())]).unwrap_err();
        assert!(m.starts_with("--trace ") && m.contains("the scene"), "{m}");
        #[cfg(unix)]
        {
            let link = d.join("l.png");
            std::os::unix::fs::symlink(&a, &link).unwrap();
            assert_eq!(FileKey::of(&a), FileKey::of(&link));
        }
    }
}
