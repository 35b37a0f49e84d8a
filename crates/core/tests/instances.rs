//! Instances: a scene whose objects share meshes renders as the same scene with every mesh
//! copied (bitwise, every method) and as the scene flattened into world-space triangles
//! (within rounding, every method); moving one instance moves its shadow and its indirect
//! light in the `Renderer`; bad instance references are typed errors naming the field.

mod common;

use common::frames::{all, max_difference, mean, settings};
use gi_core::frame::Renderer;
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::Silent;
use gi_core::{render, Image, Method, Scene};
use glam::{Mat4, Vec3};
use std::collections::HashMap;

/// The glass Cornell box with four balls of one mesh: two named by equal built-in shapes,
/// two explicit instances (one mirrored, one scaled and made of glass).
fn instanced_json() -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_str(builtin::json("cornell-glass").expect("built-in")).expect("json");
    let ball = serde_json::json!({"type": "sphere", "radius": 0.15, "subdivisions": 2});
    let objects = v["objects"].as_array_mut().expect("objects");
    objects.extend([
        serde_json::json!({"name": "ball", "shape": ball,
            "transform": {"translate": [-0.5, 0.15, 0.6]}, "material": "white"}),
        serde_json::json!({"shape": ball,
            "transform": {"translate": [0.5, 0.15, 0.75], "rotate": [10, 30, 0]},
            "material": "red"}),
        serde_json::json!({"shape": {"type": "instance", "object": "ball"},
            "transform": {"translate": [-0.05, 0.12, 0.8], "scale": [-0.8, 0.8, 0.8]}}),
        serde_json::json!({"shape": {"type": "instance", "object": "ball"},
            "transform": {"translate": [0.0, 1.3, 0.3], "scale": 0.6}, "material": "glass"}),
    ]);
    v
}

fn instanced() -> Scene {
    Scene::from_json(&instanced_json().to_string(), "instanced", &HashMap::new()).expect("scene")
}

/// The four balls are one mesh (so are the box's equal walls); the flat arrays place every
/// object's copy.
#[test]
fn equal_shapes_and_instances_share_one_mesh() {
    let s = instanced();
    let balls = &s.objects[s.objects.len() - 4..];
    assert!(balls.iter().all(|o| o.mesh == balls[0].mesh));
    assert!(balls[2].flipped && !balls[0].flipped);
    let placed: usize = s
        .objects
        .iter()
        .map(|o| s.meshes[o.mesh as usize].indices.len())
        .sum();
    assert_eq!(s.triangle_count(), placed);
    // Each mesh is used: stored once however many objects place it.
    let mut used: Vec<u32> = s.objects.iter().map(|o| o.mesh).collect();
    used.sort();
    used.dedup();
    assert_eq!(used.len(), s.meshes.len());
    let ball_triangles = s.meshes[balls[0].mesh as usize].indices.len();
    assert!(s.unique_triangle_count() + 3 * ball_triangles <= s.triangle_count());
    // The instance without a material takes the referenced object's.
    let white = s.material_names.iter().position(|n| n == "white").unwrap() as u32;
    let glass = s.material_names.iter().position(|n| n == "glass").unwrap() as u32;
    assert_eq!(
        s.triangle_material(balls[2].triangles.start as usize),
        white
    );
    assert_eq!(
        s.triangle_material(balls[3].triangles.start as usize),
        glass
    );
    let copied = s.unshared();
    assert_eq!(copied.meshes.len(), s.objects.len());
    assert_eq!(copied.flat(), s.flat());
}

/// Every method renders the instanced scene exactly (bitwise: radiance, albedo, depth) as
/// the scene with every object's mesh copied: the meshes' BVHs are built from equal
/// triangles and traversed with equal rays, and the flat arrays the GPU draws are equal.
#[test]
fn instanced_equals_unshared_bitwise() {
    let s = instanced();
    let copied = s.unshared();
    for &method in Method::ALL {
        let o = settings(method);
        let a = render(&s, &o, &Silent).expect("instanced");
        let b = render(&copied, &o, &Silent).expect("unshared");
        assert_eq!(
            max_difference(&a.radiance, &b.radiance),
            0.0,
            "{}",
            method.name()
        );
        assert_eq!(a.albedo.pixels, b.albedo.pixels, "{}", method.name());
        assert_eq!(a.depth, b.depth, "{}", method.name());
    }
}

