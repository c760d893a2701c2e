//! A scene and its BVH resident on the GPU: triangles, materials, point lights, nodes and primitive
//! references.
//! CPU-built trees are uploaded once; GPU builders write `nodes`/`prim_indices` in place each frame.

use crate::bvh::{Bvh, BvhNode};
use crate::gpu::{read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext};
use crate::scene::{PointLight, Scene};
use crate::{Error, Result};

pub struct GpuScene {
    pub triangles: wgpu::Buffer,
    pub materials: wgpu::Buffer,
    /// The scene's point lights (one zeroed entry when it has none).
    pub lights: wgpu::Buffer,
    pub light_count: u32,
    pub nodes: wgpu::Buffer,
    pub prim_indices: wgpu::Buffer,
    pub triangle_count: u32,
    /// Nodes of the current tree (written by the last build).
    pub node_count: u32,
    /// Entries of `prim_indices` used by the current tree.
    pub prim_count: u32,
}

impl GpuScene {
    /// Uploads `scene` with a CPU-built `bvh`. Fails with a clear error when a buffer exceeds the
    /// device's binding limits or the scene is empty.
    pub fn upload(ctx: &GpuContext, scene: &Scene, bvh: &Bvh) -> Result<Self> {
        if bvh.nodes.is_empty() {
            return Err(Error::EmptyScene(scene.name.clone()));
        }
        let mut gpu = Self::upload_geometry(ctx, scene)?;
        gpu.nodes = storage_buffer(ctx, "bvh nodes", &bvh.nodes)?;
        gpu.prim_indices = storage_buffer(ctx, "prim indices", &bvh.prim_indices)?;
        gpu.node_count = bvh.nodes.len() as u32;
        gpu.prim_count = bvh.prim_indices.len() as u32;
        Ok(gpu)
    }

    /// Uploads triangles, materials and lights with empty (one-element) tree buffers: GPU builders size
    /// them on their first build.
    pub fn upload_geometry(ctx: &GpuContext, scene: &Scene) -> Result<Self> {
        if scene.triangles.is_empty() {
            return Err(Error::EmptyScene(scene.name.clone()));
        }
        let triangle_count = u32::try_from(scene.triangles.len())
            .map_err(|_| Error::SceneTooLarge(format!("{} triangles", scene.triangles.len())))?;
        Ok(Self {
            triangles: storage_buffer(ctx, "triangles", &scene.triangles)?,
            materials: storage_buffer(ctx, "materials", &scene.materials)?,
            lights: if scene.lights.is_empty() {
                storage_buffer_zeroed(ctx, "lights", std::mem::size_of::<PointLight>() as u64)?
            } else {
                storage_buffer(ctx, "lights", &scene.lights)?
            },
            light_count: u32::try_from(scene.lights.len())
                .map_err(|_| Error::SceneTooLarge(format!("{} lights", scene.lights.len())))?,
            nodes: storage_buffer_zeroed(ctx, "bvh nodes", std::mem::size_of::<BvhNode>() as u64)?,
            prim_indices: storage_buffer_zeroed(ctx, "prim indices", 4)?,
            triangle_count,
            node_count: 0,
            prim_count: 0,
        })
    }

    /// Reads the current tree back (for validation, SAH and export).
    pub fn download_bvh(&self, ctx: &GpuContext) -> Result<Bvh> {
        Ok(Bvh {
            nodes: read_buffer(ctx, &self.nodes, self.node_count as usize)?,
            prim_indices: read_buffer(ctx, &self.prim_indices, self.prim_count as usize)?,
        })
    }
}
