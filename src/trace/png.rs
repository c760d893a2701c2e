//! Writing rendered images as PNG files, with write errors that name the file.

use std::path::Path;

use crate::{Error, Result};

/// Writes `image` as a PNG file at `path` (the folder must exist).
pub fn save_png(image: &image::RgbaImage, path: &Path) -> Result<()> {
    image.save(path).map_err(|e| Error::Write {
        path: path.to_path_buf(),
        message: match e {
            image::ImageError::IoError(io) => io.to_string(),
            other => other.to_string(),
        },
    })
}