/// Every method renders the instanced scene as the scene flattened into world-space
/// triangles (identity transforms). Rays meet the balls in their mesh frames instead of in
/// world space, so hit distances and barycentrics differ by rounding (~1e-7 relative); the
/// GPU places each mesh vertex by its instance's transform in the vertex stage (the
/// flattened scene's identity transforms place them exactly), so positions and normals
/// differ by ~1 ulp there too (measured: `direct` within 5e-7 of the flattened image, every
/// method's mean equal to 6 digits); a traced path changes only where a rounding flips a
/// decision (a ray grazing an edge, a Russian-roulette or BSDF-lobe threshold). Allowed:
/// the image means within 0.2%, and at least 97% of pixels within 1e-4 relative (+1e-6
/// absolute).
#[test]
fn instanced_matches_flattened_within_rounding() {
    let s = instanced();
    let flat = s.flattened();
    assert_eq!(flat.flat().positions, s.flat().positions);
    for &method in Method::ALL {
        let o = settings(method);
        let a = render(&s, &o, &Silent).expect("instanced");
        let b = render(&flat, &o, &Silent).expect("flattened");
        let (ma, mb) = (mean(&a.radiance), mean(&b.radiance));
        let close = a
            .radiance
            .pixels
            .iter()
            .zip(&b.radiance.pixels)
            .filter(|(x, y)| ((**x - **y).abs().max_element()) <= 1e-4 * x.max_element() + 1e-6)
            .count();
        let share = close as f32 / a.radiance.pixels.len() as f32;
        eprintln!(
            "{}: means {ma} {mb}, {:.2}% of pixels within 1e-4, max diff {}",
            method.name(),
            100.0 * share,
            max_difference(&a.radiance, &b.radiance)
        );
        assert!(ma > 0.0, "{}", method.name());
        assert!(
            (ma - mb).abs() <= 2e-3 * ma,
            "{}: means {ma} vs {mb}",
            method.name()
        );
        assert!(share >= 0.97, "{}: {share}", method.name());
    }
}

fn aov(o: &gi_core::RenderOutput, name: &str) -> Image {
    o.aovs
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, i)| i.clone())
        .expect("aov")
}

/// Moving one instance (the white ball, whose mesh three other objects share) in a
/// `Renderer`: its frame equals a one-shot render of the moved scene (bitwise), the floor
/// point that the ball now hides from the light gets darker (`ispm`: below half its direct
/// light; `path`: below 0.9 of its radiance, which includes the indirect light),
/// and the indirect light changes beyond the image's own difference (the same seed renders
/// the still scene twice identically). `ispm` (shadow maps, photons traced through the
/// two-level BVH) and `path`.
#[test]
fn moved_instance_moves_its_shadow_and_indirect_light() {
    let scene = instanced();
    let object = scene.objects.len() - 4;
    let moved = Mat4::from_translation(Vec3::new(0.0, 0.8, -0.4));
    let mut moved_scene = scene.clone();
    let update = SceneUpdate::Transform {
        object,
        transform: moved,
    };
    moved_scene.apply(&update).expect("move");
    // The new shadow's centre on the floor: from the light (0, 1.6, 0) through the ball.
    let c = Vec3::new(0.0, 0.8, -0.4);
    let light = Vec3::new(0.0, 1.6, 0.0);
    let floor = light + (c - light) * (light.y / (light.y - c.y));
    for method in [Method::Ispm, Method::Path] {
        let o = settings(method);
        let camera = scene.camera.with_size(40, 30);
        let (x, y, _) = camera.project(floor).expect("the floor point is in view");
        let pixel = y as usize * 40 + x as usize;
        let still = render(&scene, &o, &Silent).expect("still");
        let mut r = Renderer::new(&scene, &o).expect("renderer");
        r.render(&all(), &Silent).expect("frame 0");
        r.update(&update).expect("move");
        let after = r.render(&all(), &Silent).expect("moved");
        let one_shot = render(&moved_scene, &o, &Silent).expect("one-shot");
        assert_eq!(
            max_difference(&after.radiance, &one_shot.radiance),
            0.0,
            "{}",
            method.name()
        );
        let (direct_before, direct_after) = if method == Method::Ispm {
            (aov(&still, "direct"), aov(&after, "direct"))
        } else {
            (still.radiance.clone(), after.radiance.clone())
        };
        let (b, a) = (
            direct_before.pixels[pixel].element_sum(),
            direct_after.pixels[pixel].element_sum(),
        );
        eprintln!("{}: floor pixel {x} {y}: {b} -> {a}", method.name());
        // ispm's direct image loses the light there (measured 0.143 -> 0); path's radiance
        // keeps the indirect light (measured 1.15 -> 0.97).
        let darker = if method == Method::Ispm { 0.5 } else { 0.9 };
        assert!(a < darker * b, "{}: {b} -> {a}", method.name());
        if method == Method::Ispm {
            let (i0, i1) = (aov(&still, "indirect"), aov(&after, "indirect"));
            let d = max_difference(&i0, &i1);
            assert!(d > 0.05 * mean(&i0).max(1e-3), "indirect: {d}");
        }
    }
}

