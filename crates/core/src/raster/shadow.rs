//! Shadow maps: one perspective view per spot light, a cube (six 90°+ faces) per point
//! light, all as layers of one `Depth32Float` 2D array. The lighting pass picks the layer and
//! projects with the same matrices, so rendering and lookup agree by construction.
//! Acne is fought twice: slope-scaled depth bias when rendering, and a normal offset of
//! about one texel at lookup (`direct.wgsl`); edges are softened by PCF there.

pub use super::instances::CullUnits;
use super::instances::Draw;
use super::wgsl;
use crate::gpu::pipeline::{bind_group_layout, pipeline_layout, RenderSpec};
use crate::gpu::raw::{LightRaw, ViewRaw};
use crate::gpu::shaders;
use crate::sampling::Rng;
use crate::scene::light_views::{distant_direction, shadow_views};
use crate::scene::Scene;
use glam::{Mat4, Vec3};

pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Bias in depth units (scaled by the format's resolution) and per unit depth slope.
const DEPTH_BIAS: wgpu::DepthBiasState = wgpu::DepthBiasState {
    constant: 4,
    slope_scale: 2.0,
    clamp: 0.0,
};

/// The shadow views of a scene's lights and the lights' GPU records pointing at them.
pub struct ShadowViews {
    pub lights: Vec<LightRaw>,
    /// World -> clip per shadow-map layer.
    pub matrices: Vec<Mat4>,
}

impl ShadowViews {
    /// The views of `scene`'s lights for `size`² maps. With `jitter` (a progressive pass's
    /// seed) a directional light with a disc of directions casts its shadow along one drawn
    /// from it, hard (its record's `cos_inner` 1), so that the passes' mean has its penumbra;
    /// without, along its axis, the penumbra widened by the disc in the lighting pass.
    pub fn new(scene: &Scene, size: u32, jitter: Option<u64>) -> Self {
        let directions: Vec<Vec3> = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, light)| {
                let u = jitter.map(|seed| Rng::new(seed, 0x5017_D15C, i as u64).next_2d());
                distant_direction(light, u)
            })
            .collect();
        let (layers, matrices) = shadow_views(scene, size, Some(&directions));
        let lights = scene
            .lights
            .iter()
            .zip(layers)
            .zip(&directions)
            .map(|((light, l), dir)| {
                let mut raw = LightRaw {
                    first_layer: l.first_layer,
                    layers: l.layers,
                    texel_scale: l.texel_scale,
                    depth_extent: l.depth_extent,
                    ..light.to_raw()
                };
                if !light.is_local() {
                    raw.direction = (*dir).into();
                    if jitter.is_some() {
                        raw.cos_inner = 1.0;
                        raw.cos_outer = 1.0;
                    }
                }
                raw
            })
            .collect();
        ShadowViews { lights, matrices }
    }
}

