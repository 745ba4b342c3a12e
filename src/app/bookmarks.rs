//! The per-scene bookmarks file: camera bookmarks, kept beside the scene (`SCENE.fuzzy-vpl.json`) or,
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
pub struct BookmarksFile {
    #[serde(default)]
    pub bookmarks: Vec<Bookmark>,
}

/// Where a scene's bookmarks file lives (None: no config dir known for a built-in scene).
pub fn bookmarks_path(spec: &str) -> Option<PathBuf> {
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

/// The largest bookmarks file read (a thousand bookmarks take about 200 KB).
pub const MAX_FILE_BYTES: u64 = 1 << 20;
/// The most bookmarks a file may hold.
pub const MAX_BOOKMARKS: usize = 1000;

impl BookmarksFile {
    /// Reads the file; a missing file gives no bookmarks. Bounded like every input: only a regular
    /// file (a FIFO or device would block or never end) of at most `MAX_FILE_BYTES`, at most
    /// `MAX_BOOKMARKS` bookmarks, each finite with a name of at most 200 characters; anything else
    /// is a one-line error naming the file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = match crate::files::read_text(path, MAX_FILE_BYTES, "a bookmarks file") {
            Ok(t) => t,
            Err(_) if !path.exists() => return Ok(Self::default()),
            Err(e) => anyhow::bail!("{}: cannot read: {e}", path.display()),
        };
        let s: Self = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a fuzzy-vpl bookmarks file", path.display()))?;
        s.check()
            .map_err(|why| anyhow::anyhow!("{}: {why}", path.display()))?;
        Ok(s)
    }

    /// Bookmarks a viewer can use: at most `MAX_BOOKMARKS`, finite, a positive field of view.
    fn check(&self) -> std::result::Result<(), String> {
        if self.bookmarks.len() > MAX_BOOKMARKS {
            return Err(format!(
                "{} bookmarks, more than {MAX_BOOKMARKS}",
                self.bookmarks.len()
            ));
        }
        for (i, b) in self.bookmarks.iter().enumerate() {
            let numbers = b.eye.iter().chain([&b.yaw, &b.pitch, &b.yfov, &b.distance]);
            if numbers.clone().any(|v| !v.is_finite()) {
                return Err(format!(
                    "bookmark {} ({:?}): a value is not finite",
                    i + 1,
                    b.name
                ));
            }
            if !(b.yfov > 0.0 && b.yfov < std::f32::consts::PI) || b.distance < 0.0 {
                return Err(format!(
                    "bookmark {} ({:?}): field of view or distance out of range",
                    i + 1,
                    b.name
                ));
            }
            if b.name.chars().count() > 200 {
                return Err(format!(
                    "bookmark {}: name longer than 200 characters",
                    i + 1
                ));
            }
        }
        Ok(())
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

    /// Oversized, endless, non-regular and nonsensical files are one-line errors, never a hang.
    #[test]
    fn bad_and_oversized_files_are_refused_quickly() {
        let dir = std::env::temp_dir().join(format!("fvpl-bookmarks-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let one_line = |p: &Path| {
            // A hang guard (a FIFO opened without a writer blocks), not a speed test: the load
            // runs on its own thread and must answer within 60 s.
            let (tx, rx) = std::sync::mpsc::channel();
            let owned = p.to_path_buf();
            std::thread::spawn(move || {
                let _ = tx.send(format!("{:#}", BookmarksFile::load(&owned).unwrap_err()));
            });
            let e = rx
                .recv_timeout(std::time::Duration::from_secs(60))
                .expect("the load hangs");
            assert!(
                !e.contains('\n') && e.contains(&p.display().to_string()),
                "{e}"
            );
            e
        };
        let big = dir.join("big.json");
        std::fs::write(&big, vec![b' '; MAX_FILE_BYTES as usize + 1]).unwrap();
        assert!(one_line(&big).contains("bytes"));
        // A directory, and a FIFO (opening one without a writer would block).
        assert!(one_line(&dir).contains("not a regular file"));
        let fifo = dir.join("fifo.json");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            assert!(one_line(&fifo).contains("not a regular file"));
        }
        let bad = |name: &str, json: &str| {
            let p = dir.join(name);
            std::fs::write(&p, json).unwrap();
            one_line(&p)
        };
        let mark = |eye: &str, yfov: &str| {
            format!(r#"{{"name":"a","eye":{eye},"yaw":0,"pitch":0,"yfov":{yfov},"distance":1}}"#)
        };
        let file = |marks: Vec<String>| format!(r#"{{"bookmarks":[{}]}}"#, marks.join(","));
        // 1e39 is past f32: serde_json reads it as infinity.
        assert!(bad("huge.json", &file(vec![mark("[0,0,1e39]", "0.8")])).contains("not finite"));
        assert!(bad("text.json", "{\"bookmarks\": 3}").contains("not a fuzzy-vpl"));
        assert!(bad("fov.json", &file(vec![mark("[0,0,0]", "0")])).contains("out of range"));
        let many = file(
            (0..=MAX_BOOKMARKS)
                .map(|_| mark("[0,0,0]", "0.8"))
                .collect(),
        );
        assert!(bad("many.json", &many).contains("bookmarks, more than"));
        // A good file still loads.
        let good = dir.join("good.json");
        std::fs::write(&good, file(vec![mark("[1,2,3]", "0.8")])).unwrap();
        assert_eq!(BookmarksFile::load(&good).unwrap().bookmarks.len(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bookmarks_round_trip_through_the_file() {
        let dir = std::env::temp_dir().join(format!("fuzzy-vpl-bookmarks-{}", std::process::id()));
        let scene = dir.join("room.glb");
        let path = bookmarks_path(scene.to_str().unwrap()).unwrap();
        assert_eq!(path, dir.join("room.glb.fuzzy-vpl.json"));
        assert_eq!(
            BookmarksFile::load(&path).unwrap(),
            BookmarksFile::default()
        );
        let cam = ViewCamera {
            eye: Vec3::new(1.0, -2.5, 3.25),
            yaw: 0.5,
            pitch: -0.25,
            yfov: 0.9,
            distance: 4.0,
        };
        let s = BookmarksFile {
            bookmarks: vec![
                Bookmark::new("door".into(), &cam),
                Bookmark::new("ceiling".into(), &ViewCamera { yaw: -3.0, ..cam }),
            ],
        };
        s.save(&path).unwrap();
        let back = BookmarksFile::load(&path).unwrap();
        assert_eq!(back, s);
        assert_eq!(back.bookmarks[0].camera(), cam);
        std::fs::write(&path, "{ not json").unwrap();
        assert!(BookmarksFile::load(&path).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn builtin_bookmarks_go_to_the_config_dir() {
        let p = bookmarks_path("builtin:cornell");
        if let Some(p) = p {
            assert!(
                p.ends_with("fuzzy-vpl/builtin-cornell.json"),
                "{}",
                p.display()
            );
        }
    }
}
