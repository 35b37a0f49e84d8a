//! General affine object transforms (`"transform": {"matrix": rows}`), what the glTF and
//! Mitsuba importers place instances with: a matrix places an object exactly as the
//! translate/rotate/scale it equals (bitwise: the same f32 matrix), a mirroring matrix flips
//! the winding, matrices compose with instance sharing, scene updates and animation tracks
//! take them, and bad matrices are typed errors naming the field.

use gi_core::scene::update::UpdateTarget;
use gi_core::scene::{builtin, SceneUpdate};
use gi_core::Silent;
use gi_core::{render, Method, Scene};
use glam::{Mat4, Vec3};
use serde_json::{json, Value};
use std::collections::HashMap;

fn settings(method: Method) -> gi_core::RenderOptions {
    gi_core::RenderOptions::defaults(method)
        .with("width", 32)
        .with("height", 24)
        .with("spp", 2)
        .with("photons", 4_000)
        .with("k", 20)
        .with("max_depth", 3)
}

/// The Cornell box with two balls of one mesh, placed by `first` and `second`.
fn with_balls(first: Value, second: Value) -> Value {
    let mut v: Value =
        serde_json::from_str(builtin::json("cornell").expect("built-in")).expect("json");
    let ball = json!({"type": "sphere", "radius": 0.15, "subdivisions": 2});
    v["objects"].as_array_mut().expect("objects").extend([
        json!({"name": "a", "shape": ball, "transform": first, "material": "white"}),
        json!({"name": "b", "shape": ball, "transform": second, "material": "red"}),
    ]);
    v
}

fn load(v: &Value) -> gi_core::Result<Scene> {
    Scene::from_json(&v.to_string(), "matrix", &HashMap::new())
}

/// Rows (row-major, 4×4) of an f32 matrix, as the scene format takes them.
fn rows(m: Mat4) -> Value {
    json!(m.transpose().to_cols_array_2d())
}

const TRS_A: [f32; 3] = [-0.4, 0.3, 0.5];

fn trs_a() -> Value {
    json!({"translate": TRS_A, "rotate": [20, 35, -10], "scale": [0.7, 1.2, 0.9]})
}

fn trs_b() -> Value {
    json!({"translate": [0.45, 0.2, 0.3], "scale": [-1.0, 1.0, 1.0]})
}

/// A matrix equal to a translate/rotate/scale (its f32 values written out) places the
/// object bitwise the same, shares the mesh, and renders bitwise the same with every CPU
/// method and `direct`; a mirroring matrix is stored flipped as the mirroring scale is.
#[test]
fn a_matrix_places_an_object_as_its_translate_rotate_scale() {
    let described = load(&with_balls(trs_a(), trs_b())).expect("scene");
    let n = described.objects.len();
    let (ma, mb) = (
        described.objects[n - 2].transform,
        described.objects[n - 1].transform,
    );
    // 3 rows (the affine part) for one, 4 rows for the other.
    let three: Vec<Value> = rows(ma).as_array().expect("rows")[..3].to_vec();
    let matrices = load(&with_balls(
        json!({"matrix": three}),
        json!({"matrix": rows(mb)}),
    ))
    .expect("scene");
    let objs = &matrices.objects[n - 2..];
    assert_eq!(objs[0].transform, ma);
    assert_eq!(objs[1].transform, mb);
    assert!(
        objs[1].flipped && !objs[0].flipped,
        "the mirroring matrix flips"
    );
    assert_eq!(objs[0].mesh, objs[1].mesh, "the balls share one mesh");
    assert_eq!(matrices.meshes.len(), described.meshes.len());
    for method in [Method::Path, Method::Direct, Method::Photon] {
        let o = settings(method);
        let a = render(&described, &o, &Silent).expect("described");
        let b = render(&matrices, &o, &Silent).expect("matrices");
        assert_eq!(a.radiance.pixels, b.radiance.pixels, "{}", method.name());
        assert_eq!(a.depth, b.depth, "{}", method.name());
    }
    // A shear no translate/rotate/scale describes: given back as its matrix.
    let shear = [
        [1.0, 0.5, 0.0, 0.1],
        [0.0, 1.0, 0.0, 0.3],
        [0.0, 0.0, 1.0, 0.2],
    ];
    let s = load(&with_balls(json!({"matrix": shear}), trs_b())).expect("scene");
    assert!(s.object_desc(n - 2).expect("object").is_err());
    assert_eq!(s.objects[n - 2].transform.y_axis.x, 0.5);
}

