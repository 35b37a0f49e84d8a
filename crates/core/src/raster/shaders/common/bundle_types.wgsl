// Global ray bundles (method `bidir`, Tokuyoshi & Ogaki 2012 §3.2): the scene rasterized
// under a parallel projection along a global direction ω into per-pixel linked lists of
// fragments. Shared by the bundle pass (which builds the lists) and the lighting pass (which
// walks them).

// One bundle's view, 256 bytes (uniform with dynamic offset, and an array in storage).
struct BundleView {
    // World -> clip, orthographic along `dir`; clip z in [0, 1] over `depth_range`.
    view_proj: mat4x4<f32>,
    // The bundle's global direction ω (depth grows along it).
    dir: vec3<f32>,
    depth_range: f32,
    // Index of the bundle in the frame (its head pointers start at index·res²).
    index: u32,
    // Pixels a side.
    res: u32,
    // Node slots in the fragment buffer (all bundles together).
    capacity: u32,
    // 1 / D(ω): D is the frame's density of bundle directions over a hemisphere of
    // directions at a point, summed over bundles (n2/2π for uniform directions; see
    // `bidir.wgsl`'s `bundle_density`).
    inv_density: f32,
    _pad1: array<vec4<f32>, 10>,
}

// A fragment: its world position (the surface point at the bundle pixel's centre), the
// next node (index + 1; 0 ends the list), normals (octahedral, 2×16-bit snorm each) and the
// material (2×16-bit floats). 40 bytes.
struct Node {
    x: f32,
    y: f32,
    z: f32,
    next: u32,
    ns: u32,
    ng: u32,
    // diffuse rg, diffuse b + roughness, specular rg (2×16-bit floats each); specular b
    // (16-bit float) + the material word (16 bits: the Fresnel flag, the material's index
    // + 1 above it).
    m0: u32,
    m1: u32,
    m2: u32,
    m3: u32,
}
