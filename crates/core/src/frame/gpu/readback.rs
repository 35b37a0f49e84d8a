//! The end of a GPU method's frame: which render targets to read back for the images asked
//! for, and the frame's output assembled from them (radiance and the first-hit AOVs), the
//! same for `direct`, `ispm` and `bidir`.

use super::{rgb_image, Readback, Targets};
use crate::frame::{Images, RenderOutput, RenderStats};
use crate::image::Image;
use crate::raster::oct_decode;
use crate::scene::Scene;
use glam::{Vec2, Vec3, Vec4};

/// The textures to read back for `images` (`accum` for the ISPM direct AOV; `indirect`
/// when the method has one).
pub(crate) fn readback_names(images: Images, indirect: bool) -> Vec<&'static str> {
    let mut names = vec!["radiance"];
    if images.aovs || images.extras {
        names.extend(["position", "normals", "albedo"]);
    }
    if images.extras {
        names.push("accum");
        if indirect {
            names.push("indirect");
        }
    }
    names
}

/// Radiance (in the forms read back) and the first-hit AOVs from the read-back textures.
pub(crate) fn assemble(
    scene: &Scene,
    t: &Targets,
    data: &Readback,
    stats: RenderStats,
) -> RenderOutput {
    let (w, h) = (t.width, t.height);
    let empty = || Image::new(0, 0);
    let mut out = RenderOutput {
        radiance: data
            .get("radiance")
            .map(|r| rgb_image(w, h, r))
            .unwrap_or_else(empty),
        albedo: empty(),
        normal: empty(),
        position: empty(),
        depth: Vec::new(),
        caustics: empty(),
        aovs: Vec::new(),
        stats,
        display: data.display.clone(),
        radiance_half: data.half.clone(),
    };
    if let (Some(position), Some(normals), Some(albedo)) = (
        data.get("position"),
        data.get("normals"),
        data.get("albedo"),
    ) {
        let cam = &scene.camera;
        out.albedo = Image::new(w, h);
        out.normal = Image::new(w, h);
        out.position = Image::new(w, h);
        out.caustics = Image::new(w, h);
        out.depth = vec![0.0; (w * h) as usize];
        for i in 0..(w * h) as usize {
            if position[i].w > 0.0 {
                let p = position[i].truncate();
                out.position.pixels[i] = p;
                out.normal.pixels[i] = oct_decode(Vec2::new(normals[i].x, normals[i].y));
                out.albedo.pixels[i] = albedo[i].truncate();
                out.depth[i] = (p - cam.position).dot(cam.forward);
            }
        }
    }
    out
}

/// The accumulated direct light divided by its weights.
pub(crate) fn normalized(t: &Targets, accum: &[Vec4]) -> Image {
    let mut img = Image::new(t.width, t.height);
    for (d, a) in img.pixels.iter_mut().zip(accum) {
        *d = if a.w > 0.0 {
            a.truncate() / a.w
        } else {
            Vec3::ZERO
        };
    }
    img
}
