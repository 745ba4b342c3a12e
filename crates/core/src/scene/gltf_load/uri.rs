//! Resolving glTF URIs: `data:` URIs (base64 or percent-encoded) and relative file references.

use std::path::{Component, Path, PathBuf};

/// What a URI refers to.
pub(super) enum Resolved {
    /// Inline bytes from a `data:` URI.
    Data(Vec<u8>),
    /// A file on disk (relative URIs joined to the glTF file's folder).
    File(std::path::PathBuf),
}

/// The folder a scene file's relative URIs resolve in, and whether they may name files outside it
/// (`--allow-outside-uris`).
pub(super) struct Folder<'a> {
    pub dir: &'a Path,
    /// `dir` with every symlink resolved (`None` if it cannot be).
    canonical: Option<PathBuf>,
    pub allow_outside: bool,
}

impl<'a> Folder<'a> {
    pub fn new(dir: &'a Path, allow_outside: bool) -> Self {
        Folder {
            dir,
            canonical: std::fs::canonicalize(dir).ok(),
            allow_outside,
        }
    }
}

/// Resolves `uri` against `base` (the glTF file's folder; `None` for in-memory scenes). A URI that
/// names a file outside the folder is refused by `check_inside` unless the folder allows it.
pub(super) fn resolve(uri: &str, base: Option<&Folder>) -> Result<Resolved, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, payload) = rest
            .split_once(',')
            .ok_or_else(|| "malformed data: URI (no ',')".to_string())?;
        let bytes = if meta.ends_with(";base64") {
            base64_decode(payload).ok_or_else(|| "data: URI is not valid base64".to_string())?
        } else {
            percent_decode(payload)
        };
        return Ok(Resolved::Data(bytes));
    }
    let path = decoded_path(uri)?;
    match base {
        Some(base) => {
            let file = base.dir.join(&path);
            check_inside(uri, &path, &file, base).map_err(|Refused(why)| why)?;
            Ok(Resolved::File(file))
        }
        None => Err(format!(
            "external file '{}' cannot be resolved for an in-memory scene",
            short(&path)
        )),
    }
}

/// The path a file URI (relative, or `file:`) names, percent-decoded; an error for another scheme.
fn decoded_path(uri: &str) -> Result<String, String> {
    let path = if let Some(p) = uri.strip_prefix("file://") {
        percent_decode(p)
    } else if let Some(p) = uri.strip_prefix("file:") {
        percent_decode(p)
    } else if has_scheme(uri) {
        return Err(format!("unsupported URI scheme in '{}'", short(uri)));
    } else {
        percent_decode(uri)
    };
    String::from_utf8(path)
        .map_err(|_| format!("URI '{}' is not valid UTF-8 once decoded", short(uri)))
}

/// A URI the policy refuses, with why.
struct Refused(String);

/// The URI policy: a `file:` URI, an absolute path, or a relative path that leads out of the
/// scene's folder (by `..` once percent-decoded, or through a symbolic link) is refused unless
/// `--allow-outside-uris` is given, so a scene from elsewhere cannot read (and show in its image)
/// any file its user can read. `decoded` is the URI's path, `file` where it resolves.
fn check_inside(uri: &str, decoded: &str, file: &Path, base: &Folder) -> Result<(), Refused> {
    if base.allow_outside {
        return Ok(());
    }
    let refuse = |how: &str| {
        Err(Refused(format!(
            "URI '{}' {how}; a scene may only name files inside its own folder (--allow-outside-uris lets it read others)",
            short(uri)
        )))
    };
    if uri.starts_with("file:") {
        return refuse("is a file: URI");
    }
    let mut depth = 0i64;
    for c in Path::new(decoded).components() {
        match c {
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::ParentDir => {
                depth -= 1;
                if depth < 0 {
                    return refuse("leads outside the scene's folder (by '..')");
                }
            }
            Component::RootDir | Component::Prefix(_) => {
                return refuse("is an absolute path");
            }
        }
    }
    // Symbolic links: where the file really is. A file that does not exist is left to the reader,
    // which says so.
    if let (Some(dir), Ok(real)) = (&base.canonical, std::fs::canonicalize(file))
        && !real.starts_with(dir)
    {
        return refuse(&format!(
            "leads outside the scene's folder (through a symbolic link, to {})",
            real.display()
        ));
    }
    Ok(())
}

