// The GPU-traced photons made ready for the binned estimators without leaving the GPU
// (`gpu/photon/resident.rs`): each record's volume radius as `VolumeRadius::of` gives it
// (`photon/radius.rs`), caustic records widened to at least a pixel as `at_least_a_pixel`
// does (`frame/ispm/indirect.rs`), the path index cleared from the pad word, and the caustic
// records counted (`photon::density::is_caustic`).

struct ResidentParams {
    eye: vec3<f32>,
    r_base: f32,
    r_max: f32,
    exponent: f32,
    max_widening: f32,
    caustic_density: f32,
    // The least caustic radius per metre of distance from the eye.
    pixel_per_metre: f32,
    first: u32,
    count: u32,
    _pad: u32,
};

// Four texels a record: position, bounce; incident, path density; power, pad; normal, radius.
@group(0) @binding(0) var<storage, read_write> resident_records: array<vec4<f32>>;
@group(0) @binding(1) var<uniform> resident: ResidentParams;
@group(0) @binding(2) var<storage, read_write> resident_caustics: array<atomic<u32>>;

@compute @workgroup_size(64)
fn resident_size(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = resident.first + gid.x;
    if gid.x >= resident.count {
        return;
    }
    let at = 4u * i;
    let head = resident_records[at];
    let density = resident_records[at + 1u].w;
    let tail = resident_records[at + 3u];
    var r: f32;
    if tail.w > 0.0 {
        r = min(tail.w, resident.r_max);
    } else {
        let g = clamp(pow(max(density, 1e-30), -resident.exponent), 1.0, resident.max_widening);
        r = min(resident.r_base * g, resident.r_max);
    }
    let bounce = bitcast<u32>(head.w);
    if bounce >= 1u && density > resident.caustic_density {
        r = max(r, length(head.xyz - resident.eye) * resident.pixel_per_metre);
        atomicAdd(&resident_caustics[0], 1u);
    }
    resident_records[at + 3u] = vec4<f32>(tail.xyz, r);
    let power = resident_records[at + 2u];
    resident_records[at + 2u] = vec4<f32>(power.xyz, 0.0);
}