/// Bad instance references are typed errors naming the object's field: a missing object,
/// an instance of itself, a cycle of instances; a degenerate or non-finite transform of an
/// instance names its transform field.
#[test]
fn bad_instances_are_errors_naming_the_field() {
    let with = |extra: Vec<serde_json::Value>| {
        let mut v = instanced_json();
        v["objects"].as_array_mut().expect("objects").extend(extra);
        Scene::from_json(&v.to_string(), "bad", &HashMap::new())
            .expect_err("invalid")
            .to_string()
    };
    let inst = |of: &str| serde_json::json!({"type": "instance", "object": of});
    let n = instanced_json()["objects"]
        .as_array()
        .expect("objects")
        .len();
    let missing = with(vec![serde_json::json!({"shape": inst("nowhere")})]);
    assert!(
        missing.contains(&format!("objects[{n}].shape.object")) && missing.contains("nowhere"),
        "{missing}"
    );
    let own = with(vec![serde_json::json!({"name": "me", "shape": inst("me")})]);
    assert!(
        own.contains(&format!("objects[{n}].shape.object")) && own.contains("itself"),
        "{own}"
    );
    let cycle = with(vec![
        serde_json::json!({"name": "a", "shape": inst("b"), "material": "white"}),
        serde_json::json!({"name": "b", "shape": inst("a"), "material": "white"}),
    ]);
    assert!(
        cycle.contains(&format!("objects[{n}].shape.object")) && cycle.contains("cycle"),
        "{cycle}"
    );
    let flat = with(vec![serde_json::json!({"shape": inst("ball"),
        "transform": {"scale": [1.0, 0.0, 1.0]}})]);
    assert!(
        flat.contains(&format!("objects[{n}].transform.scale")),
        "{flat}"
    );
    // JSON has no NaN: a non-finite transform reaches the core as a huge number.
    let far = with(vec![serde_json::json!({"shape": inst("ball"),
        "transform": {"translate": [1e39, 0.0, 0.0]}})]);
    assert!(far.contains(&format!("objects[{n}].transform")), "{far}");
    // A moved instance keeps its transform checks.
    let mut s = instanced();
    let object = s.objects.len() - 1;
    let e = s
        .apply(&SceneUpdate::Transform {
            object,
            transform: Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)),
        })
        .expect_err("degenerate")
        .to_string();
    assert!(e.contains(&format!("objects[{object}].transform")), "{e}");
    let e = s
        .apply(&SceneUpdate::Transform {
            object,
            transform: Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
        })
        .expect_err("non-finite")
        .to_string();
    assert!(e.contains(&format!("objects[{object}].transform")), "{e}");
}

