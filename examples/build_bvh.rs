//! treelet as a library: build a BVH on the GPU over triangles that already live in your own wgpu
//! buffer, and trace a batch of rays through it.
//!
//! ```text
//! cargo run --release --no-default-features --example build_bvh
//! ```
//!
//! The caller opens its own device (with the limits treelet's kernels need) and writes its
//! triangles into a buffer of its own, in treelet's 48-byte `Triangle` layout. treelet wraps both
//! (`GpuContext::from_device`, `Geometry::from_buffer`), records a TRBVH build into a `Recorder`
//! (nothing runs until the recording is submitted: a renderer records its frame around it) and
//! traces rays with `closest_hits`. The example checks the tree with the validator and the hits
//! against a brute-force CPU oracle, and exits with an error on any difference (CI runs it).

use std::time::Instant;

use glam::Vec3;
use treelet::bvh::treelet::{TrbvhBuilder, TreeletSettings};
use treelet::bvh::{sah_cost, validate, SahParams};
use treelet::device::{Geometry, Tree};
use treelet::geometry::Ray;
use treelet::gpu::{instance_flags, GpuContext, ParamSlab, Recorder};
use treelet::scene::{Material, Triangle};
use treelet::trace::{brute_force_closest_hit, closest_hits};
use wgpu::util::DeviceExt;

/// A wavy terrain of `cells`² quads over [-1, 1]², two triangles each.
fn terrain(cells: u32) -> Vec<Triangle> {
    let point = |i: u32, j: u32| {
        let (x, z) = (
            2.0 * i as f32 / cells as f32 - 1.0,
            2.0 * j as f32 / cells as f32 - 1.0,
        );
        Vec3::new(x, 0.1 * (7.0 * x).sin() * (5.0 * z).cos(), z)
    };
    let mut triangles = Vec::with_capacity(2 * (cells * cells) as usize);
    for i in 0..cells {
        for j in 0..cells {
            let (a, b, c, d) = (
                point(i, j),
                point(i + 1, j),
                point(i + 1, j + 1),
                point(i, j + 1),
            );
            triangles.push(Triangle::new(a, b, c, 0));
            triangles.push(Triangle::new(a, c, d, 0));
        }
    }
    triangles
}

/// Rays from above aimed at a grid of points on the terrain's plane, tilted a little.
fn rays(count_per_side: u32) -> Vec<Ray> {
    let mut rays = Vec::new();
    for i in 0..count_per_side {
        for j in 0..count_per_side {
            let s = (i as f32 + 0.5) / count_per_side as f32 * 2.2 - 1.1;
            let t = (j as f32 + 0.5) / count_per_side as f32 * 2.2 - 1.1;
            let origin = Vec3::new(s * 0.5, 2.0, t * 0.5);
            rays.push(Ray::new(
                origin,
                Vec3::new(s, 0.0, t) - origin,
                0.0,
                f32::MAX,
            ));
        }
    }
    rays
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The caller's device and buffer; the instance without wgpu's validation of indirect
    // dispatch arguments (`instance_flags`), which would add a dispatch to each of the builder's
    // indirect ones.
    let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    descriptor.flags = instance_flags();
    let instance = wgpu::Instance::new(descriptor);
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("my renderer"),
        required_limits: GpuContext::required_limits(),
        ..Default::default()
    }))?;
    let triangles = terrain(200);
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("my triangles"),
        contents: bytemuck::cast_slice(&triangles),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    });

    // treelet on top of them.
    let ctx = GpuContext::from_device(adapter, device, queue)?;
    println!("device: {}", ctx.adapter_description());
    let material = Material {
        albedo: [0.7; 3],
        _pad0: 0.0,
        emission: [0.0; 3],
        _pad1: 0.0,
    };
    let geometry = Geometry::from_buffer(&ctx, buffer, triangles.len() as u32, &[material])?;
    let sah = SahParams::default();
    let mut builder = TrbvhBuilder::new(&ctx, TreeletSettings::BALANCED, sah)?;
    let mut tree = Tree::empty(&ctx)?;
    let mut params = ParamSlab::new(&ctx);
    // The first build compiles the kernels; a renderer rebuilds every frame, as the second does.
    for build in ["first", "second"] {
        let start = Instant::now();
        let mut rec = Recorder::new(&ctx, &mut params, None);
        builder.record(&mut rec, &geometry, &mut tree)?;
        rec.submit();
        ctx.device.poll(wgpu::PollType::wait_indefinitely())?;
        println!(
            "{build} build: TRBVH over {} triangles in {:.1} ms",
            triangles.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
    }

    let rays = rays(64);
    let hits = closest_hits(&ctx, &geometry, &tree, &rays)?;

    // Checks: a valid tree, and the hits of brute force.
    let bvh = tree.download(&ctx)?;
    let stats = validate(&bvh, &triangles)?;
    println!(
        "tree: {} nodes, {} leaves, SAH {:.2}",
        bvh.nodes.len(),
        stats.leaves,
        sah_cost(&bvh, &sah)
    );
    let mut hit_count = 0;
    for (ray, hit) in rays.iter().zip(&hits) {
        let oracle = brute_force_closest_hit(&triangles, ray);
        if hit.is_hit() != oracle.is_hit()
            || (hit.is_hit() && (hit.t - oracle.t).abs() > 1e-5 * oracle.t.max(1.0))
        {
            return Err(format!("ray {ray:?}: GPU hit {hit:?}, brute force {oracle:?}").into());
        }
        hit_count += usize::from(hit.is_hit());
    }
    println!(
        "traced {} rays: {hit_count} hits, all equal to brute force",
        rays.len()
    );
    Ok(())
}
