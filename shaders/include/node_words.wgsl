// Node boxes accessed as atomics: `node_words` views the BvhNode array as 8 u32 words per node
// (min xyz, left_or_first, max xyz, right_or_count). The bottom-up passes share node data across
// workgroups, so they read and write it only through these atomics. The including kernel declares
// `node_words: array<atomic<u32>>` (read_write storage).

fn store_box(node: u32, lo: vec3<f32>, hi: vec3<f32>) {
    let w = node * 8u;
    atomicStore(&node_words[w + 0u], bitcast<u32>(lo.x));
    atomicStore(&node_words[w + 1u], bitcast<u32>(lo.y));
    atomicStore(&node_words[w + 2u], bitcast<u32>(lo.z));
    atomicStore(&node_words[w + 4u], bitcast<u32>(hi.x));
    atomicStore(&node_words[w + 5u], bitcast<u32>(hi.y));
    atomicStore(&node_words[w + 6u], bitcast<u32>(hi.z));
}

fn load_min(node: u32) -> vec3<f32> {
    let w = node * 8u;
    return vec3<f32>(
        bitcast<f32>(atomicLoad(&node_words[w + 0u])),
        bitcast<f32>(atomicLoad(&node_words[w + 1u])),
        bitcast<f32>(atomicLoad(&node_words[w + 2u])),
    );
}

fn load_max(node: u32) -> vec3<f32> {
    let w = node * 8u;
    return vec3<f32>(
        bitcast<f32>(atomicLoad(&node_words[w + 4u])),
        bitcast<f32>(atomicLoad(&node_words[w + 5u])),
        bitcast<f32>(atomicLoad(&node_words[w + 6u])),
    );
}
