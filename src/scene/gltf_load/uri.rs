//! Resolving glTF URIs: `data:` URIs (base64 or percent-encoded) and relative file references.

use std::path::Path;

/// What a URI refers to.
pub(super) enum Resolved {
    /// Inline bytes from a `data:` URI.
    Data(Vec<u8>),
    /// A file on disk (relative URIs joined to the glTF file's folder).
    File(std::path::PathBuf),
}

/// Resolves `uri` against `base` (the glTF file's folder; `None` for in-memory scenes).
pub(super) fn resolve(uri: &str, base: Option<&Path>) -> Result<Resolved, String> {
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
    let path = if let Some(p) = uri.strip_prefix("file://") {
        percent_decode(p)
    } else if let Some(p) = uri.strip_prefix("file:") {
        percent_decode(p)
    } else if has_scheme(uri) {
        return Err(format!("unsupported URI scheme in '{}'", short(uri)));
    } else {
        percent_decode(uri)
    };
    let path = String::from_utf8(path)
        .map_err(|_| format!("URI '{}' is not valid UTF-8 once decoded", short(uri)))?;
    match base {
        Some(base) => Ok(Resolved::File(base.join(path))),
        None => Err(format!(
            "external file '{}' cannot be resolved for an in-memory scene",
            short(&path)
        )),
    }
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
        assert!(resolve("http://example.com/x.bin", Some(Path::new("."))).is_err());
    }
}
