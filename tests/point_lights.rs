//! Point lights in the path tracer (next-event estimation with shadow rays): a floor under one
//! light, seen straight from above with primary rays only, shows albedo · intensity · cos θ
//! (through the tonemap) where the light is visible and black where an occluder shadows it;
//! every path vertex traces exactly one shadow ray per light, and the rays are counted (also in
//! workgroups partly outside the image). Both layouts trace every scene, the binary one and the
//! wide one converted from it, to the same image and rays; with and without lights they run
//! different pipelines (`POINT_LIGHTS_OVERRIDE`).

mod common;

use common::{convert_wide, gpu};
use glam::Vec3;
use treelet::bvh::wide::{Layout, WideCollapse};
use treelet::bvh::{build_sweep_sah, SahParams};
use treelet::device::{Geometry, Tree};
use treelet::scene::{Camera, Material, PointLight, Scene, Triangle};
use treelet::trace::{PathTracer, RenderSettings};

const SIZE: u32 = 64;
const SPP: u32 = 4;
const ALBEDO: f32 = 0.5;
const INTENSITY: f32 = 0.2;
const LIGHT: Vec3 = Vec3::new(0.0, 1.0, 0.0);
const FOV_Y: f32 = 30.0;
const EYE_HEIGHT: f32 = 3.0;

fn square(y: f32, half: f32) -> [Triangle; 2] {
    let (a, b) = (Vec3::new(-half, y, -half), Vec3::new(half, y, -half));
    let (c, d) = (Vec3::new(half, y, half), Vec3::new(-half, y, half));
    [Triangle::new(a, b, c, 0), Triangle::new(a, c, d, 0)]
}

/// A 2×2 floor at y = 0 under a light at y = 1, seen from y = 3 looking down (+x to the right of
/// the image, −z up), black sky; with `blocker`, a 0.4×0.4 square at y = 0.5 shadows the floor
/// within |x|, |z| < 0.4.
fn scene(lights: Vec<PointLight>, blocker: bool) -> Scene {
    let mut triangles = square(0.0, 1.0).to_vec();
    if blocker {
        triangles.extend(square(0.5, 0.2));
    }
    Scene {
        name: "point light".into(),
        triangles,
        materials: vec![Material::diffuse(Vec3::splat(ALBEDO))],
        camera: Camera {
            eye: Vec3::new(0.0, EYE_HEIGHT, 0.0),
            target: Vec3::ZERO,
            up: Vec3::new(0.0, 0.0, -1.0),
            fov_y_degrees: FOV_Y,
        },
        sky: Vec3::ZERO,
        lights,
    }
}

/// The image and the rays traced, through the binary layout, after checking that the wide
/// layout traces the same.
fn render(scene: &Scene) -> (image::RgbaImage, u64) {
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    let geometry = Geometry::upload(gpu(), scene).unwrap();
    let mut tree = Tree::upload(gpu(), &bvh).unwrap();
    convert_wide(&geometry, &mut tree, WideCollapse::Greedy);
    let [binary, wide] = [Layout::Binary, Layout::Wide].map(|layout| {
        let settings = RenderSettings {
            width: SIZE,
            height: SIZE,
            max_depth: 1,
            layout,
            ..RenderSettings::default()
        };
        let mut tracer = PathTracer::new(gpu(), settings).unwrap();
        let stats = tracer
            .trace(gpu(), &geometry, &tree, &scene.camera, scene.sky, SPP)
            .unwrap();
        (tracer.read_image(gpu()).unwrap(), stats.rays)
    });
    assert_eq!(binary.1, wide.1, "rays traced, binary against wide");
    assert!(binary.0 == wide.0, "the layouts' images differ");
    binary
}

/// The red byte the tonemap (`image_tonemap.wgsl`: ACES fit, then sRGB) gives radiance `v`.
fn tonemapped(v: f32) -> f32 {
    let aces = ((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14)).clamp(0.0, 1.0);
    let srgb = if aces <= 0.0031308 {
        aces * 12.92
    } else {
        1.055 * aces.powf(1.0 / 2.4) - 0.055
    };
    srgb * 255.0
}

/// The pixel in the middle row whose centre sees the floor at x ≈ `x`, and that floor point's x.
fn pixel_at_floor_x(x: f32) -> (u32, f32) {
    let half_extent = EYE_HEIGHT * (0.5 * FOV_Y).to_radians().tan();
    let column = ((x / half_extent + 1.0) * 0.5 * SIZE as f32).floor() as u32;
    let centre_x = ((column as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0) * half_extent;
    (column, centre_x)
}

#[test]
fn lit_floor_shows_albedo_times_intensity_times_cosine() {
    let light = PointLight::new(LIGHT, Vec3::splat(INTENSITY));
    let (image, rays) = render(&scene(vec![light], false));
    // One primary ray and one shadow ray per path: the light is above every floor point.
    assert_eq!(rays, 2 * u64::from(SIZE * SIZE * SPP));
    for x in [0.0, 0.35, 0.7] {
        let (column, fx) = pixel_at_floor_x(x);
        let cos = 1.0 / (fx * fx + 1.0).sqrt();
        let expected = tonemapped(ALBEDO * INTENSITY * cos);
        let got = f32::from(image.get_pixel(column, SIZE / 2)[0]);
        assert!(
            (got - expected).abs() <= 3.0,
            "floor x = {fx}: pixel {got}, expected {expected}"
        );
    }
}

#[test]
fn occluded_light_leaves_the_floor_black() {
    let light = PointLight::new(LIGHT, Vec3::splat(INTENSITY));
    let (image, rays) = render(&scene(vec![light], true));
    assert_eq!(rays, 2 * u64::from(SIZE * SIZE * SPP));
    // x = 0.3: visible past the blocker (which covers |x| < 0.24 of the floor in this view) but
    // inside its shadow (|x| < 0.4); x = 0.7: lit.
    let (shadowed, _) = pixel_at_floor_x(0.3);
    let (lit, _) = pixel_at_floor_x(0.7);
    assert_eq!(image.get_pixel(shadowed, SIZE / 2)[0], 0, "shadowed floor");
    assert!(image.get_pixel(lit, SIZE / 2)[0] > 50, "lit floor");
}

#[test]
fn without_lights_the_floor_is_black_and_no_shadow_rays_are_traced() {
    let (image, rays) = render(&scene(Vec::new(), false));
    assert_eq!(rays, u64::from(SIZE * SIZE * SPP));
    assert!(image.pixels().all(|p| p[0] == 0), "no light, black sky");
}

/// Every ray is counted where the image's sides are not multiples of the 8x8 workgroups (the
/// tally's last invocation of a workgroup half outside the image adds its rays too): without
/// lights, one primary ray per path, hit or not.
#[test]
fn rays_are_counted_in_partial_workgroups() {
    let scene = scene(Vec::new(), false);
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let tree = Tree::upload(gpu(), &bvh).unwrap();
    for (width, height) in [(13, 7), (1, 1), (9, 17)] {
        let settings = RenderSettings {
            width,
            height,
            max_depth: 1,
            ..RenderSettings::default()
        };
        let mut tracer = PathTracer::new(gpu(), settings).unwrap();
        let stats = tracer
            .trace(gpu(), &geometry, &tree, &scene.camera, scene.sky, 3)
            .unwrap();
        assert_eq!(
            stats.rays,
            u64::from(width * height * 3),
            "{width}x{height}"
        );
    }
}