/// A `layers`-deep array of `size`² shadow maps: the texture's views per layer (render
/// targets) and over the whole array (for lookups), and the texture (its layers can be
/// copied out, for tests).
pub fn layered_maps(
    device: &wgpu::Device,
    label: &str,
    size: u32,
    layers: u32,
) -> (Vec<wgpu::TextureView>, wgpu::TextureView, wgpu::Texture) {
    let maps = crate::gpu::create_texture(
        device,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        },
    );
    let layer_views = (0..layers)
        .map(|i| {
            maps.create_view(&wgpu::TextureViewDescriptor {
                label: Some(label),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: i,
                array_layer_count: Some(1),
                ..Default::default()
            })
        })
        .collect();
    let array = maps.create_view(&wgpu::TextureViewDescriptor {
        label: Some(label),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (layer_views, array, maps)
}

/// Pipeline of the shadow pass (depth only).
pub struct ShadowPass {
    pub pipeline: wgpu::RenderPipeline,
    /// For scenes with alpha-masked materials: discards cut-out fragments (group 1: the
    /// textures).
    pub masked: wgpu::RenderPipeline,
    /// Group 0: the layer's view (uniform, dynamic offset).
    pub layout: wgpu::BindGroupLayout,
}

impl ShadowPass {
    /// The bind group of a set of shadow-map layers: `views` holds one view record per
    /// layer (read at a dynamic offset).
    pub fn view_group(
        &self,
        device: &wgpu::Device,
        label: &str,
        views: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        crate::gpu::create_bind_group(
            device,
            &wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &self.layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: crate::gpu::layout::view_binding(views),
                }],
            },
        )
    }

    pub fn new(device: &wgpu::Device, textures: &wgpu::BindGroupLayout) -> Self {
        let layout = bind_group_layout(device, "shadow bind group layout", &[super::view_entry(0)]);
        let shadow_layout = pipeline_layout(device, "shadow pipeline layout", &[&layout]);
        let module = shaders::module(device, "shadow shader", &[shaders::COMMON, wgsl::SHADOW]);
        let masked_layout = pipeline_layout(
            device,
            "masked shadow pipeline layout",
            &[&layout, textures],
        );
        let masked_module = shaders::module(
            device,
            "masked shadow shader",
            &[shaders::COMMON, shaders::TEXTURE, wgsl::SHADOW_MASKED],
        );
        let attributes = super::gbuffer::VERTEX_ATTRIBUTES;
        let masked_attributes = [attributes[0], attributes[3], attributes[4]];
        let instance = super::gbuffer::INSTANCE_ATTRIBUTES;
        let masked_instance = [
            instance[0],
            instance[1],
            instance[2],
            instance[3],
            instance[7],
        ];
        let masked = RenderSpec {
            buffers: &[
                Some(wgpu::VertexBufferLayout {
                    attributes: &masked_attributes,
                    ..super::gbuffer::vertex_layout()
                }),
                Some(wgpu::VertexBufferLayout {
                    attributes: &masked_instance,
                    ..super::gbuffer::instance_layout()
                }),
            ],
            depth_stencil: Some(depth_state()),
            ..RenderSpec::new(
                "masked shadow pipeline",
                &masked_layout,
                &masked_module,
                "vs_main",
                Some("fs_main"),
            )
        }
        .create(device);
        let pipeline = RenderSpec {
            buffers: &[
                Some(wgpu::VertexBufferLayout {
                    attributes: &super::gbuffer::VERTEX_ATTRIBUTES[..1],
                    ..super::gbuffer::vertex_layout()
                }),
                Some(wgpu::VertexBufferLayout {
                    attributes: &super::gbuffer::INSTANCE_ATTRIBUTES[..4],
                    ..super::gbuffer::instance_layout()
                }),
            ],
            depth_stencil: Some(depth_state()),
            ..RenderSpec::new("shadow pipeline", &shadow_layout, &module, "vs_main", None)
        }
        .create(device);
        ShadowPass {
            pipeline,
            masked,
            layout,
        }
    }

    /// The views to render, one per layer, for the view uniform buffer.
    pub fn views(views: &ShadowViews) -> Vec<ViewRaw> {
        views
            .matrices
            .iter()
            .map(|m| ViewRaw::new(*m, Vec3::ZERO, 1.0))
            .collect()
    }

    /// Records one layer's pass.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        layer: &wgpu::TextureView,
        bind_group: &wgpu::BindGroup,
        view_offset: u32,
        geometry: &super::Geometry,
        draws: Option<&[Draw]>,
        masks: Option<&wgpu::BindGroup>,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let tile = Tile {
            viewport: None,
            view_offset,
            draws,
        };
        let target = (layer, bind_group, geometry, masks);
        self.record_tiles(encoder, target, &[tile], timestamps);
    }

    /// Records one layer's pass drawing several views, each into its own rectangle of the
    /// layer (an atlas of shadow maps: the lookup's matrix maps into the rectangle, see
    /// `raster::vpl::tile_matrix`). The layer is cleared once.
    pub fn record_tiles(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (layer, bind_group, geometry, masks): TileTarget<'_>,
        tiles: &[Tile<'_>],
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let ops = (wgpu::LoadOp::Clear(1.0), wgpu::StoreOp::Store);
        let mut pass = super::depth_pass(encoder, "shadow pass", layer, ops, timestamps);
        match masks {
            Some(textures) => {
                pass.set_pipeline(&self.masked);
                pass.set_bind_group(1, textures, &[]);
            }
            None => pass.set_pipeline(&self.pipeline),
        }
        for t in tiles {
            if let Some([x, y, w, h]) = t.viewport {
                pass.set_viewport(x, y, w, h, 0.0, 1.0);
                pass.set_scissor_rect(x as u32, y as u32, w as u32, h as u32);
            }
            pass.set_bind_group(0, bind_group, &[t.view_offset]);
            geometry.draw(&mut pass, t.draws);
        }
    }
}