/// Many instances of a large mesh: 200,000 spheres of 20,480 triangles (4.1·10⁹ placed
/// triangles) load and render with `path` (one mesh BVH and 200,000 instances: the flat
/// view is never built). On the GPU they fit too: the GPU geometry is the unique meshes
/// (20k triangles, 4 MB) plus 128 bytes per instance (26 MB), where the flat view main drew
/// was ~190 GB and was refused with `OutOfMemory`. Rasterizing 4·10⁹ triangles is beyond
/// a CPU rasterizer in a test, so `direct` renders them with the camera turned to the
/// ceiling and no light (no shadow maps): per-instance culling skips every sphere, and the
/// image (albedo, depth) equals that of the scene without them, bitwise. 500,000 spheres
/// exceed the 32-bit triangle numbering, a typed error naming `objects` at load: an
/// absurd count is refused before anything is placed.
#[test]
fn billions_of_instanced_triangles_render_on_the_cpu_and_fit_on_the_gpu() {
    let scene_of = |copies: usize, ceiling: bool| {
        let mut v = instanced_json();
        if ceiling {
            v["lights"] = serde_json::json!([]);
            v["camera"]["position"] = serde_json::json!([0.0, 1.0, 0.0]);
            v["camera"]["look_at"] = serde_json::json!([0.1, 2.0, 0.0]);
            v["camera"]["up"] = serde_json::json!([0.0, 0.0, -1.0]);
        }
        let objects = v["objects"].as_array_mut().expect("objects");
        objects.push(serde_json::json!({"name": "big",
            "shape": {"type": "sphere", "radius": 0.004, "subdivisions": 5},
            "transform": {"translate": [0.0, 0.01, 0.0]}, "material": "white"}));
        let side = (copies as f64).sqrt().ceil() as usize;
        objects.extend((0..copies).map(|i| {
            let (x, z) = (i % side, i / side);
            let at = |k: usize| -0.9 + 1.8 * k as f64 / side as f64;
            serde_json::json!({"shape": {"type": "instance", "object": "big"},
                "transform": {"translate": [at(x), 0.01, at(z)]}})
        }));
        Scene::from_json(&v.to_string(), "many", &HashMap::new())
    };
    let scene = scene_of(200_000, false).expect("loads");
    assert!(scene.triangle_count() > 4_000_000_000);
    let path = render(&scene, &settings(Method::Path).with("spp", 1), &Silent).expect("path");
    assert!(path.radiance.pixels.iter().all(|p| p.is_finite()) && mean(&path.radiance) > 0.0);
    assert!(!scene.flat_is_built());
    let up = scene_of(200_000, true).expect("loads");
    let o = settings(Method::Direct).with("spp", 1);
    let many = render(&up, &o, &Silent).expect("200,000 instances on the GPU");
    assert!(!up.flat_is_built());
    let none = render(&scene_of(0, true).expect("loads"), &o, &Silent).expect("direct");
    assert!(mean(&many.albedo) > 0.0);
    assert_eq!(many.albedo.pixels, none.albedo.pixels);
    assert_eq!(many.depth, none.depth);
    let e = scene_of(500_000, false)
        .expect_err("too many triangles")
        .to_string();
    assert!(e.contains("objects") && e.contains("2^32"), "{e}");
}

/// The CPU methods trace meshes and transforms: rendering the instanced scene with `path`,
/// `photon` or `gather` never builds the flat world-space view, nor do the GPU methods
/// (they draw meshes and instances; `ispm` and `bidir` trace photons in a CPU BVH, which
/// bakes a scene of at most 4096 placed triangles into one world-space mesh from it). A
/// flat view built before an object moved is updated in place to what a fresh build of
/// the moved scene holds (positions, normals, winding of a now mirrored object, texture
/// coordinates, materials).
#[test]
fn cpu_methods_never_build_the_flat_view() {
    let scene = instanced();
    assert!(!scene.flat_is_built());
    for method in [Method::Path, Method::Photon, Method::Gather] {
        let mut r = Renderer::new(&scene, &settings(method)).expect("renderer");
        r.render(&all(), &Silent).expect("frame");
        assert!(!r.scene().flat_is_built(), "{}", method.name());
    }
    // The GPU methods draw meshes and instance records (`raster::instances`).
    for method in [Method::Direct, Method::Ispm, Method::Bidir] {
        let mut r = Renderer::new(&scene, &settings(method)).expect("renderer");
        r.render(&all(), &Silent).expect("frame");
        let baked = method != Method::Direct && scene.triangle_count() <= 4096;
        assert_eq!(r.scene().flat_is_built(), baked, "{}", method.name());
    }

    let mut built = instanced();
    let _ = built.flat();
    let object = built.objects.len() - 4;
    let update = SceneUpdate::Transform {
        object,
        transform: Mat4::from_translation(Vec3::new(0.1, 0.5, 0.0))
            * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)),
    };
    built.apply(&update).expect("move");
    assert!(built.flat_is_built() && built.objects[object].flipped);
    let mut fresh = instanced();
    fresh.apply(&update).expect("move");
    assert!(!fresh.flat_is_built());
    assert_eq!(built.flat(), fresh.flat());
    // The accessors agree with the flat view, and the box of the placed vertices (two
    // corners per scaled-and-translated object) is the flat positions' box exactly.
    let f = fresh.flat();
    let (lo, hi) = f
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    assert_eq!(fresh.vertex_box(), (lo, hi));
    let grid = gi_core::scene::bench::sphere_copies(9, false);
    let (lo, hi) = grid
        .flat()
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    assert_eq!(grid.vertex_box(), (lo, hi));
    for t in (0..fresh.triangle_count()).step_by(7) {
        let (p, n) = fresh.corners(t);
        assert_eq!(p, f.triangles[t].map(|i| f.positions[i as usize]));
        assert_eq!(n, f.triangles[t].map(|i| f.normals[i as usize]));
        assert_eq!(fresh.corner_uvs(t), f.uvs[t]);
        assert_eq!(fresh.triangle_material(t), f.triangle_materials[t]);
    }
}

