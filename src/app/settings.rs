//! The per-scene settings file: camera bookmarks, kept beside the scene (`SCENE.fuzzy-vpl.json`) or,
//! for built-in scenes, in the user's config dir (`$XDG_CONFIG_HOME/fuzzy-vpl/builtin-NAME.json`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::camera::ViewCamera;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bookmark {
    pub name: String,
    pub eye: [f32; 3],
    pub yaw: f32,
    pub pitch: f32,
    pub yfov: f32,
    pub distance: f32,
}

impl Bookmark {
    pub fn new(name: String, c: &ViewCamera) -> Self {
        Bookmark {
            name,
            eye: c.eye.into(),
            yaw: c.yaw,
            pitch: c.pitch,
            yfov: c.yfov,
            distance: c.distance,
        }
    }

    pub fn camera(&self) -> ViewCamera {
        ViewCamera {
            eye: Vec3::from(self.eye),
            yaw: self.yaw,
            pitch: self.pitch,
            yfov: self.yfov,
            distance: self.distance,
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SceneSettings {
    #[serde(default)]
    pub bookmarks: Vec<Bookmark>,
}

/// Where a scene's settings live (None: no config dir known for a built-in scene).
pub fn settings_path(spec: &str) -> Option<PathBuf> {
    if let Some(name) = spec.strip_prefix("builtin:") {
        let base = std::env::var_os("XDG_CONFIG_HOME")
            .map(PathBuf::from)
            .filter(|p| p.is_absolute())
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
        return Some(base.join("fuzzy-vpl").join(format!("builtin-{name}.json")));
    }
    let p = Path::new(spec);
    let file = p.file_name()?.to_string_lossy().into_owned();
    Some(p.with_file_name(format!("{file}.fuzzy-vpl.json")))
}

impl SceneSettings {
    /// Reads the file; a missing file gives empty settings.
    pub fn load(path: &Path) -> Result<Self> {
        match std::fs::read_to_string(path) {
            Ok(text) => serde_json::from_str(&text)
                .with_context(|| format!("{}: not a fuzzy-vpl settings file", path.display())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Self::default()),
            Err(e) => Err(e).with_context(|| format!("{}: cannot read", path.display())),
        }
    }

    /// Saves to `path` without losing a file there that failed to load (`unreadable`): that file is
    /// first moved aside to `PATH.bad-N` (the first free N), which is returned.
    pub fn save_keeping(&self, path: &Path, unreadable: bool) -> Result<Option<PathBuf>> {
        let moved = if unreadable && std::fs::symlink_metadata(path).is_ok() {
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            let aside = (1..)
                .map(|n| path.with_file_name(format!("{name}.bad-{n}")))
                .find(|p| std::fs::symlink_metadata(p).is_err())
                .expect("a free name");
            std::fs::rename(path, &aside).with_context(|| {
                format!(
                    "{}: could not be read and cannot be moved aside to {}; bookmarks not saved",
                    path.display(),
                    aside.display()
                )
            })?;
            Some(aside)
        } else {
            None
        };
        self.save(path)?;
        Ok(moved)
    }

    pub fn save(&self, path: &Path) -> Result<()> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("{}: cannot create", dir.display()))?;
        }
        let json = serde_json::to_string_pretty(self)?;
        crate::export::write_atomic(path, |w| {
            use std::io::Write;
            w.write_all(json.as_bytes())?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bookmarks_round_trip_through_the_file() {
        let dir = std::env::temp_dir().join(format!("fuzzy-vpl-settings-{}", std::process::id()));
        let scene = dir.join("room.glb");
        let path = settings_path(scene.to_str().unwrap()).unwrap();
        assert_eq!(path, dir.join("room.glb.fuzzy-vpl.json"));
        assert_eq!(
            SceneSettings::load(&path).unwrap(),
            SceneSettings::default()
        );
        let cam = ViewCamera {
            eye: Vec3::new(1.0, -2.5, 3.25),
            yaw: 0.5,
            pitch: -0.25,
            yfov: 0.9,
            distance: 4.0,
        };
        let s = SceneSettings {
            bookmarks: vec![
                Bookmark::new("door".into(), &cam),
                Bookmark::new("ceiling".into(), &ViewCamera { yaw: -3.0, ..cam }),
            ],
        };
        s.save(&path).unwrap();
        let back = SceneSettings::load(&path).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.bookmarks[0].camera(), cam);
        std::fs::write(&path, "{ not json").unwrap();
        assert!(SceneSettings::load(&path).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn builtin_settings_go_to_the_config_dir() {
        let p = settings_path("builtin:cornell");
        if let Some(p) = p {
            assert!(
                p.ends_with("fuzzy-vpl/builtin-cornell.json"),
                "{}",
                p.display()
            );
        }
    }
}