/// One view of a shadow-map layer's pass: its rectangle of the layer (x, y, width, height
/// in texels; `None`: the whole layer), its view record's offset and its draws.
pub struct Tile<'a> {
    pub viewport: Option<[f32; 4]>,
    pub view_offset: u32,
    pub draws: Option<&'a [Draw]>,
}

/// What a shadow-map layer's pass draws into and with: the layer, the views' bind group,
/// the scene's geometry and its alpha masks (if any).
pub type TileTarget<'a> = (
    &'a wgpu::TextureView,
    &'a wgpu::BindGroup,
    &'a super::Geometry,
    Option<&'a wgpu::BindGroup>,
);

/// Whether the box `lo..hi` may reach into the view of clip matrix `m` (world -> clip, depth
/// 0..1): false only when all eight corners lie outside one clip plane, so every triangle
/// inside the box is clipped away entirely and drawing it changes nothing.
pub fn box_in_view(m: &Mat4, lo: Vec3, hi: Vec3) -> bool {
    super::instances::clip_box(m, lo, hi) != super::instances::Clip::Outside
}

impl crate::gpu::Pipelines for ShadowPass {
    fn create(ctx: &crate::gpu::GpuContext) -> Self {
        ShadowPass::new(
            &ctx.device,
            &super::textures::TexturesLayout::get(ctx).layout,
        )
    }
}

/// The shadow maps' depth test: nearest wins, written, with the slope-scaled bias.
fn depth_state() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: FORMAT,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::Less),
        stencil: Default::default(),
        bias: DEPTH_BIAS,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;
    use crate::scene::light_views::{look_to, square_perspective};

    /// Culling is conservative: for random boxes against a cube face's view, a box judged
    /// outside has no point (of 64 random ones and its corners) inside the view volume,
    /// and both outcomes occur.
    #[test]
    fn culled_boxes_are_outside_the_view() {
        let m = square_perspective(1.05, 0.01, 10.0) * look_to(Vec3::ZERO, Vec3::X, Vec3::Y);
        let inside = |p: Vec3| {
            let c = m * p.extend(1.0);
            c.w > 0.0 && c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w
        };
        let mut rng = Rng::new(3, 0, 0);
        let (mut culled, mut kept) = (0, 0);
        for _ in 0..2000 {
            let a = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 8.0 - 4.0;
            let b = a + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0;
            if box_in_view(&m, a, b) {
                kept += 1;
                continue;
            }
            culled += 1;
            for _ in 0..64 {
                let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let p = a + (b - a) * t;
                assert!(!inside(p), "culled box {a} {b} holds {p}");
            }
        }
        assert!(culled > 100 && kept > 100, "{culled} culled, {kept} kept");
    }

    /// On `dense-cornell` (a point light: six faces) the faces draw far fewer triangles
    /// than six times the scene (measured 1.75 times), and every triangle is drawn into
    /// some face (the light sees all of the room).
    #[test]
    fn cube_faces_draw_only_what_they_see() {
        let scene = crate::scene::bench::dense_cornell();
        let views = ShadowViews::new(&scene, 1024, None);
        let draws = CullUnits::of(&scene).draws(&views.matrices);
        assert_eq!(draws.len(), 6);
        let drawn: u64 = draws
            .iter()
            .map(|d| super::super::instances::triangles_drawn(d))
            .sum();
        let n = scene.triangle_count() as u64;
        assert!(drawn < 2 * n, "{drawn} of 6 x {n}");
        // Every triangle is drawn into some face.
        let cull = CullUnits::of(&scene);
        let mut seen = vec![false; n as usize];
        for d in draws.iter().flatten() {
            let mesh = cull
                .meshes()
                .iter()
                .find(|m| m.vertices.contains(&d.vertices.start))
                .expect("a mesh's vertices");
            for i in d.instances.clone() {
                let first = scene.objects[i as usize].triangles.start;
                let t = |v: u32| (first + (v - mesh.vertices.start) / 3) as usize;
                seen[t(d.vertices.start)..t(d.vertices.end)].fill(true);
            }
        }
        assert!(seen.iter().all(|&s| s), "a triangle is drawn into no face");
        eprintln!("dense-cornell: {drawn} triangles drawn into 6 faces, {n} in the scene");
    }
}
