//! All-or-nothing output: a report is written into a staging directory beside its
//! destination and renamed into place only when every file is complete.
//!
//! A run that fails (a file that cannot be written, a full disk, an error in a
//! configuration) removes its staging directory and leaves the previous report
//! untouched; a run that succeeds replaces the previous report as a whole, so no
//! file of an earlier run survives. The replacement takes two renames in the same
//! parent directory (previous report aside, new report in), then the previous
//! report is deleted.
//!
//! An existing destination is replaced only when it is empty or holds nothing but
//! files a report writes (see [`is_report_file`]) and the backend's `rendered/`
//! directory of PNG images: `--out` pointed at a directory of other files is
//! refused, never emptied. `rendered/` is not the report's: it is carried over into
//! the new report as it is.

use std::path::{Path, PathBuf};

use crate::EvalError;

/// A staging directory for one report; removed on drop unless committed.
#[derive(Debug)]
pub(super) struct Staging {
    dir: PathBuf,
    target: PathBuf,
    committed: bool,
}

/// Whether `name` is a file `compare` writes (so replacing it loses no user data).
#[must_use]
pub(super) fn is_report_file(name: &str) -> bool {
    matches!(
        name,
        "report.md"
            | "metrics.csv"
            | "references.csv"
            | "legend.png"
            | "index.html"
            | "colorbar.svg"
            | "sweep.svg"
    ) || (name.ends_with(".png") && (name.starts_with("heatmap_") || name.starts_with("mask_")))
        || (name.ends_with(".svg") && name.starts_with("aliasing_"))
}

/// The directory of a report where `render_scene` (the wgpu example) writes its
/// images; carried over from one report to the next.
pub(super) const RENDERED: &str = "rendered";

/// The PNG files of `report/rendered`, as paths relative to `report`, sorted; empty
/// when there is none.
pub(super) fn rendered_images(report: &Path) -> Vec<String> {
    let Ok(entries) = std::fs::read_dir(report.join(RENDERED)) else {
        return Vec::new();
    };
    let mut names: Vec<String> = entries
        .filter_map(Result::ok)
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .filter_map(|e| e.file_name().to_str().map(str::to_string))
        .filter(|n| n.ends_with(".png") && !n.contains(['"', '<', '>', '&']))
        .map(|n| format!("{RENDERED}/{n}"))
        .collect();
    names.sort();
    names
}

/// Whether `dir` holds only PNG files (the backend's images).
fn holds_only_png(dir: &Path) -> bool {
    std::fs::read_dir(dir).is_ok_and(|entries| {
        entries.filter_map(Result::ok).all(|e| {
            e.file_type().is_ok_and(|t| t.is_file())
                && e.file_name().to_str().is_some_and(|n| n.ends_with(".png"))
        })
    })
}

fn write_error(path: &Path, message: impl Into<String>) -> EvalError {
    EvalError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(message.into()),
    }
}

/// Checks that `target` is absent, or a directory holding only report files and
/// writable.
fn check_target(target: &Path) -> Result<(), EvalError> {
    let meta = match std::fs::symlink_metadata(target) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(EvalError::Write {
                path: target.to_path_buf(),
                source,
            });
        }
    };
    if !meta.is_dir() {
        return Err(write_error(target, "exists and is not a directory"));
    }
    let entries = std::fs::read_dir(target).map_err(|source| EvalError::Write {
        path: target.to_path_buf(),
        source,
    })?;
    for entry in entries {
        let entry = entry.map_err(|source| EvalError::Write {
            path: target.to_path_buf(),
            source,
        })?;
        let name = entry.file_name();
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        let is_rendered = name == RENDERED
            && entry.file_type().is_ok_and(|t| t.is_dir())
            && holds_only_png(&entry.path());
        if !(is_rendered || is_file && name.to_str().is_some_and(is_report_file)) {
            return Err(write_error(
                target,
                format!(
                    "refusing to replace it: it holds {:?}, which is not a file of a compare \
                     report (move it away or choose another --out)",
                    name
                ),
            ));
        }
    }
    // The previous report must be replaceable: probe a write inside it.
    let probe = target.join(format!(".compare-probe-{}", std::process::id()));
    std::fs::write(&probe, b"").map_err(|source| EvalError::Write {
        path: target.to_path_buf(),
        source,
    })?;
    std::fs::remove_file(&probe).map_err(|source| EvalError::Write {
        path: probe.clone(),
        source,
    })
}

