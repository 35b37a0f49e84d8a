//! Which direct-light variant a scene's frames compile (`GpuScene::direct_variant`, once
//! its light samples are drawn as a frame draws them): a scene pays only for the kinds of
//! light it has.

use super::*;
use crate::raster::direct_variant::DirectVariant;
use std::collections::HashMap;

/// The variant of `scene`'s direct-light pipelines after its first frame's light samples
/// (the defaults' 16 points and 64 sky directions).
fn variant_of(ctx: &GpuContext, scene: &Scene) -> DirectVariant {
    let counts = SampleCounts {
        area: 16,
        sky: 64,
        size: 256,
        background: true,
    };
    let mut gs = GpuScene::new(ctx, scene, 256, counts).expect("GPU scene");
    gs.samples.prepare(ctx, scene, 1, 1.0, true);
    gs.direct_variant()
}

/// A glossy floor under an emitting `shape` (JSON), nothing else emitting.
fn glossy_floor_under(shape: &str) -> Scene {
    let json = format!(
        r#"{{"camera": {{"position": [0, 1, 3], "look_at": [0, 0, 0]}},
          "materials": {{"floor": {{"diffuse": [0.3, 0.3, 0.3], "specular": [0.5, 0.5, 0.5], "roughness": 0.3}},
                        "lamp": {{"diffuse": [0, 0, 0], "emission": [4, 4, 4]}}}},
          "objects": [{{"shape": {{"type": "quad", "size": [4, 4]}}, "material": "floor"}},
                      {{"shape": {shape}, "material": "lamp", "transform": {{"rotate": [180, 0, 0], "translate": [0, 1.5, 0]}}}}]}}"#
    );
    Scene::from_json(&json, "glossy floor", &HashMap::new()).expect("scene")
}

/// The point-lit `cornell` compiles neither the LTC glossy lobe nor the round emitters
/// (nor any sampled light); a glossy floor under a quad light compiles LTC without round
/// emitters, under an emitting geodesic sphere both: the switches follow the scene.
#[test]
fn point_lit_cornell_compiles_no_ltc_and_no_round_lights() {
    let ctx = crate::gpu::context(None).expect("a GPU adapter");
    let cornell = crate::scene::builtin::load("cornell").expect("cornell");
    let v = variant_of(&ctx, &cornell);
    assert!(!v.ltc && !v.round && !v.sampled, "{v:?}");
    let quad = variant_of(
        &ctx,
        &glossy_floor_under(r#"{"type": "quad", "size": [1, 1]}"#),
    );
    assert!(quad.ltc && !quad.round && quad.sampled, "{quad:?}");
    let sphere = r#"{"type": "sphere", "radius": 0.2, "subdivisions": 3}"#;
    let round = variant_of(&ctx, &glossy_floor_under(sphere));
    assert!(round.ltc && round.round, "{round:?}");
}
