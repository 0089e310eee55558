//! Series files: a sequence's frame files with their scene times, in
//! ParaView's file-series JSON (`{"file-series-version": "1.0", "files":
//! [{"name": ..., "time": ...}, ...]}`, names relative to the series file).
//! ParaView opens `<stem>.<extension>.series` as one time series whatever
//! reader the files take (its VTK XML, PLY and OBJ readers among them);
//! other tools read the JSON to load a sequence in order with its times.
//!
//! The frame writer rewrites a sequence's series file after each of its
//! frames, on the file thread after that frame's file
//! ([`super::file_queue`]), atomically ([`super::write_atomically`]): a
//! run stopped at any moment leaves series files that list only files
//! already on disk.

use std::io::Write;

use op_dynamics::Real;
use serde::Serialize;

/// ParaView's `.series` file: the frame files and their times.
#[derive(Serialize)]
struct Series<'a> {
    #[serde(rename = "file-series-version")]
    version: &'static str,
    files: Vec<SeriesFile<'a>>,
}

#[derive(Serialize)]
struct SeriesFile<'a> {
    name: &'a str,
    time: Real,
}

/// Writes the `.series` JSON of `files` (name relative to the series file,
/// scene time), in the order given.
pub fn write(files: &[(String, Real)], w: &mut dyn Write) -> std::io::Result<()> {
    let series = Series {
        version: "1.0",
        files: files
            .iter()
            .map(|(name, time)| SeriesFile { name, time: *time })
            .collect(),
    };
    serde_json::to_writer_pretty(&mut *w, &series).map_err(std::io::Error::other)?;
    writeln!(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_files_and_times_in_order() {
        let mut bytes = Vec::new();
        write(
            &[("a_00000.ply".into(), 0.0), ("a_00001.ply".into(), 0.5)],
            &mut bytes,
        )
        .unwrap();
        let v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
        assert_eq!(v["file-series-version"], "1.0");
        assert_eq!(v["files"][1]["name"], "a_00001.ply");
        assert_eq!(v["files"][1]["time"], 0.5);
    }
}