impl Staging {
    /// Checks that `target` can be written or replaced and creates the staging
    /// directory beside it (creating `target`'s missing parents).
    ///
    /// # Errors
    /// [`EvalError::Write`] naming the path and the reason.
    pub(super) fn create(target: &Path) -> Result<Self, EvalError> {
        let name = target
            .file_name()
            .ok_or_else(|| write_error(target, "the output path has no directory name"))?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(|source| EvalError::Write {
            path: parent.clone(),
            source,
        })?;
        check_target(target)?;
        let dir = parent.join(format!(
            ".{}.partial-{}",
            name.to_string_lossy(),
            std::process::id()
        ));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(|source| EvalError::Write {
                path: dir.clone(),
                source,
            })?;
        }
        std::fs::create_dir(&dir).map_err(|source| EvalError::Write {
            path: dir.clone(),
            source,
        })?;
        Ok(Self {
            dir,
            target: target.to_path_buf(),
            committed: false,
        })
    }

    /// Where the files go until [`Staging::commit`].
    pub(super) fn path(&self) -> &Path {
        &self.dir
    }

    /// Puts the finished report in place of `target`, replacing a previous report.
    ///
    /// # Errors
    /// [`EvalError::Write`] when a rename fails; the previous report is then put
    /// back where it was.
    pub(super) fn commit(mut self) -> Result<(), EvalError> {
        let rename_error = |path: &Path, source| EvalError::Write {
            path: path.to_path_buf(),
            source,
        };
        let previous = self.dir.with_file_name(format!(
            "{}.previous",
            self.dir.file_name().unwrap_or_default().to_string_lossy()
        ));
        let had_previous = self.target.exists();
        // The backend's images move into the new report first.
        let kept = self.target.join(RENDERED);
        let carried = self.dir.join(RENDERED);
        let carry = had_previous && kept.is_dir();
        if carry {
            std::fs::rename(&kept, &carried).map_err(|source| rename_error(&kept, source))?;
        }
        if had_previous {
            if let Err(source) = std::fs::rename(&self.target, &previous) {
                if carry {
                    let _ = std::fs::rename(&carried, &kept);
                }
                return Err(rename_error(&self.target, source));
            }
        }
        if let Err(source) = std::fs::rename(&self.dir, &self.target) {
            if had_previous {
                let _ = std::fs::rename(&previous, &self.target);
            }
            if carry {
                let _ = std::fs::rename(&carried, &kept);
            }
            return Err(rename_error(&self.target, source));
        }
        self.committed = true;
        if had_previous {
            std::fs::remove_dir_all(&previous).map_err(|source| rename_error(&previous, source))?;
        }
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rendered_images_are_kept_and_nothing_else_is_taken_for_them() {
        let dir = std::env::temp_dir().join(format!("shadowmap-rendered-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let target = dir.join("report");
        std::fs::create_dir_all(target.join(RENDERED)).unwrap();
        std::fs::write(target.join("report.md"), "old").unwrap();
        std::fs::write(target.join("rendered/lispsm.png"), "png").unwrap();
        assert!(check_target(&target).is_ok());
        assert_eq!(rendered_images(&target), ["rendered/lispsm.png"]);
        let staging = Staging::create(&target).unwrap();
        std::fs::write(staging.path().join("report.md"), "new").unwrap();
        staging.commit().unwrap();
        assert_eq!(
            std::fs::read_to_string(target.join("report.md")).unwrap(),
            "new"
        );
        assert_eq!(
            rendered_images(&target),
            ["rendered/lispsm.png"],
            "carried over"
        );
        // A rendered/ holding anything but PNG files is not the backend's.
        std::fs::write(target.join("rendered/notes.txt"), "mine").unwrap();
        assert!(check_target(&target).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn report_files_are_recognised() {
        for name in [
            "report.md",
            "metrics.csv",
            "legend.png",
            "heatmap_overhead_lispsm.png",
            "mask_overhead_lispsm.png",
            "index.html",
            "colorbar.svg",
            "sweep.svg",
            "aliasing_overhead.svg",
        ] {
            assert!(is_report_file(name), "{name}");
        }
        for name in [
            "notes.txt",
            "heatmap.txt",
            "metrics.csv.bak",
            "photo.png",
            "aliasing.txt",
            "index.htm",
            "",
        ] {
            assert!(!is_report_file(name), "{name}");
        }
    }
}
