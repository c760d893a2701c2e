// The diffuse path integrator of the path-tracing kernels (paths_trace.wgsl: binary BVH,
// paths_trace_wide.wgsl: wide BVH), which declare the bindings and include their traversal
// (`traverse`) before this file.
// Diffuse path tracing: one invocation per pixel, `samples` paths per pixel per dispatch (in one
// loop over the bounce rays of all of them, see `main`), each with up to `max_depth` closest-hit
// rays (cosine-weighted bounces; emissive surfaces, a sky and point lights as light). At every
// path vertex each point light is sampled with a shadow ray (next-event estimation) and adds
// albedo · intensity · cos θ when visible, with no distance falloff (the BART scenes'
// Whitted-style light convention, see `PointLight`). Radiance sums accumulate progressively in
// `accum` (rgb sum, sample count in w). Every traced ray, bounce and shadow, is counted: each
// invocation adds its rays to a workgroup tally, and the workgroup's last invocation to finish
// adds the total to the dispatch's counter (one global atomic per workgroup, no barrier). With
// COUNT_STEPS each invocation also adds its traversals' steps (internal nodes, triangles) to the
// dispatch's 64-bit counts after all the dispatches' ray counters (`TRACE_STEPS_AT`).
#include "random.wgsl"

struct TraceParams {
    eye: vec3<f32>,
    seed: u32,
    // Camera basis scaled to the image plane at distance 1: right * tan(fov/2) * aspect, ...
    right: vec3<f32>,
    width: u32,
    up: vec3<f32>,
    height: u32,
    forward: vec3<f32>,
    max_depth: u32,
    sky: vec3<f32>,
    samples: u32,
    light_count: u32,
    // Always 0 (see unfused.wgsl).
    opaque_zero: u32,
    // This dispatch's pair of `counters`.
    counter_slot: u32,
    pad: u32,
}

struct PointLight {
    position: vec3<f32>,
    intensity: vec3<f32>,
}

// The workgroup's rays << TALLY_SHIFT | its invocations finished (zero-initialized, as all
// workgroup memory). One word for both, so the atomic add of the last invocation to finish
// returns every other invocation's rays: the tally needs no barrier. (Lavapipe compiles a kernel
// with barriers as a coroutine: with the two barriers of a workgroup reduction the binary trace
// was 11-13 % slower, the wide one 4-8 %.) `PathTracer` keeps a workgroup's rays per dispatch
// below 2^(32 - TALLY_SHIFT).
var<workgroup> workgroup_tally: atomic<u32>;
const TALLY_SHIFT: u32 = 7u;
// 1: shadow rays towards the point lights (params.light_count of them); 0: a pipeline for scenes
// without point lights, which holds no light loop and no shadow ray's traversal.
override POINT_LIGHTS: u32 = 1u;
// Invocations per workgroup (8 x 8).
const WORKGROUP_INVOCATIONS: u32 = 64u;

const PI: f32 = 3.14159265358979;

fn sky_radiance(dir: vec3<f32>) -> vec3<f32> {
    // Zenith colour above, fading to a darker horizon and ground.
    let h = clamp(dir.y, -1.0, 1.0);
    return params.sky * mix(0.35, 1.0, max(h, 0.0)) * select(0.6, 1.0, h >= 0.0);
}

// Adds `value` to the 64-bit count whose low word is counters[low] and high word the next.
fn add_to_count(low: u32, value: u32) {
    let before = atomicAdd(&counters[low], value);
    if before > 0xffffffffu - value {
        atomicAdd(&counters[low + 1u], 1u);
    }
}

// Cosine-weighted direction around the unit normal n (Duff et al. 2017 orthonormal basis).
fn cosine_direction(n: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    let r1 = random_f32(rng);
    let r2 = random_f32(rng);
    let phi = 2.0 * PI * r1;
    let r = sqrt(r2);
    let s = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    let bt = vec3<f32>(b, s + n.y * n.y * a, -n.y);
    return normalize(t * (r * cos(phi)) + bt * (r * sin(phi)) + n * sqrt(max(0.0, 1.0 - r2)));
}

// A path being traced: its next bounce ray (origin, dir), the bounce rays it has traced (`depth`;
// its shadow rays are not counted there), its throughput and the radiance it has gathered.
struct PathState {
    origin: vec3<f32>,
    depth: u32,
    dir: vec3<f32>,
    throughput: vec3<f32>,
    radiance: vec3<f32>,
}

