//! The one error type of the render stage.

use std::path::PathBuf;

/// What can go wrong while reading frames, drawing or saving a picture.
///
/// Every variant says what to fix; none is raised by a panic.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// A file or directory could not be read or written (the system's
    /// message is the source, not repeated in this one's).
    /// Fix: check that the path exists and is readable (or its directory writable).
    #[error("{}: cannot read or write", path.display())]
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// An input file is not one that can be read: not a regular file (a
    /// directory, device, pipe or socket) or larger than
    /// [`super::MAX_OBJ_FILE_BYTES`]. Fix: give a regular OBJ file.
    #[error("{}: {message}", path.display())]
    Input {
        /// The file.
        path: PathBuf,
        /// What is wrong and what would be valid.
        message: String,
    },
    /// A line of an OBJ file is malformed (bad number, index out of range, ...).
    /// Fix: the message names the file, the 1-based line and what is wrong.
    #[error("{file}:{line}: {message}")]
    Parse {
        /// The file (or source name given to the parser).
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong with the line.
        message: String,
    },
    /// Geometry built in code is inconsistent (e.g. a triangle index past the vertex list).
    #[error("invalid geometry in object '{object}': {message}")]
    InvalidData {
        /// Name of the object.
        object: String,
        /// What is wrong.
        message: String,
    },
    /// There is nothing to draw: no vertices, no frames.
    #[error("nothing to draw: {what}")]
    Empty {
        /// What was empty.
        what: String,
    },
    /// An option is out of range; the message says what is allowed.
    #[error("bad render option {option}: {message}")]
    BadOption {
        /// The option's name (e.g. `width`).
        option: &'static str,
        /// What was given and what is allowed.
        message: String,
    },
    /// The GIF encoder failed (an animation, [`super::render_run_animation`]).
    #[error("{}: cannot encode GIF", path.display())]
    EncodeGif {
        /// The run directory animated.
        path: PathBuf,
        /// The encoder's error.
        #[source]
        source: gif::EncodingError,
    },
    /// The PNG encoder failed for a reason other than I/O.
    #[error("{}: cannot encode PNG", path.display())]
    Encode {
        /// The file being written.
        path: PathBuf,
        /// The encoder's error.
        #[source]
        source: image::ImageError,
    },
}

impl RenderError {
    /// An [`RenderError::Io`] for `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        RenderError::Io {
            path: path.into(),
            source,
        }
    }

    /// A [`RenderError::BadOption`].
    pub(crate) fn option(option: &'static str, message: impl Into<String>) -> Self {
        RenderError::BadOption {
            option,
            message: message.into(),
        }
    }

    /// A [`RenderError::Empty`].
    pub(crate) fn empty(what: impl Into<String>) -> Self {
        RenderError::Empty { what: what.into() }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn error_is_send_sync_static() {
        // So that callers (e.g. a CLI flag parser) can box and pass it across threads.
        fn check<T: std::error::Error + Send + Sync + 'static>() {}
        check::<super::RenderError>();
    }

    /// The system's message is the source and is not repeated in the
    /// error's own (the chain printed it twice).
    #[test]
    fn io_error_does_not_repeat_its_source() {
        let e = super::RenderError::io(
            "f.obj",
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        );
        assert_eq!(e.to_string(), "f.obj: cannot read or write");
        let source = std::error::Error::source(&e).map(|s| s.to_string());
        assert_eq!(source.as_deref(), Some("no such file"));
    }
}
