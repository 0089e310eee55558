//! Frames of a run directory, whatever its layout: one OBJ file per object
//! and frame (`frames/<stem>/<stem>_00000.obj`, what `opsim run` writes),
//! one OBJ file per frame (`frames/frame_00000.obj`, older runs), or a
//! folder of numbered OBJ files (one sequence).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::error::RenderError;
use super::obj::ObjData;

/// One frame: its number (from the file names; `None` when a file has
/// none) and its OBJ files, one per object.
pub(crate) type FrameSet = (Option<u64>, Vec<PathBuf>);

/// The frames under `dir`, in frame order: its `*.obj` files, one frame
/// each, when it has any; else the numbered files of its subfolders, the
/// files with the same number making one frame; else the same in
/// `dir/frames`.
///
/// # Errors
/// [`RenderError::Io`] if a folder cannot be read; [`RenderError::Empty`]
/// if no OBJ file is found.
pub(crate) fn frame_sets(dir: &Path) -> Result<Vec<FrameSet>, RenderError> {
    let mut sets = in_folder(dir)?;
    let sub = dir.join("frames");
    if sets.is_empty() && sub.is_dir() {
        sets = in_folder(&sub)?;
    }
    if sets.is_empty() {
        return Err(RenderError::empty(format!(
            "no .obj files in {}, {} or their subfolders",
            dir.display(),
            sub.display()
        )));
    }
    Ok(sets)
}

/// Frame `k` (the number in its file names) of the run directory `dir`,
/// all objects in one [`ObjData`].
///
/// # Errors
/// [`RenderError::Io`] if a folder cannot be read, [`RenderError::Empty`]
/// when no OBJ file is found or none has number `k`, and
/// [`ObjData::read`]'s errors.
pub fn read_run_frame(dir: &Path, k: u64) -> Result<ObjData, RenderError> {
    let sets = frame_sets(dir)?;
    let (_, files) = sets
        .iter()
        .find(|(n, _)| *n == Some(k))
        .ok_or_else(|| RenderError::empty(format!("no frame {k} in {}", dir.display())))?;
    read_frame(files)
}

/// The up direction, in scene coordinates (z-up), of the run that holds
/// `path` (a run directory, its `frames` folder, a sequence folder or a
/// frame file): the `up` of the first `summary.json` found in `path` or
/// up to three folders above it. `None` when there is none, or it has no
/// valid `up`.
pub fn run_up_axis(path: &Path) -> Option<[f64; 3]> {
    run_direction(path, "up")
}

/// The view direction, in scene coordinates, of the run that holds `path`
/// (as [`run_up_axis`]): the `view` of its `summary.json` (the scene's
/// `outputs.view`). `None` when there is none or it is not valid.
pub fn run_view_axis(path: &Path) -> Option<[f64; 3]> {
    run_direction(path, "view")
}

/// The frame rate (frames per unit of scene time) of the run that holds
/// `path` (as [`run_up_axis`]): the `frame_rate` of its `summary.json`.
/// `None` when there is none, or it is not finite and positive.
pub fn run_frame_rate(path: &Path) -> Option<f64> {
    run_summary(path, |v| {
        v.get("frame_rate")?
            .as_f64()
            .filter(|r| r.is_finite() && *r > 0.0)
    })
}

/// What `read` finds in the first `summary.json` in `path` or up to three
/// folders above it.
fn run_summary<T>(path: &Path, read: impl Fn(&serde_json::Value) -> Option<T>) -> Option<T> {
    let start = if path.is_dir() { path } else { path.parent()? };
    start.ancestors().take(4).find_map(|dir| {
        let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
        let v: serde_json::Value = serde_json::from_str(&text).ok()?;
        read(&v)
    })
}

/// The direction `key` of the first `summary.json` in `path` or up to three
/// folders above it.
fn run_direction(path: &Path, key: &str) -> Option<[f64; 3]> {
    run_summary(path, |v| {
        let up = v.get(key)?.as_array()?;
        let c: Vec<f64> = up.iter().filter_map(serde_json::Value::as_f64).collect();
        let up = <[f64; 3]>::try_from(c).ok()?;
        let n = (up[0] * up[0] + up[1] * up[1] + up[2] * up[2]).sqrt();
        (n.is_finite() && n > 0.0).then_some(up)
    })
}