// A new path of the pixel at `coords` from the camera (a jittered primary ray).
fn start_path(coords: vec2<u32>, rng: ptr<function, u32>) -> PathState {
    let jitter = vec2<f32>(random_f32(rng), random_f32(rng));
    let ndc = vec2<f32>(
        2.0 * (f32(coords.x) + jitter.x) / f32(params.width) - 1.0,
        1.0 - 2.0 * (f32(coords.y) + jitter.y) / f32(params.height),
    );
    let dir = normalize(params.forward + ndc.x * params.right + ndc.y * params.up);
    return PathState(params.eye, 0u, dir, vec3<f32>(1.0), vec3<f32>(0.0));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    // The workgroup's 8x8 pixels, numbered so that every 8 consecutive invocations cover a 4x2
    // block and every 32 an 8x4 block (lid bits 0, 1, 3 are x, bits 2, 4, 5 are y): a CPU
    // device's SIMD lanes (8 on lavapipe) and a GPU's subgroups trace neighbouring pixels,
    // whose rays take similar paths through the tree. Each pixel's paths stay the same.
    let block = vec2<u32>((lid & 3u) | ((lid >> 1u) & 4u), ((lid >> 2u) & 1u) | ((lid >> 3u) & 6u));
    let coords = wid.xy * 8u + block;
    var rays = 0u;
    var overflows = 0u;
    var steps = vec2<u32>(0u);
    // One traversal stack for all of this invocation's rays (zero-filled once).
    var stack: TraversalStack;
    if coords.x < params.width && coords.y < params.height && params.samples != 0u {
        let pixel = coords.y * params.width + coords.x;
        var rng = pcg_hash(pixel ^ pcg_hash(params.seed));
        var sum = vec3<f32>(0.0);
        // One loop over the bounce rays of all the pixel's paths: a path that ends starts the
        // pixel's next one at once, so the invocations of a SIMD batch (a warp) wait for each
        // other at the end of all their paths, not at the end of every path. The shadow rays of
        // a path vertex are traced together, light by light, as the batch's invocations reach it
        // (against one traversal call site shared by shadow and bounce rays: an NVIDIA H200's
        // trace 8-16 % faster in the binary layout, 0-3 % in the wide one; README, "Wide vs
        // binary: measurements").
        var path = start_path(coords, &rng);
        var samples_done = 0u;
        loop {
            let traced = traverse(path.origin, path.dir, 0.0, 3.0e38, params.opaque_zero, false, &stack);
            rays++;
            overflows += traced.overflow;
            steps += traced.steps;
            let hit = traced.hit;
            path.depth++;
            var ended = path.depth == params.max_depth;
            if hit.tri == MISS {
                path.radiance += path.throughput * sky_radiance(path.dir);
                ended = true;
            } else {
                // Both loads at once: the material came with the hit.
                let tri = load_triangle(hit.tri);
                let material = materials[traced.material];
                path.radiance += path.throughput * material.emission;
                path.throughput *= material.albedo;
                var n = normalize(cross(tri.v1 - tri.v0, tri.v2 - tri.v0));
                if dot(n, path.dir) > 0.0 {
                    n = -n;
                }
                let p = path.origin + hit.t * path.dir;
                let eps = 1e-4 * max(1.0, max(abs(p.x), max(abs(p.y), abs(p.z))));
                path.origin = p + n * eps;
                for (var l = 0u; POINT_LIGHTS != 0u && l < params.light_count; l++) {
                    let light = lights[l];
                    let to_light = light.position - path.origin;
                    let distance = length(to_light);
                    let cos_theta = dot(n, to_light) / max(distance, 1e-30);
                    if cos_theta > 0.0 {
                        let shadow = traverse(path.origin, to_light / distance, 0.0, distance, params.opaque_zero, true, &stack);
                        rays++;
                        overflows += shadow.overflow;
                        steps += shadow.steps;
                        if shadow.hit.tri == MISS {
                            path.radiance += path.throughput * light.intensity * cos_theta;
                        }
                    }
                }
                // Drawn after every bounce, the last one too: the pixel's random numbers are
                // drawn in the same order as a path at a time.
                path.dir = cosine_direction(n, &rng);
            }
            if ended {
                sum += path.radiance;
                samples_done++;
                if samples_done == params.samples {
                    break;
                }
                path = start_path(coords, &rng);
            }
        }
        accum[pixel] += vec4<f32>(sum, f32(params.samples));
    }
    if overflows != 0u {
        atomicAdd(&counters[2u * params.counter_slot + 1u], overflows);
    }
    if COUNT_STEPS != 0u {
        let at = TRACE_STEPS_AT + 4u * params.counter_slot;
        add_to_count(at, steps.x);
        add_to_count(at + 2u, steps.y);
    }
    let mine = (rays << TALLY_SHIFT) | 1u;
    let tally = atomicAdd(&workgroup_tally, mine) + mine;
    if (tally & ((1u << TALLY_SHIFT) - 1u)) == WORKGROUP_INVOCATIONS {
        atomicAdd(&counters[2u * params.counter_slot], tally >> TALLY_SHIFT);
    }
}
