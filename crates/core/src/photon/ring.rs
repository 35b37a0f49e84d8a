//! Temporal photon reuse (Jozwowski 2002, section 4): the photons of the last `frames`
//! frames are kept and splatted together, each frame's set weighted so that the average of
//! the sets is a full estimate. A frame traces only its own photons.
//!
//! Invalidation: when a light changes, its photons go; when materials change, all go; when
//! an object moves, the photons that landed in the region it swept (its old and new bounds,
//! grown by the kernel radius) go from every older frame. Where some frames' photons were
//! dropped, the remaining frames' photons are re-weighted by 1/(frames still valid there),
//! so the estimate stays a mean over the frames that know the current geometry there.
//! Photons whose paths touched the object but landed elsewhere (light it reflects onto a far
//! wall) are kept until they age out: a lag of at most `frames` frames.

use super::lbvh::Aabb;
use super::Photon;
use glam::Vec3;
use std::collections::VecDeque;

/// One frame's photons of one light.
struct Entry {
    frame: u64,
    light: usize,
    /// As traced.
    photons: Vec<Photon>,
    /// The same photons with boundary compensation (the splat's power); empty when the
    /// splat uses them as traced.
    compensated: Vec<Photon>,
    /// Regions whose photons in this entry are no longer valid.
    invalid: Vec<Aabb>,
}

/// The photons of the last frames, per light.
pub struct PhotonRing {
    frames: usize,
    entries: VecDeque<Entry>,
    /// A number unique in the process, new at every change of the photons held
    /// ([`PhotonRing::generation`]).
    generation: u64,
}

/// The photons to use this frame, weighted.
pub struct RingPhotons {
    /// With boundary compensation (for the splat).
    pub splat: Vec<Photon>,
    /// As traced, where they differ from `splat`.
    traced: Option<Vec<Photon>>,
}

impl RingPhotons {
    /// The photons as traced (for gathers along specular paths).
    pub fn traced(&self) -> &[Photon] {
        self.traced.as_deref().unwrap_or(&self.splat)
    }
}

impl PhotonRing {
    /// Keeps the photons of the last `frames` frames (at least 1).
    pub fn new(frames: usize) -> Self {
        let mut ring = PhotonRing {
            frames: frames.max(1),
            entries: VecDeque::new(),
            generation: 0,
        };
        ring.touch();
        ring
    }

    /// Which photons the ring holds: equal generations (of any ring of the process) hold
    /// the same photons, so what [`PhotonRing::collect`] made of one generation can be kept
    /// until the next (a still frame collects nothing).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The photons held are about to change: a new generation.
    fn touch(&mut self) {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        self.generation = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }

    pub fn frames(&self) -> usize {
        self.frames
    }

    pub fn clear(&mut self) {
        self.touch();
        self.entries.clear();
    }

    /// Drops the photons of light `light`.
    pub fn invalidate_light(&mut self, light: usize) {
        self.touch();
        self.entries.retain(|e| e.light != light);
    }

    /// Marks the photons inside `region` invalid in every frame held so far.
    pub fn invalidate_region(&mut self, region: Aabb) {
        self.touch();
        for e in &mut self.entries {
            e.invalid.push(region);
        }
    }

    /// Frames of light `light` held now.
    pub fn held(&self, light: usize) -> usize {
        self.entries.iter().filter(|e| e.light == light).count()
    }

    /// Adds frame `frame`'s photons of light `light` (with their compensated copies, or
    /// none when the splat takes them as traced), dropping that light's oldest frames
    /// beyond the capacity.
    pub fn push(
        &mut self,
        frame: u64,
        light: usize,
        photons: Vec<Photon>,
        compensated: Vec<Photon>,
    ) {
        debug_assert!(compensated.is_empty() || photons.len() == compensated.len());
        self.touch();
        self.entries.push_back(Entry {
            frame,
            light,
            photons,
            compensated,
            invalid: Vec::new(),
        });
        while self.held(light) > self.frames {
            let oldest = self
                .entries
                .iter()
                .enumerate()
                .filter(|(_, e)| e.light == light)
                .min_by_key(|(_, e)| e.frame)
                .map(|(i, _)| i);
            match oldest {
                Some(i) => {
                    self.entries.remove(i);
                }
                None => break,
            }
        }
    }