/// All objects of `files` in one [`ObjData`], in file order.
pub(crate) fn read_frame(files: &[PathBuf]) -> Result<ObjData, RenderError> {
    let mut data = ObjData::default();
    for f in files {
        for o in ObjData::read(f)?.objects() {
            data.push_object(o.clone());
        }
    }
    Ok(data)
}

/// The frames of one folder: its OBJ files one frame each (numeric
/// order), or when it has none the numbered OBJ files of its subfolders
/// grouped by number (subfolders in name order).
fn in_folder(dir: &Path) -> Result<Vec<FrameSet>, RenderError> {
    let (files, subfolders) = entries(dir)?;
    if !files.is_empty() {
        let mut files = files;
        files.sort_by_cached_key(|p| sort_key(p));
        return Ok(files
            .into_iter()
            .map(|f| (frame_number(&f), vec![f]))
            .collect());
    }
    let mut by_number: BTreeMap<u64, Vec<PathBuf>> = BTreeMap::new();
    let mut subfolders = subfolders;
    subfolders.sort();
    for sub in subfolders {
        let (mut files, _) = entries(&sub)?;
        files.sort_by_cached_key(|p| sort_key(p));
        for f in files {
            if let Some(n) = frame_number(&f) {
                by_number.entry(n).or_default().push(f);
            }
        }
    }
    Ok(by_number.into_iter().map(|(n, f)| (Some(n), f)).collect())
}

/// The `*.obj` regular files and the subfolders of `dir`.
fn entries(dir: &Path) -> Result<(Vec<PathBuf>, Vec<PathBuf>), RenderError> {
    let list = std::fs::read_dir(dir).map_err(|e| RenderError::io(dir, e))?;
    let (mut files, mut folders) = (Vec::new(), Vec::new());
    for entry in list {
        let path = entry.map_err(|e| RenderError::io(dir, e))?.path();
        let is_obj = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if is_obj && path.is_file() {
            files.push(path);
        } else if path.is_dir() {
            folders.push(path);
        }
    }
    Ok((files, folders))
}

/// The trailing number of a file stem (`frame_00012.obj` -> 12).
pub(crate) fn frame_number(path: &Path) -> Option<u64> {
    let stem = path.file_stem()?.to_str()?;
    let digits = stem.len() - stem.trim_end_matches(|c: char| c.is_ascii_digit()).len();
    stem[stem.len() - digits..].parse().ok()
}

/// Sort key: stem without its trailing number, the number, then the full name.
pub(crate) fn sort_key(path: &Path) -> (String, Option<u64>, String) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = path
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let prefix = stem
        .trim_end_matches(|c: char| c.is_ascii_digit())
        .to_string();
    (prefix, frame_number(path), name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_object_folders_group_by_frame_number() {
        let dir = std::env::temp_dir().join(format!("op-run-dir-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for (stem, k) in [("a", 0), ("a", 1), ("b", 0), ("b", 1)] {
            let folder = dir.join("frames").join(stem);
            std::fs::create_dir_all(&folder).unwrap();
            std::fs::write(
                folder.join(format!("{stem}_{k:05}.obj")),
                format!("o {stem}\nv {k} 0 0\n"),
            )
            .unwrap();
        }
        let sets = frame_sets(&dir).unwrap();
        assert_eq!(sets.len(), 2);
        assert_eq!(sets[1].0, Some(1));
        let frame = read_run_frame(&dir, 1).unwrap();
        let names: Vec<&str> = frame.objects().iter().map(|o| o.name()).collect();
        assert_eq!(names, ["a", "b"]);
        assert_eq!(frame.objects()[1].vertices()[0][0], 1.0);
        assert!(read_run_frame(&dir, 7).is_err());
        // One sequence folder: one file per frame.
        assert_eq!(frame_sets(&dir.join("frames/a")).unwrap().len(), 2);
        // The run's up axis, found from a frame file three folders down.
        assert_eq!(run_up_axis(&dir.join("frames/a/a_00000.obj")), None);
        std::fs::write(dir.join("summary.json"), r#"{"up": [0, -1, 0]}"#).unwrap();
        assert_eq!(
            run_up_axis(&dir.join("frames/a/a_00000.obj")),
            Some([0.0, -1.0, 0.0])
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