/// Normal-mapped instances on the GPU: a quad whose normal map tilts its normals 30°
/// (towards +u and −v), placed as instances turned about y, tipped, and mirrored (x scale −1: the
/// tangent frame's handedness flips, `InstanceRaw::normal[0].w`), renders with `direct` as
/// the same scene flattened into world-space triangles, whose tangents the CPU computes
/// from the placed corners: means within 1e-4 relative, 99.5% of pixels within 1e-3
/// relative (the vertex stage places the tangent by the linear part, ~1 ulp off the
/// CPU's). The map matters: with a flat map over 10% of the pixels (the tiles') change, so
/// a wrong tangent on one tile (unplaced, or the mirrored tile's handedness kept) would
/// fail the comparison.
#[test]
fn normal_mapped_instances_match_flattened_on_the_gpu() {
    let scene_of = |tilt: f32| {
        // Tilted towards +u and −v alike: both the tangent and the bitangent (the
        // handedness) matter.
        let h = tilt.sin() * std::f32::consts::FRAC_1_SQRT_2;
        let n = Vec3::new(h, h, tilt.cos()) * 0.5 + Vec3::splat(0.5);
        let texels: Vec<f32> = (0..4).flat_map(|_| [n.x, n.y, n.z, 1.0]).collect();
        let map = gi_core::texture::Texture::new(2, 2, &texels).expect("texture");
        let tile = serde_json::json!({"type": "quad", "size": [0.6, 0.6]});
        let json = serde_json::json!({
            "camera": {"position": [0, 2.5, 1.2], "look_at": [0, 0, 0], "width": 48, "height": 40},
            "lights": [{"type": "point", "position": [0.4, 1.5, 0.3], "intensity": [2, 2, 2]}],
            "materials": {"white": {"diffuse": [0.7, 0.7, 0.7]},
                          "bumpy": {"diffuse": [0.8, 0.6, 0.4], "normal_texture": "map"}},
            "objects": [
                {"shape": {"type": "quad", "size": [4, 4]}, "material": "white"},
                {"name": "tile", "shape": tile, "material": "bumpy",
                 "transform": {"translate": [-0.6, 0.05, -0.4]}},
                {"shape": {"type": "instance", "object": "tile"},
                 "transform": {"rotate": [0, 60, 0], "translate": [0.5, 0.05, -0.4]}},
                {"shape": {"type": "instance", "object": "tile"},
                 "transform": {"rotate": [20, 0, 10], "translate": [-0.5, 0.25, 0.5]}},
                {"shape": {"type": "instance", "object": "tile"},
                 "transform": {"scale": [-1, 1, 1], "rotate": [0, 30, 0],
                               "translate": [0.5, 0.05, 0.5]}},
            ],
        });
        let textures: gi_core::scene::TextureMap = [("map".to_string(), std::sync::Arc::new(map))]
            .into_iter()
            .collect();
        Scene::from_json_textured(&json.to_string(), "tiles", &HashMap::new(), &textures)
            .expect("scene")
    };
    let o = settings(Method::Direct);
    let s = scene_of(30f32.to_radians());
    assert_eq!(s.meshes.len(), 2, "the floor and one tile mesh");
    assert!(s.objects[4].flipped);
    let a = render(&s, &o, &Silent).expect("instanced");
    let b = render(&s.flattened(), &o, &Silent).expect("flattened");
    let flat_map = render(&scene_of(0.0), &o, &Silent).expect("flat map");
    let (ma, mb) = (mean(&a.radiance), mean(&b.radiance));
    // Share of pixels of `x` within 1e-3 relative of `y`.
    let close = |x: &Image, y: &Image| {
        x.pixels
            .iter()
            .zip(&y.pixels)
            .filter(|(x, y)| (**x - **y).abs().max_element() <= 1e-3 * x.max_element() + 1e-6)
            .count() as f32
            / x.pixels.len() as f32
    };
    let (same, unmapped) = (
        close(&a.radiance, &b.radiance),
        close(&a.radiance, &flat_map.radiance),
    );
    eprintln!(
        "means {ma} {mb}; {:.2}% of pixels within 1e-3 of flattened, {:.2}% of the flat map's",
        100.0 * same,
        100.0 * unmapped
    );
    assert!((ma - mb).abs() <= 1e-4 * ma, "{ma} vs {mb}");
    assert!(same >= 0.995, "{same}");
    // The tiles' pixels (four tiles, each well over the 0.5% allowed) change with the map.
    assert!(unmapped < 0.9, "the map changes too little: {unmapped}");
}

