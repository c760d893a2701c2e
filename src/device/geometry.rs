//! A scene's geometry on the GPU: triangles (the 48-byte `Triangle` layout), materials and point
//! lights. Uploaded once from a `Scene`, or wrapped around buffers the caller already has;
//! animations rewrite the triangles in place (same count).

use crate::gpu::{read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext};
use crate::scene::{Material, PointLight, Scene, Triangle};
use crate::{Error, Result};

pub struct Geometry {
    pub triangles: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    /// The point lights (one zeroed entry when there are none).
    pub lights: wgpu::Buffer,
    pub triangle_count: u32,
    pub light_count: u32,
}

impl Geometry {
    /// Uploads `scene`'s triangles, materials and lights. Fails with a clear error on an empty
    /// scene or when a buffer exceeds the device's binding limits.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        if scene.triangles.is_empty() {
            return Err(Error::EmptyScene(scene.name.clone()));
        }
        let triangle_count = u32::try_from(scene.triangles.len())
            .map_err(|_| Error::SceneTooLarge(format!("{} triangles", scene.triangles.len())))?;
        let light_count = u32::try_from(scene.lights.len())
            .map_err(|_| Error::SceneTooLarge(format!("{} lights", scene.lights.len())))?;
        Ok(Self {
            triangles: storage_buffer(ctx, "triangles", &scene.triangles)?,
            materials: storage_buffer(ctx, "materials", &scene.materials)?,
            lights: lights_buffer(ctx, &scene.lights)?,
            triangle_count,
            light_count,
        })
    }

    /// Geometry over a buffer the caller already has: `triangle_count` triangles in the
    /// `Triangle` layout (48 bytes each; the buffer needs `STORAGE` usage), every material index
    /// pointing into `materials` (at least one), no point lights.
    pub fn from_buffer(
        ctx: &GpuContext,
        triangles: wgpu::Buffer,
        triangle_count: u32,
        materials: &[Material],
    ) -> Result<Self> {
        if triangle_count == 0 {
            return Err(Error::InvalidArgument("geometry of zero triangles".into()));
        }
        let needed = u64::from(triangle_count) * std::mem::size_of::<Triangle>() as u64;
        if triangles.size() < needed || !triangles.usage().contains(wgpu::BufferUsages::STORAGE) {
            return Err(Error::InvalidArgument(format!(
                "a buffer of {triangle_count} triangles needs {needed} bytes and STORAGE usage; \
                 this one has {} bytes and {:?}",
                triangles.size(),
                triangles.usage()
            )));
        }
        if materials.is_empty() {
            return Err(Error::InvalidArgument(
                "geometry needs at least one material".into(),
            ));
        }
        Ok(Self {
            triangles,
            materials: storage_buffer(ctx, "materials", materials)?,
            lights: lights_buffer(ctx, &[])?,
            triangle_count,
            light_count: 0,
        })
    }

    /// Replaces the triangles by `triangles` (the same count; animations evaluated on the CPU).
    pub fn write_triangles(&self, ctx: &GpuContext, triangles: &[Triangle]) -> Result<()> {
        if triangles.len() != self.triangle_count as usize {
            return Err(Error::InvalidArgument(format!(
                "{} triangles for geometry of {}",
                triangles.len(),
                self.triangle_count
            )));
        }
        ctx.queue
            .write_buffer(&self.triangles, 0, bytemuck::cast_slice(triangles));
        Ok(())
    }

    /// Reads the triangles back (tests, CPU reference builders over animated geometry).
    pub fn read_triangles(&self, ctx: &GpuContext) -> Result<Vec<Triangle>> {
        read_buffer(ctx, &self.triangles, self.triangle_count as usize)
    }
}

fn lights_buffer(ctx: &GpuContext, lights: &[PointLight]) -> Result<wgpu::Buffer> {
    if lights.is_empty() {
        storage_buffer_zeroed(ctx, "lights", std::mem::size_of::<PointLight>() as u64)
    } else {
        storage_buffer(ctx, "lights", lights)
    }
}
