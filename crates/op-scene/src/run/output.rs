//! The output directory of a run, made ready before the first frame.

use std::fs;
use std::path::{Path, PathBuf};

use super::{io, RunError};
use crate::export::{layout, Files, FrameFormat};

/// Makes `out_dir` ready for a run: creates it and `folders` (the frame
/// folders, [`crate::export::FrameWriter::folders`]), refuses symbolic links where opsim
/// writes, and removes the files a previous run left there (only the names
/// opsim writes: `summary.json`, `metrics.csv`, `checkpoint.bin`, the sequence files
/// `frames/<stem>/<stem>_<digits>.obj|ply` and `<stem>.obj|ply.series` (and
/// the emptied folders), the older layout's `frames/frame_*.obj`,
/// `vtu/*_<digits>.vtu`, `vtu/*.vtu.series`, `usd/run.usda` and opsim's
/// temporary files: [`crate::export::FileFormat::owns`]), so frames of two
/// runs never mix.
pub fn prepare_output(out_dir: &Path, folders: &[PathBuf]) -> Result<(), RunError> {
    prepare(out_dir, folders, false)
}

/// [`prepare_output`] for a run resumed from a checkpoint
/// ([`super::checkpoint`]): the same checks, but only the temporary files
/// of an interrupted write are removed; the frames, `metrics.csv` and the
/// checkpoint stay (frames after the checkpoint's are written again).
pub(super) fn prepare_resume(out_dir: &Path, folders: &[PathBuf]) -> Result<(), RunError> {
    prepare(out_dir, folders, true)
}

fn prepare(out_dir: &Path, folders: &[PathBuf], resume: bool) -> Result<(), RunError> {
    fs::create_dir_all(out_dir).map_err(io(out_dir))?;
    let frames_dir = out_dir.join("frames");
    let state_dirs: Vec<(FrameFormat, PathBuf)> = FrameFormat::all()
        .filter(|f| matches!(f.files(), Files::State | Files::Run))
        .map(|f| (f, layout::state_folder(out_dir, f)))
        .collect();
    let link = |p: &Path| {
        fs::symlink_metadata(p)
            .map(|m| m.file_type().is_symlink())
            .unwrap_or(false)
    };
    for p in [
        frames_dir.clone(),
        out_dir.join("metrics.csv"),
        out_dir.join("summary.json"),
        out_dir.join(super::checkpoint::FILE),
    ]
    .iter()
    .chain(state_dirs.iter().map(|(_, d)| d))
    .chain(folders)
    {
        if link(p) {
            return Err(RunError::Symlink { path: p.clone() });
        }
    }
    let temporary = crate::export::is_temporary;
    let clean = |dir: &Path, ours: &dyn Fn(&str) -> bool| -> Result<bool, RunError> {
        let Ok(entries) = fs::read_dir(dir) else {
            return Ok(false);
        };
        let mut left = false;
        for e in entries {
            let e = e.map_err(io(dir))?;
            let name = e.file_name().to_string_lossy().into_owned();
            if (ours(&name) && !resume) || temporary(&name) {
                let path = e.path();
                if link(&path) {
                    return Err(RunError::Symlink { path });
                }
                fs::remove_file(&path).map_err(io(&path))?;
            } else {
                left = true;
            }
        }
        Ok(left)
    };
    clean(out_dir, &|name| {
        name == "summary.json" || name == "metrics.csv" || name == super::checkpoint::FILE
    })?;
    for (f, dir) in &state_dirs {
        clean(dir, &|name| f.format().owns(name, ""))?;
    }
    if let Ok(entries) = fs::read_dir(&frames_dir) {
        for e in entries {
            let e = e.map_err(io(&frames_dir))?;
            let path = e.path();
            if !e.file_type().map_err(io(&path))?.is_dir() {
                continue;
            }
            let stem = e.file_name().to_string_lossy().into_owned();
            let left = clean(&path, &|name| {
                FrameFormat::all()
                    .any(|f| f.files() == Files::PerSequence && f.format().owns(name, &stem))
            })?;
            if !left && !resume {
                fs::remove_dir(&path).map_err(io(&path))?;
            }
        }
    }
    clean(&frames_dir, &|name| {
        name.starts_with("frame_") && name.ends_with(".obj")
    })?;
    for dir in folders {
        fs::create_dir_all(dir).map_err(io(dir))?;
    }
    Ok(())
}
