//! The sky's pilot ([`super::sky_guide`]: the rays of a batch of plain sky photons whose
//! paths stored a photon) kept from frame to frame. It depends on the geometry, the
//! materials (which surfaces store, which are mirrors or glass), the sky and the trace
//! settings, not on the frame: traced once with a fixed seed, it is kept until one of
//! them changes. A frame that keeps it pays none of its rays (window room, 200k photons:
//! 200k pilot rays, most of the sky photons' trace time besides the aimed ones').
//!
//! The kept pilot is exactly what a new renderer traces for the same scene (the same seed,
//! the same rays), so a frame's guide does not depend on what the renderer drew before.

use super::sky_guide::SkyRay;
use super::trace::{sky_pilot, TraceControl};
use super::PhotonTraceSettings;
use crate::error::Result;
use crate::scene::environment::Environment;
use crate::scene::{Changes, Scene};
use crate::trace::SceneBvh;
use std::sync::{Arc, Mutex};

/// The pilot's random seed: fixed, so that the pilot is a function of the scene.
const PILOT_SEED: u64 = 0x51C7_9170_A1B2_0001;

/// What the pilot was traced for besides the geometry and materials (whose changes drop
/// it, [`KeptPilot::invalidate`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Key {
    rays: u64,
    max_bounces: u32,
    store_direct: bool,
}

struct Kept {
    key: Key,
    /// The sky traced (held, so that its address cannot be another sky's).
    sky: Arc<Environment>,
    rays: Arc<Vec<SkyRay>>,
}

/// The sky's pilot of the last frame, if still valid (see the module).
#[derive(Default)]
pub struct KeptPilot {
    kept: Mutex<Option<Kept>>,
    builds: std::sync::atomic::AtomicU64,
    /// Seconds the last [`KeptPilot::rays`] spent tracing (0 when it kept the pilot), until
    /// taken ([`KeptPilot::take_seconds`]).
    seconds: Mutex<Option<f64>>,
}

impl KeptPilot {
    /// Drops the pilot when `changes` moved geometry or changed materials.
    pub fn invalidate(&mut self, changes: Changes) {
        if changes.geometry || changes.materials {
            *self.kept.get_mut().unwrap_or_else(|p| p.into_inner()) = None;
        }
    }

    /// The pilot of `n` rays of `scene`'s sky traced with `s`: the kept one when traced for
    /// the same sky, count and settings, else traced now (with the fixed seed) and kept.
    /// Empty without a sky.
    pub fn rays(
        &self,
        scene: &Scene,
        bvh: &SceneBvh,
        n: u64,
        s: &PhotonTraceSettings,
        control: &dyn TraceControl,
    ) -> Result<Arc<Vec<SkyRay>>> {
        let Some(sky) = scene.environment.as_ref() else {
            return Ok(Arc::default());
        };
        let key = Key {
            rays: n,
            max_bounces: s.max_bounces,
            store_direct: s.store_direct,
        };
        let mut kept = self.kept.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(k) = kept.as_ref() {
            if k.key == key && Arc::ptr_eq(&k.sky, sky) {
                *self.seconds.lock().unwrap_or_else(|p| p.into_inner()) = Some(0.0);
                return Ok(k.rays.clone());
            }
        }
        *kept = None;
        let t = std::time::Instant::now();
        let rays = Arc::new(sky_pilot(scene, bvh, n, s, PILOT_SEED, control)?);
        *self.seconds.lock().unwrap_or_else(|p| p.into_inner()) = Some(t.elapsed().as_secs_f64());
        self.builds
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        *kept = Some(Kept {
            key,
            sky: sky.clone(),
            rays: rays.clone(),
        });
        Ok(rays)
    }

    /// The seconds the pilot took to trace since the last call (0: kept), if asked for.
    pub fn take_seconds(&self) -> Option<f64> {
        self.seconds
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .take()
    }

    /// How many pilots this has traced (tests).
    pub fn builds(&self) -> u64 {
        self.builds.load(std::sync::atomic::Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::trace::Unchecked;
    use crate::scene::update::SceneUpdate;
    use glam::{Mat4, Vec3};
    use std::collections::HashMap;

    fn window_room() -> Scene {
        let text = include_str!("../../../../tests/scenes/openings/window_room.json");
        Scene::from_json(text, "window_room", &HashMap::new()).unwrap()
    }

    fn settings() -> PhotonTraceSettings {
        PhotonTraceSettings {
            max_bounces: 4,
            store_direct: false,
            differentials: None,
        }
    }

    /// A second frame keeps the pilot (the same rays, not traced again); a moved object
    /// drops it, and the pilot traced then is a new renderer's for the moved scene.
    #[test]
    fn kept_until_geometry_changes_then_a_new_renderers() {
        let mut scene = window_room();
        let (n, s) = (20_000, settings());
        let mut kept = KeptPilot::default();
        let bvh = SceneBvh::build(&scene);
        let first = kept.rays(&scene, &bvh, n, &s, &Unchecked).unwrap();
        assert!(first.len() >= 16, "{}", first.len());
        kept.invalidate(Changes {
            camera: true,
            lights: true,
            ..Default::default()
        });
        let second = kept.rays(&scene, &bvh, n, &s, &Unchecked).unwrap();
        assert!(Arc::ptr_eq(&first, &second));
        assert_eq!(kept.builds(), 1);
        // Another count or other settings: traced again.
        let other = kept.rays(&scene, &bvh, n / 2, &s, &Unchecked).unwrap();
        assert_eq!(kept.builds(), 2);
        assert!(other.len() < first.len());
        kept.rays(&scene, &bvh, n, &s, &Unchecked).unwrap();
        assert_eq!(kept.builds(), 3);

        // The wall with the window (the last object) moved 1 m into the room.
        let wall = scene.objects.len() - 1;
        let t = Mat4::from_translation(Vec3::new(-1.0, 0.0, 0.0)) * scene.objects[wall].transform;
        let changes = scene
            .apply(&SceneUpdate::Transform {
                object: wall,
                transform: t,
            })
            .unwrap();
        kept.invalidate(changes);
        let bvh = SceneBvh::build(&scene);
        let moved = kept.rays(&scene, &bvh, n, &s, &Unchecked).unwrap();
        assert_eq!(kept.builds(), 4);
        let fresh = KeptPilot::default()
            .rays(&scene, &bvh, n, &s, &Unchecked)
            .unwrap();
        assert_eq!(*moved, *fresh);
        assert_ne!(*moved, *first);
    }

    /// Another sky (a new environment) is traced again, though nothing else changed.
    #[test]
    fn another_sky_is_traced_again() {
        let mut scene = window_room();
        let (n, s) = (8_000, settings());
        let kept = KeptPilot::default();
        let bvh = SceneBvh::build(&scene);
        let first = kept.rays(&scene, &bvh, n, &s, &Unchecked).unwrap();
        let sky = scene.environment.as_deref().unwrap().clone();
        scene.environment = Some(Arc::new(sky));
        let again = kept.rays(&scene, &bvh, n, &s, &Unchecked).unwrap();
        assert_eq!(kept.builds(), 2);
        assert_eq!(*first, *again);
        scene.environment = None;
        assert!(kept
            .rays(&scene, &bvh, n, &s, &Unchecked)
            .unwrap()
            .is_empty());
    }
}