/// The external files `doc`'s buffers and images name, resolved in `base`; the first URI the policy
/// refuses (`check_inside`) is an error naming it. Checked before anything is read, so a refused
/// URI ends the load whichever texture slot names it.
pub(super) fn external_files(doc: &gltf::Document, base: &Folder) -> Result<Vec<PathBuf>, String> {
    let buffers = doc.buffers().filter_map(|b| match b.source() {
        gltf::buffer::Source::Uri(u) => Some((format!("buffer {}", b.index()), u)),
        gltf::buffer::Source::Bin => None,
    });
    let images = doc.images().filter_map(|i| match i.source() {
        gltf::image::Source::Uri { uri, .. } => Some((format!("image {}", i.index()), uri)),
        gltf::image::Source::View { .. } => None,
    });
    let mut files = Vec::new();
    for (what, u) in buffers.chain(images) {
        // A data: URI names no file; a URI with no path is the reader's to report.
        let Some(path) = Some(u)
            .filter(|u| !u.starts_with("data:"))
            .and_then(|u| decoded_path(u).ok())
        else {
            continue;
        };
        let file = base.dir.join(&path);
        check_inside(u, &path, &file, base).map_err(|Refused(why)| format!("{what}: {why}"))?;
        files.push(file);
    }
    Ok(files)
}

/// At most 80 characters of `s`, for messages.
pub(super) fn short(s: &str) -> String {
    if s.chars().count() <= 80 {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(77).collect::<String>())
    }
}

/// `scheme:` per RFC 3986 (a letter, then letters, digits, `+`, `-`, `.`), at least 2 characters so
/// Windows drive letters are not mistaken for schemes.
fn has_scheme(uri: &str) -> bool {
    match uri.split_once(':') {
        Some((s, _)) => {
            s.len() > 1
                && s.starts_with(|c: char| c.is_ascii_alphabetic())
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
        }
        None => false,
    }
}

/// Decodes `%XX` escapes (`percent-encoding`); malformed escapes are kept literally.
fn percent_decode(s: &str) -> Vec<u8> {
    percent_encoding::percent_decode(s.as_bytes()).collect()
}

/// Standard or URL-safe base64, padding optional, ASCII whitespace ignored (`base64`, the
/// version the `gltf` crate uses). `None` if malformed.
fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let standard: Vec<u8> = s
        .bytes()
        .filter(|c| !matches!(c, b' ' | b'\t' | b'\r' | b'\n'))
        .map(|c| match c {
            b'-' => b'+',
            b'_' => b'/',
            c => c,
        })
        .collect();
    base64::decode_config(standard, base64::STANDARD.decode_allow_trailing_bits(true)).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips() {
        assert_eq!(base64_decode("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64_decode("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64_decode("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert_eq!(base64_decode("").unwrap(), b"");
        assert!(base64_decode("a").is_none());
        assert!(base64_decode("aGV$").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b%2"), b"a b%2");
        assert_eq!(percent_decode("%"), b"%");
        assert_eq!(percent_decode("x%zz"), b"x%zz");
    }

    #[test]
    fn schemes() {
        assert!(has_scheme("http://x"));
        assert!(!has_scheme("C:/x.bin"));
        assert!(!has_scheme("a b.bin"));
        assert!(matches!(
            resolve("data:application/octet-stream;base64,AAAA", None),
            Ok(Resolved::Data(d)) if d == [0, 0, 0]
        ));
        assert!(resolve("x.bin", None).is_err());
        let here = Folder::new(Path::new("."), false);
        assert!(resolve("http://example.com/x.bin", Some(&here)).is_err());
    }

    /// The policy by the path alone (no file exists): `..` out, also percent-encoded and after a
    /// subfolder, absolute and `file:` refused; `..` that stays inside allowed; all allowed with
    /// `--allow-outside-uris`.
    #[test]
    fn uris_leaving_the_folder() {
        let here = Folder::new(Path::new("no-such-folder"), false);
        let anywhere = Folder::new(Path::new("no-such-folder"), true);
        for uri in [
            "../x.bin",
            "%2E%2e/x.bin",
            "a/../../x.bin",
            "a%2F..%2F..%2Fx.bin",
            "/etc/passwd",
            "%2Fetc%2Fpasswd",
            "file:///etc/passwd",
            "file:x.bin",
        ] {
            let e = resolve(uri, Some(&here))
                .err()
                .unwrap_or_else(|| panic!("{uri}"));
            assert!(e.contains(uri) && e.contains("--allow-outside-uris"), "{e}");
            assert!(resolve(uri, Some(&anywhere)).is_ok(), "{uri}");
        }
        for uri in [
            "x.bin",
            "a/../x.bin",
            "./a/b/../x.bin",
            "a%2Fx.bin",
            "..x.bin",
        ] {
            assert!(resolve(uri, Some(&here)).is_ok(), "{uri}");
        }
    }
}
