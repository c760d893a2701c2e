//! Whole-window screenshots (image and panel): the frame is drawn a second time into an offscreen
//! texture of the surface's format, which is copied to a buffer, read back and written as PNG.
//! Also the timestamped file names of the Screenshot button.

use std::path::PathBuf;

use crate::gpu::{read_buffer, GpuContext};
use crate::{Error, Result};

/// An offscreen copy of one frame, drawn like the surface and then read back.
pub struct Capture {
    texture: wgpu::Texture,
    buffer: wgpu::Buffer,
    padded_row: u32,
}

impl Capture {
    /// A capture target of `size` in `format` (8-bit RGBA or BGRA, sRGB or not).
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat, size: (u32, u32)) -> Result<Self> {
        if !matches!(
            format,
            wgpu::TextureFormat::Rgba8Unorm
                | wgpu::TextureFormat::Rgba8UnormSrgb
                | wgpu::TextureFormat::Bgra8Unorm
                | wgpu::TextureFormat::Bgra8UnormSrgb
        ) {
            return Err(Error::Gpu(format!(
                "screenshots need an 8-bit RGBA/BGRA surface, this one is {format:?}"
            )));
        }
        let (width, height) = (size.0.max(1), size.1.max(1));
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let padded_row = (width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot pixels"),
            size: u64::from(padded_row) * u64::from(height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Ok(Self {
            texture,
            buffer,
            padded_row,
        })
    }

    pub fn view(&self) -> wgpu::TextureView {
        self.texture.create_view(&Default::default())
    }

    /// Records the copy of the drawn texture into the read-back buffer; call after drawing.
    pub fn record_copy(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: None,
                },
            },
            self.texture.size(),
        );
    }

    /// Reads the copied frame back (after the submission with `record_copy`) as RGBA.
    pub fn read(&self, ctx: &GpuContext) -> Result<image::RgbaImage> {
        let (width, height) = (self.texture.width(), self.texture.height());
        let bytes: Vec<u8> = read_buffer(
            ctx,
            &self.buffer,
            self.padded_row as usize * height as usize,
        )?;
        let bgra = matches!(
            self.texture.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let mut rgba = Vec::with_capacity(width as usize * height as usize * 4);
        for row in bytes.chunks_exact(self.padded_row as usize) {
            for px in row[..width as usize * 4].chunks_exact(4) {
                let (r, b) = if bgra { (px[2], px[0]) } else { (px[0], px[2]) };
                // The window is opaque: ignore whatever alpha the compositor format carries.
                rgba.extend_from_slice(&[r, px[1], b, 255]);
            }
        }
        image::RgbaImage::from_raw(width, height, rgba)
            .ok_or_else(|| Error::Gpu("screenshot buffer has the wrong size".into()))
    }
}

/// `treelet-YYYYMMDD-HHMMSS.png` (UTC) in the current directory.
pub fn timestamped_path(unix_seconds: u64) -> PathBuf {
    let days = (unix_seconds / 86_400) as i64;
    let secs = unix_seconds % 86_400;
    let (year, month, day) = civil_from_days(days);
    PathBuf::from(format!(
        "treelet-{year:04}{month:02}{day:02}-{:02}{:02}{:02}.png",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    ))
}

/// Gregorian (year, month, day) of a day count since 1970-01-01 (H. Hinnant's algorithm).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamps_name_files_in_utc() {
        assert_eq!(
            timestamped_path(0),
            PathBuf::from("treelet-19700101-000000.png")
        );
        // 2024-02-29 13:45:07 UTC (a leap day).
        assert_eq!(
            timestamped_path(1_709_214_307),
            PathBuf::from("treelet-20240229-134507.png")
        );
    }
}
