// The harness of a test kernel (common/kernel.rs): the test's WGSL, joined before this,
// names its input record `Item` and computes one vec4 result per item in `evaluate`.

@group(0) @binding(0) var<storage, read> items: array<Item>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&items) {
        return;
    }
    results[i] = evaluate(items[i]);
}