/// Scene updates and animation tracks take a matrix (3 or 4 rows) where they take a
/// transform; a partial update of a matrix-described object applies to the matrix taken
/// apart; a matrix track replaces the whole transform and excludes translate tracks.
#[test]
fn updates_and_animation_tracks_take_matrices() {
    let mut s = load(&with_balls(
        json!({"matrix": rows(Mat4::from_translation(TRS_A.into()))}),
        trs_b(),
    ))
    .expect("scene");
    let i = s.object_index("a").expect("a");
    let target = Mat4::from_scale_rotation_translation(
        Vec3::new(0.5, 0.5, -0.5),
        glam::Quat::from_rotation_y(0.3),
        Vec3::new(0.1, 0.2, 0.3),
    );
    let three: Vec<Value> = rows(target).as_array().expect("rows")[..3].to_vec();
    let u = s
        .update_from_json(&UpdateTarget::Object(i), &json!({"matrix": three}))
        .expect("update");
    s.apply(&u).expect("apply");
    assert_eq!(s.objects[i].transform, target);
    assert!(s.objects[i].flipped, "a mirroring update flips");
    // `translate` alone on a matrix-described object (no shear): the rest is kept.
    let mut t = load(&with_balls(
        json!({"matrix": rows(Mat4::from_translation(TRS_A.into()))}),
        trs_b(),
    ))
    .expect("scene");
    let u = t
        .update_from_json(&UpdateTarget::Object(i), &json!({"translate": [0, 0.5, 0]}))
        .expect("update");
    t.apply(&u).expect("apply");
    assert!(t.objects[i]
        .transform
        .abs_diff_eq(Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)), 1e-6));
    // An animated matrix: halfway between two keys, the element-wise mean.
    let mut v = with_balls(trs_a(), trs_b());
    let (m0, m1) = (
        Mat4::IDENTITY,
        Mat4::from_translation(Vec3::new(0.2, 0.4, 0.0)),
    );
    v["animation"] = json!({"tracks": [{"target": "object", "name": "a", "keys": [
        {"time": 0, "value": {"matrix": rows(m0)}},
        {"time": 1, "value": {"matrix": rows(m1)}}]}]});
    let anim = load(&v).expect("animated scene");
    match anim.animation_at(0.5).expect("valid").as_slice() {
        [SceneUpdate::Transform { object, transform }] => {
            assert_eq!(*object, i);
            assert!(transform.abs_diff_eq(Mat4::from_translation(Vec3::new(0.1, 0.2, 0.0)), 1e-6));
        }
        other => panic!("one transform update expected, got {other:?}"),
    }
    // A matrix track and a translate track on one object describe it twice.
    v["animation"]["tracks"]
        .as_array_mut()
        .expect("tracks")
        .push(json!({"target": "object", "name": "a", "keys": [
            {"time": 0, "value": {"translate": [0, 0, 0]}}]}));
    let e = load(&v).expect_err("matrix and translate").to_string();
    assert!(
        e.contains("animation.tracks[1].keys[0].value.translate") && e.contains("excludes"),
        "{e}"
    );
    // A bad matrix in a key names the key's field.
    let mut v = with_balls(trs_a(), trs_b());
    v["animation"] = json!({"tracks": [{"target": "object", "name": "a", "keys": [
        {"time": 0, "value": {"matrix": [[0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}}]}]});
    let e = load(&v).expect_err("singular key").to_string();
    assert!(
        e.contains("animation.tracks[0].keys[0].value.matrix"),
        "{e}"
    );
}

/// Singular, non-finite, projective, misshapen and out-of-range matrices, and a matrix
/// given with translate/rotate/scale, are typed errors naming the field.
#[test]
fn bad_matrices_are_errors_naming_the_field() {
    let base = load(&with_balls(trs_a(), trs_b())).expect("scene");
    let n = base.objects.len() - 2;
    let cases: Vec<(Value, &str, &str)> = vec![
        // Two equal columns: rank 2.
        (
            json!({"matrix": [[1, 1, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0]]}),
            ".matrix",
            "singular",
        ),
        (
            json!({"matrix": [[1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 1, 0]]}),
            ".matrix",
            "[1e-6, 1e6]",
        ),
        // JSON has no NaN: a non-finite matrix reaches the core as a huge number.
        (
            json!({"matrix": [[1e39, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}),
            ".matrix",
            "finite",
        ),
        (
            json!({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0.5, 1]]}),
            ".matrix[3]",
            "affine",
        ),
        (
            json!({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0]]}),
            ".matrix",
            "3 or 4 rows",
        ),
        (
            json!({"matrix": [[1, 0, 0, 0], [0, 1, 0], [0, 0, 1, 0]]}),
            ".matrix[1]",
            "4 numbers",
        ),
        (
            json!({"matrix": [[1, 0, 0, 2e5], [0, 1, 0, 0], [0, 0, 1, 0]]}),
            ".matrix",
            "±100000",
        ),
        (
            json!({"matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "translate": [1, 0, 0]}),
            ".matrix",
            "excludes",
        ),
        // Within range itself, but placing the ball's vertices beyond ±100000 m.
        (
            json!({"matrix": [[1e6, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}),
            "",
            "outside",
        ),
    ];
    for (transform, field, says) in cases {
        let e = load(&with_balls(trs_a(), transform.clone()))
            .expect_err("invalid")
            .to_string();
        let want = format!("objects[{}].transform{field}", n + 1);
        assert!(e.contains(&want) && e.contains(says), "{transform}: {e}");
        // The same matrix as an update of a loaded scene.
        if !field.is_empty() {
            let e = base
                .update_from_json(&UpdateTarget::Object(n + 1), &transform)
                .map(|_| ())
                .expect_err("invalid update")
                .to_string();
            let object = format!("objects[{}].transform", n + 1);
            assert!(
                e.contains(&object) && e.contains(says),
                "update {transform}: {e}"
            );
        }
    }
}
