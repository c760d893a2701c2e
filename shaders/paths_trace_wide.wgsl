// Diffuse path tracing through the compressed wide BVH: the integrator of path_integrator.wgsl
// over the traversal of wide_traverse.wgsl (the bindings of paths_trace.wgsl, with the wide nodes
// at 3 and the references' triangles at 4).
#include "wide_traverse.wgsl"
#include "path_integrator.wgsl"

@group(0) @binding(0) var<uniform> params: TraceParams;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>; // Triangle, three words each
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read> wide_nodes: array<vec4<u32>>; // WideNode, five words each
@group(0) @binding(4) var<storage, read> wide_triangles: array<vec4<u32>>; // WideTree::triangles, as words
@group(0) @binding(5) var<storage, read_write> accum: array<vec4<f32>>;
// Per dispatch (counter_slot): [2 slot]: rays traced, [2 slot + 1]: stack overflows; with
// COUNT_STEPS, [TRACE_STEPS_AT + 4 slot ..]: internal nodes and triangles tested, 64 bits each
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> lights: array<PointLight>;
