//! Built-in scenes embedded in the binary (`builtin:NAME`).

use super::{Scene, SceneError, gltf_load};

/// Names accepted by [`load`].
pub const NAMES: &[&str] = &["cornell", "conference"];

/// The embedded GLB of a built-in scene.
fn bytes(name: &str) -> Option<&'static [u8]> {
    match name {
        "cornell" => Some(include_bytes!("../../assets/cornell.glb")),
        "conference" => Some(include_bytes!("../../assets/conference.glb")),
        _ => None,
    }
}

/// Loads built-in scene `name` (without the `builtin:` prefix); the scene is named `builtin:NAME`.
pub fn load(name: &str) -> Result<Scene, SceneError> {
    let label = format!("builtin:{name}");
    match bytes(name) {
        Some(b) => gltf_load::load_slice(b, &label),
        None => Err(SceneError::new(
            label,
            format!("unknown built-in scene (known: {})", NAMES.join(", ")),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_loads() {
        for name in NAMES {
            let s = load(name).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.name, format!("builtin:{name}"));
            assert!(!s.triangles.is_empty());
            assert!(s.path.is_none());
        }
    }

    #[test]
    fn unknown_builtin_is_an_error() {
        let e = load("nope").unwrap_err().to_string();
        assert!(e.contains("builtin:nope"), "{e}");
        assert!(e.contains("cornell") && e.contains("conference"), "{e}");
    }
}
