//! The crate's error type: every failure caused by user input ends up here with a readable message.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("malformed OBJ file {path}: {message}")]
    Obj { path: PathBuf, message: String },
    #[error("malformed AFF file {path}, line {line}: {message}")]
    Aff {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("scene '{0}' has no usable triangles")]
    EmptyScene(String),
    #[error("unknown scene '{name}': not a built-in scene name ({known}) and no such file")]
    UnknownScene { name: String, known: String },
    #[error("scene too large for this device: {0}")]
    SceneTooLarge(String),
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    #[error("cannot write {path}: {message}")]
    Write { path: PathBuf, message: String },
}

pub type Result<T> = std::result::Result<T, Error>;

/// `value` if it is one of `allowed`, else a clear error naming `what`.
pub(crate) fn one_of(what: &str, value: u32, allowed: &[u32]) -> Result<u32> {
    if allowed.contains(&value) {
        Ok(value)
    } else {
        Err(Error::InvalidArgument(format!(
            "{what} must be one of {allowed:?}, got {value}"
        )))
    }
}