    /// The valid photons of all frames, each with power divided by the number of frames of
    /// its light that are valid at its position.
    pub fn collect(&self) -> RingPhotons {
        let total: usize = self.entries.iter().map(|e| e.photons.len()).sum();
        // Without compensation the splat's photons are the traced ones: one copy.
        let separate = self.entries.iter().any(|e| !e.compensated.is_empty());
        let mut out = RingPhotons {
            splat: Vec::with_capacity(total),
            traced: separate.then(|| Vec::with_capacity(total)),
        };
        let inside = |e: &Entry, p: Vec3| e.invalid.iter().any(|b| b.contains(p));
        for e in &self.entries {
            let same: Vec<&Entry> = self.entries.iter().filter(|o| o.light == e.light).collect();
            let simple = same.iter().all(|o| o.invalid.is_empty());
            for (i, p) in e.photons.iter().enumerate() {
                let c = e.compensated.get(i).unwrap_or(p);
                let x = p.position();
                let valid = if simple {
                    same.len()
                } else {
                    if inside(e, x) {
                        continue;
                    }
                    same.iter().filter(|o| !inside(o, x)).count()
                };
                let w = 1.0 / valid as f32;
                if let Some(traced) = &mut out.traced {
                    let mut p = *p;
                    p.power = (p.power() * w).into();
                    traced.push(p);
                }
                let mut splat = *c;
                splat.power = (c.power() * w).into();
                out.splat.push(splat);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photon(x: f32, power: f32) -> Photon {
        Photon {
            position: [x, 0.0, 0.0],
            power: [power; 3],
            ..Default::default()
        }
    }

    /// Frames pushed without compensated copies splat their photons as traced, with the
    /// same weights; a frame with copies beside them keeps both.
    #[test]
    fn uncompensated_frames_splat_as_traced() {
        let mut ring = PhotonRing::new(2);
        ring.push(0, 0, vec![photon(0.0, 2.0)], Vec::new());
        ring.push(1, 0, vec![photon(1.0, 4.0)], Vec::new());
        let got = ring.collect();
        let power = |v: &[Photon]| v.iter().map(|p| p.power[0]).collect::<Vec<_>>();
        assert_eq!(power(&got.splat), [1.0, 2.0]);
        assert_eq!(power(got.traced()), [1.0, 2.0]);
        ring.push(2, 0, vec![photon(2.0, 4.0)], vec![photon(2.0, 8.0)]);
        let got = ring.collect();
        assert_eq!(power(&got.splat), [2.0, 4.0]);
        assert_eq!(power(got.traced()), [2.0, 2.0]);
    }

    /// Power is conserved: N full frames average to one frame's power.
    #[test]
    fn frames_average() {
        let mut ring = PhotonRing::new(3);
        for f in 0..5 {
            let p = vec![photon(0.0, 2.0), photon(1.0, 4.0)];
            ring.push(f, 0, p.clone(), p);
        }
        assert_eq!(ring.held(0), 3);
        let got = ring.collect();
        assert_eq!(got.splat.len(), 6);
        assert_eq!(got.traced().len(), 6);
        let total: f32 = got.splat.iter().map(|p| p.power[0]).sum();
        assert!((total - 6.0).abs() < 1e-5);
    }

    /// Inside an invalidated region only the frames traced after the change count, each with
    /// full weight there; outside, all frames average.
    #[test]
    fn regions_reweight() {
        let mut ring = PhotonRing::new(4);
        for f in 0..3 {
            let p = vec![photon(0.0, 1.0), photon(5.0, 1.0)];
            ring.push(f, 0, p.clone(), p);
        }
        ring.invalidate_region(Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        });
        let p = vec![photon(0.0, 1.0), photon(5.0, 1.0)];
        ring.push(3, 0, p, vec![photon(0.0, 2.0), photon(5.0, 2.0)]);
        let got = ring.collect();
        let near: f32 = got
            .traced()
            .iter()
            .filter(|p| p.position[0] == 0.0)
            .map(|p| p.power[0])
            .sum();
        let far: f32 = got
            .traced()
            .iter()
            .filter(|p| p.position[0] == 5.0)
            .map(|p| p.power[0])
            .sum();
        assert!((near - 1.0).abs() < 1e-6, "{near}");
        assert!((far - 1.0).abs() < 1e-6, "{far}");
        // The splat set carries the compensation of the newest frame's photons.
        let splat_near: f32 = got
            .splat
            .iter()
            .filter(|p| p.position[0] == 0.0)
            .map(|p| p.power[0])
            .sum();
        assert!((splat_near - 2.0).abs() < 1e-6);
    }

    /// Every change of the photons held is a new generation, unique across rings; reading
    /// is not a change.
    #[test]
    fn generations_change_with_the_photons() {
        let mut ring = PhotonRing::new(2);
        let other = PhotonRing::new(2);
        let mut seen = vec![ring.generation(), other.generation()];
        let _ = (ring.collect(), ring.held(0), ring.frames());
        assert_eq!(ring.generation(), seen[0]);
        ring.push(0, 0, vec![photon(0.0, 1.0)], Vec::new());
        seen.push(ring.generation());
        ring.invalidate_region(Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        });
        seen.push(ring.generation());
        ring.invalidate_light(0);
        seen.push(ring.generation());
        ring.clear();
        seen.push(ring.generation());
        let mut unique = seen.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), seen.len(), "{seen:?}");
    }

    #[test]
    fn lights_are_independent() {
        let mut ring = PhotonRing::new(2);
        let p = vec![photon(0.0, 1.0)];
        ring.push(0, 0, p.clone(), p.clone());
        ring.push(0, 1, p.clone(), p.clone());
        ring.push(1, 1, p.clone(), p);
        ring.invalidate_light(0);
        assert_eq!(ring.held(0), 0);
        assert_eq!(ring.held(1), 2);
        let total: f32 = ring.collect().traced().iter().map(|p| p.power[0]).sum();
        assert!((total - 1.0).abs() < 1e-6);
    }
}