/// A mesh file that carries its materials, placed by three objects (two of one smoothing,
/// one of another: two unique meshes): its materials are in the scene once, shared by the
/// three, each triangle keeping its file material; a second file's materials come after.
#[test]
fn a_mesh_file_placed_by_several_objects_has_its_materials_once() {
    use gi_core::bsdf::Material;
    use gi_core::scene::{MeshData, TriMesh};
    let quad = TriMesh {
        positions: vec![
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(-1.0, 0.0, 1.0),
        ],
        normals: vec![],
        indices: vec![[0, 2, 1], [0, 3, 2]],
    };
    let tinted = |r: f32| Material {
        diffuse: Vec3::new(r, 0.2, 0.2),
        ..Default::default()
    };
    let file = |names: [&str; 2]| MeshData {
        mesh: quad.clone(),
        materials: vec![
            (names[0].to_string(), tinted(0.3)),
            (names[1].to_string(), tinted(0.6)),
        ],
        face_materials: vec![0, 1],
        ..Default::default()
    };
    let meshes = HashMap::from([
        ("a.obj".to_string(), file(["a.obj:red", "a.obj:pink"])),
        ("b.obj".to_string(), file(["b.obj:red", "b.obj:pink"])),
    ]);
    let mesh = |f: &str| serde_json::json!({"type": "mesh", "file": f});
    let desc = serde_json::json!({
        "camera": {"position": [0, 3, 3], "look_at": [0, 0, 0]},
        "materials": {"grey": {}},
        "objects": [
            {"shape": mesh("a.obj")},
            {"shape": mesh("a.obj"), "transform": {"translate": [3, 0, 0]}},
            {"shape": mesh("b.obj")},
            {"shape": mesh("a.obj"), "smooth": true, "transform": {"translate": [-3, 0, 0]}},
        ]
    });
    let s = Scene::from_json(&desc.to_string(), "files", &meshes).expect("scene");
    assert_eq!(
        s.material_names,
        ["grey", "a.obj:red", "a.obj:pink", "b.obj:red", "b.obj:pink"]
    );
    assert_eq!(s.meshes.len(), 3, "a.obj twice (two smoothings) and b.obj");
    let a: Vec<u32> = [0usize, 1, 3]
        .iter()
        .map(|&o| s.objects[o].material)
        .collect();
    assert_eq!(a, [1, 1, 1]);
    assert_eq!(s.objects[2].material, 3);
    for t in 0..s.triangle_count() {
        let want = if (4..6).contains(&t) { 3 } else { 1 } + (t as u32 % 2);
        assert_eq!(s.triangle_material(t), want, "triangle {t}");
    }
}
