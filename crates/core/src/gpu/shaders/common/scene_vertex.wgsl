// The scene's vertices as the passes that rasterize it read them: the unique meshes'
// vertices in their own frames (`gpu::raw::VertexRaw`, per vertex) placed by the object's
// instance record (`gpu::raw::InstanceRaw`, per instance), and what they carry to the
// fragment stage: world position, shading and geometric normal, material, texture
// coordinates and tangent.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) geometric_normal: vec3<f32>,
    @location(3) material: u32,
    @location(4) uv: vec2<f32>,
    @location(5) tangent: vec4<f32>,
}

struct InstanceIn {
    // Object -> world, by columns.
    @location(6) model0: vec4<f32>,
    @location(7) model1: vec4<f32>,
    @location(8) model2: vec4<f32>,
    @location(9) model3: vec4<f32>,
    // Normal matrix (inverse transpose of the linear part), by columns; normal0.w is -1 for
    // a mirroring transform (the tangent's handedness flips), else 1.
    @location(10) normal0: vec4<f32>,
    @location(11) normal1: vec4<f32>,
    @location(12) normal2: vec4<f32>,
    // Added to the vertex's material (its file's per-face offset, or 0).
    @location(13) material: u32,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) geometric_normal: vec3<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) uv: vec2<f32>,
    // Interpolated across the triangle, as `Scene::tangent_at` does on the CPU.
    @location(5) tangent: vec4<f32>,
}

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if l > 0.0 {
        return v / l;
    }
    return vec3<f32>(0.0);
}

// Vertex `v` placed by instance `i` (as `Scene::flat` places it on the CPU: the position by
// the object's transform, normals by the normal matrix, renormalized; the tangent by the
// linear part) and projected by `view_proj` (world -> clip), its attributes carried along.
fn scene_vertex(v: VertexIn, i: InstanceIn, view_proj: mat4x4<f32>) -> VertexOut {
    let model = mat4x4<f32>(i.model0, i.model1, i.model2, i.model3);
    let nm = mat3x3<f32>(i.normal0.xyz, i.normal1.xyz, i.normal2.xyz);
    let world = (model * vec4<f32>(v.position, 1.0)).xyz;
    var o: VertexOut;
    o.clip = view_proj * vec4<f32>(world, 1.0);
    o.world = world;
    o.normal = normalize_or_zero(nm * v.normal);
    o.geometric_normal = normalize_or_zero(nm * v.geometric_normal);
    o.material = v.material + i.material;
    o.uv = v.uv;
    let linear = mat3x3<f32>(i.model0.xyz, i.model1.xyz, i.model2.xyz);
    o.tangent = vec4<f32>(normalize_or_zero(linear * v.tangent.xyz), v.tangent.w * i.normal0.w);
    return o;
}

// The interpolated shading normal `n` as trace::Interaction::new starts it: normalized and
// on the side of the geometric normal `ng`, or `ng` where it has no length.
fn shading_normal(n: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    let len = length(n);
    if !(len > 0.0) {
        return ng;
    }
    let ns = n / len;
    if dot(ns, ng) < 0.0 {
        return -ns;
    }
    return ns;
}

// The normal of a fragment's front face (`trace::Interaction`'s `front`): the interpolated
// vertex normal `n` as it is, else the winding's normal `ng`.
fn front_normal(n: vec3<f32>, ng: vec3<f32>) -> vec3<f32> {
    return select(ng, n, dot(n, n) > 0.0);
}

// A fragment's normals seen from direction `wo` (towards the viewer or the light).
struct FacingNormals {
    shading: vec3<f32>,
    geometric: vec3<f32>,
}

// Normals `ns` and `ng` turned towards `wo`, as trace::Interaction::new turns them: `ns`
// replaced by `ng` where the two disagree about the side `wo` comes from, then both flipped
// where `ng` faces away.
fn facing_normals(wo: vec3<f32>, ns: vec3<f32>, ng: vec3<f32>) -> FacingNormals {
    var o = FacingNormals(ns, ng);
    if dot(wo, ns) * dot(wo, ng) <= 0.0 {
        o.shading = ng;
    }
    if dot(wo, ng) < 0.0 {
        o.geometric = -ng;
        o.shading = -o.shading;
    }
    return o;
}

// A fragment's shading normal and material.
struct FragmentSurface {
    ns: vec3<f32>,
    m: Material,
}

// Fragment `in`'s shading normal (`shading_normal`) and material `base`, with its
// textures (common/texture.wgsl, `material_maps`) applied where `textured`: the normal map,
// then the textured material, at the mip level of the uv derivatives `duvdx`, `duvdy`.
fn fragment_surface(
    in: VertexOut,
    base: Material,
    textured: bool,
    duvdx: vec2<f32>,
    duvdy: vec2<f32>,
) -> FragmentSurface {
    var o = FragmentSurface(shading_normal(in.normal, in.geometric_normal), base);
    if textured {
        let maps = material_maps[in.material];
        o.ns = mapped_normal(maps, o.ns, in.tangent, in.uv, duvdx, duvdy);
        o.m = textured_material(maps, o.m, in.uv, duvdx, duvdy);
    }
    return o;
}
