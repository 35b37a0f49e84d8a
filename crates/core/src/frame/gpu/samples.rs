//! The direct pass's sampled lights: points drawn on the emitters by power and directions
//! drawn from the sky, each with its shadow layers in one array of maps a quarter of the
//! lights' side, their records, and the environment's radiance and irradiance tables.
//!
//! The samples are drawn from a seed: the options' seed for ordinary frames (a still view
//! re-draws and re-renders nothing), a new one per progressive pass (their mean converges
//! to the emitters' and the sky's exact direct light, bar the shadow maps' own bias).
//! Shadow layers: six per emitter point (a cube; for a one-sided emitter the faces wholly
//! behind it are not rendered: they are never looked up), one orthographic view per sky
//! direction.

use crate::error::{Error, Result};
use crate::gpu::raw::ViewRaw;
use crate::gpu::timer::Timer;
use crate::gpu::{self, GpuContext, Pipelines};
use crate::raster::direct::{
    DirectParamsRaw, SampledLightRaw, MAX_GROUPS, MAX_POLYGONS, POLYGON_TEXELS, SAMPLE_TEXELS,
    TREE_ROW,
};
use crate::raster::shadow::{self, CullUnits, ShadowPass};
use crate::raster::{buffer_init, Geometry, VIEW_SIZE};
use crate::scene::emitters::{
    EmitterPoint, EmitterPolygon, Emitters, PolygonGroups, TREE_ENTRY_TEXELS,
};
use crate::scene::light_views::{self, orthographic_view, CUBE_FACES};
use crate::scene::{Environment, Scene};
use bytemuck::Zeroable;
use glam::{Mat4, Vec3};
use std::f32::consts::PI;

/// Columns of the irradiance table (longitude); its rows: half that plus one, pole to pole.
const IRRADIANCE_SIDE: u32 = 64;
/// Extra field of view of the sampled lights' shadow views, in texels on each side.
const MARGIN_TEXELS: f32 = 4.0;

/// How many lights to draw and where: from the options and the method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SampleCounts {
    /// Points drawn on the emitters per frame.
    pub area: u32,
    /// Directions drawn from the sky per frame (0: the method lights the sky otherwise).
    pub sky: u32,
    /// Side of their shadow maps.
    pub size: u32,
    /// Uncovered samples see the environment (false: the method draws it itself).
    pub background: bool,
}

impl SampleCounts {
    /// The counts `scene` needs: no points without emitters, no directions without sky.
    pub fn of(scene: &Scene, requested: SampleCounts) -> SampleCounts {
        let emits = scene.materials.iter().any(|m| m.emits());
        let sky = scene.environment.is_some();
        SampleCounts {
            area: if emits { requested.area } else { 0 },
            sky: if sky { requested.sky } else { 0 },
            size: requested.size,
            background: sky && requested.background,
        }
    }

    fn layers(&self) -> u32 {
        6 * self.area + self.sky
    }
}

/// The sampled lights' GPU resources and what was drawn into them.
pub(crate) struct LightSamples {
    pub counts: SampleCounts,
    records: wgpu::Texture,
    pub records_view: wgpu::TextureView,
    matrices: wgpu::Texture,
    pub matrices_view: wgpu::TextureView,
    views: wgpu::Buffer,
    view_group: wgpu::BindGroup,
    layer_views: Vec<wgpu::TextureView>,
    pub array: wgpu::TextureView,
    #[cfg_attr(not(test), allow(dead_code))]
    maps: wgpu::Texture,
    pub env_view: wgpu::TextureView,
    pub irradiance_view: wgpu::TextureView,
    pub params: wgpu::Buffer,
    params_raw: DirectParamsRaw,
    polygons: wgpu::Texture,
    pub polygons_view: wgpu::TextureView,
    /// The emitting triangles (kept until geometry or materials change) and the polygon
    /// groups the polygons texture holds.
    emitters: Option<(Emitters, PolygonGroups)>,
    /// The per-pixel emitter tree (`scene::emitters::PixelTree`), its capacity in entries
    /// (sized for the scene's emitters when made) and the (nodes, triangles) it holds
    /// ((0, 0): none, or more than the capacity after an edit).
    tree: wgpu::Texture,
    pub tree_view: wgpu::TextureView,
    tree_capacity: u32,
    tree_held: (u32, u32),
    /// CPU copies of the layers' matrices (for culling), and which layers to render.
    clip: Vec<Mat4>,
    render: Vec<bool>,
    /// The seed and near-field scale of the samples drawn; `None`: to be drawn.
    drawn: Option<(u64, f32)>,
    shadows_stale: bool,
}

/// An `Rgba32Float` texture of `w`×`h` texels, with `data` (row-major) when given.
fn float_texture(
    ctx: &GpuContext,
    label: &str,
    w: u32,
    h: u32,
    data: Option<&[[f32; 4]]>,
) -> wgpu::Texture {
    let texture = gpu::texture_2d(
        &ctx.device,
        label,
        w,
        h,
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    if let Some(data) = data {
        gpu::write_rows(ctx, &texture, label, w, data);
    }
    texture
}

/// The environment's radiance table and its irradiance table (1×1 black without one).
fn env_tables(ctx: &GpuContext, env: Option<&Environment>) -> (wgpu::Texture, wgpu::Texture) {
    let rgba =
        |v: &[Vec3]| -> Vec<[f32; 4]> { v.iter().map(|t| t.extend(0.0).to_array()).collect() };
    match env {
        Some(e) => {
            let (w, h, texels, _) = e.gpu_table();
            let (iw, ih) = (IRRADIANCE_SIDE, IRRADIANCE_SIDE / 2 + 1);
            let irradiance = e.irradiance_table(iw, ih);
            (
                float_texture(ctx, "environment radiance", w, h, Some(&rgba(&texels))),
                float_texture(
                    ctx,
                    "environment irradiance",
                    iw,
                    ih,
                    Some(&rgba(&irradiance)),
                ),
            )
        }
        None => {
            let black = [[0.0f32; 4]];
            (
                float_texture(ctx, "environment radiance", 1, 1, Some(&black)),
                float_texture(ctx, "environment irradiance", 1, 1, Some(&black)),
            )
        }
    }
}

/// Each polygon group's [first, end) emitter points and [first, end) polygons.
type GroupRanges = [[u32; 4]; MAX_GROUPS];

impl LightSamples {
    /// Resources for `counts` (already fitted to the scene by [`SampleCounts::of`]), or a
    /// setting error when the GPU cannot hold their shadow maps.
    pub fn new(ctx: &GpuContext, scene: &Scene, counts: SampleCounts) -> Result<Self> {
        let device = &ctx.device;
        let layers = counts.layers().max(1);
        let max_layers = device.limits().max_texture_array_layers;
        if layers > max_layers {
            return Err(Error::setting(
                "area_samples",
                format!(
                    "the sampled lights need {layers} shadow-map layers; the GPU allows {max_layers}"
                ),
            ));
        }
        let bytes = layers as u64 * counts.size as u64 * counts.size as u64 * 4;
        crate::memory::check(|| "the sampled lights' shadow maps".to_string(), bytes)?;
        let rows = (counts.area + counts.sky).max(1);
        let records = float_texture(ctx, "sampled lights", SAMPLE_TEXELS, rows, None);
        let matrices = float_texture(ctx, "sampled light matrices", 4, layers, None);
        let views = buffer_init(
            ctx,
            "sampled light views",
            &vec![0u8; layers as usize * VIEW_SIZE as usize],
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let view_group =
            ShadowPass::get(ctx).view_group(device, "sampled light shadow bind group", &views);
        let (layer_views, array, maps) =
            shadow::layered_maps(device, "sampled light shadow maps", counts.size, layers);
        let (env, irradiance) = env_tables(ctx, scene.environment.as_deref());
        let rows = if counts.area > 0 {
            MAX_POLYGONS as u32
        } else {
            1
        };
        let polygons = float_texture(ctx, "emitter polygons", POLYGON_TEXELS, rows, None);
        // The tree of the emitters outside the polygon groups: at most 2n − 1 nodes and n
        // triangles for n emitting triangles.
        let emitting = if counts.area > 0 {
            Emitters::of(scene).len() as u32
        } else {
            0
        };
        let tree_rows = (3 * emitting).div_ceil(TREE_ROW).max(1);
        let tree = float_texture(
            ctx,
            "emitter tree",
            TREE_ROW * TREE_ENTRY_TEXELS,
            tree_rows,
            None,
        );
        let params_raw = DirectParamsRaw::zeroed();
        let params = buffer_init(
            ctx,
            "direct params",
            bytemuck::bytes_of(&params_raw),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        Ok(LightSamples {
            counts,
            records_view: view(&records),
            records,
            matrices_view: view(&matrices),
            matrices,
            views,
            view_group,
            layer_views,
            array,
            maps,
            env_view: view(&env),
            irradiance_view: view(&irradiance),
            params,
            params_raw,
            polygons_view: view(&polygons),
            polygons,
            tree_view: view(&tree),
            tree,
            tree_capacity: if emitting > 0 {
                tree_rows * TREE_ROW
            } else {
                0
            },
            tree_held: (0, 0),
            emitters: None,
            clip: Vec::new(),
            render: Vec::new(),
            drawn: None,
            shadows_stale: false,
        })
    }

    /// Replaces the environment's radiance and irradiance tables (the scene's lighting
    /// changed; the bind groups that hold the old views are to be made again) and draws the
    /// samples anew at the next frame.
    pub fn set_environment(&mut self, ctx: &GpuContext, env: Option<&Environment>) {
        let (radiance, irradiance) = env_tables(ctx, env);
        self.env_view = radiance.create_view(&Default::default());
        self.irradiance_view = irradiance.create_view(&Default::default());
        self.drawn = None;
    }

    /// Whether the emitters found so far form polygon groups (their light in closed form).
    pub fn has_polygon_groups(&self) -> bool {
        self.emitters.as_ref().is_some_and(|(_, g)| g.groups > 0)
    }

    /// Whether some polygon group found so far is round (a sphere).
    pub fn has_round_groups(&self) -> bool {
        self.emitters
            .as_ref()
            .is_some_and(|(_, g)| g.polygons.iter().any(|p| p.round.is_some()))
    }

    /// The samples are to be drawn again at the next frame (the lights, the geometry or the
    /// materials changed); `emitters`: the emitting triangles may have changed too.
    pub fn invalidate(&mut self, emitters: bool) {
        self.drawn = None;
        if emitters {
            self.emitters = None;
        }
    }

    /// Draws the samples of `seed` (their near-field discs' radii scaled by `disc_scale`)
    /// unless they are drawn already, and uploads them; `ratio`: the ratio estimator (not
    /// in progressive passes, whose mean must converge). True when it drew.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        seed: u64,
        disc_scale: f32,
        ratio: bool,
    ) -> bool {
        let c = self.counts;
        if c.area + c.sky == 0 || self.drawn == Some((seed, disc_scale)) {
            return false;
        }
        if self.emitters.is_none() && c.area > 0 {
            self.upload_emitters(ctx, scene, c.area);
        }
        let (points, polygons, group_ranges) = self.points(scene, seed);
        let mut records = Vec::new();
        self.clip.clear();
        self.render.clear();
        self.point_records(scene, points, disc_scale, &mut records);
        let area = records.len() as u32;
        self.sky_records(scene, seed, &mut records);
        let sky = records.len() as u32 - area;
        let texels: Vec<[f32; 4]> = records.iter().flat_map(|r| r.texels()).collect();
        gpu::write_rows(ctx, &self.records, "sampled lights", SAMPLE_TEXELS, &texels);
        let columns: Vec<[f32; 4]> = self
            .clip
            .iter()
            .flat_map(|m| m.to_cols_array_2d())
            .collect();
        gpu::write_rows(ctx, &self.matrices, "sampled light matrices", 4, &columns);
        let views: Vec<ViewRaw> = self
            .clip
            .iter()
            .map(|m| ViewRaw::new(*m, Vec3::ZERO, 1.0))
            .collect();
        if !views.is_empty() {
            gpu::write_buffer(
                &ctx.queue,
                "sampled light views",
                &self.views,
                0,
                bytemuck::cast_slice(&views),
            );
        }
        let params = DirectParamsRaw {
            polygons,
            groups: self.emitters.as_ref().map_or(0, |(_, g)| g.groups),
            group_ranges,
            ratio: ratio as u32,
            tree_nodes: self.tree_held.0,
            tree_triangles: self.tree_held.1,
            pixel_samples: c.area,
            seed: (seed ^ (seed >> 32)) as u32,
            ..params_of(scene, c, area, sky)
        };
        if params != self.params_raw {
            gpu::write_buffer(
                &ctx.queue,
                "direct params",
                &self.params,
                0,
                bytemuck::bytes_of(&params),
            );
            self.params_raw = params;
        }
        self.drawn = Some((seed, disc_scale));
        self.shadows_stale = true;
        true
    }

    /// Finds the emitters' polygon groups and uploads their polygons and the per-pixel tree
    /// of the others (once, until [`Self::invalidate`] drops them).
    fn upload_emitters(&mut self, ctx: &GpuContext, scene: &Scene, area: u32) {
        let emitters = Emitters::of(scene);
        let groups = emitters.polygon_groups(scene, (MAX_POLYGONS, MAX_GROUPS), area);
        let texels: Vec<[f32; 4]> = groups.polygons.iter().flat_map(polygon_texels).collect();
        gpu::write_rows(
            ctx,
            &self.polygons,
            "emitter polygons",
            POLYGON_TEXELS,
            &texels,
        );
        self.tree_held = self.write_tree(ctx, scene, &emitters, &groups);
        self.emitters = Some((emitters, groups));
    }

    /// The frame's emitter points of `seed` (the polygon groups' first, group by group,
    /// then the others'), the number of polygons, and each group's [points, polygons)
    /// ranges.
    fn points(
        &self,
        scene: &Scene,
        seed: u64,
    ) -> (Vec<(Option<u32>, EmitterPoint)>, u32, GroupRanges) {
        let mut polygons = 0;
        let mut group_ranges = [[0u32; 4]; MAX_GROUPS];
        let mut points = Vec::new();
        if let Some((e, groups)) = &self.emitters {
            points = e.stratified_points(scene, groups, seed);
            polygons = groups.polygons.len() as u32;
            for (g, range) in group_ranges
                .iter_mut()
                .enumerate()
                .take(groups.groups as usize)
            {
                let polygons = groups.polygons_of(g as u32);
                range[2..].copy_from_slice(&[polygons.start, polygons.end]);
            }
            for (i, (g, _)) in points.iter().enumerate() {
                if let Some(range) = g.map(|g| &mut group_ranges[g as usize]) {
                    if range[1] == 0 {
                        range[0] = i as u32;
                    }
                    range[1] = i as u32 + 1;
                }
            }
        }
        (points, polygons, group_ranges)
    }

    /// A cube of shadow views and a record for each emitter point.
    fn point_records(
        &mut self,
        scene: &Scene,
        points: Vec<(Option<u32>, EmitterPoint)>,
        disc_scale: f32,
        records: &mut Vec<SampledLightRaw>,
    ) {
        let c = self.counts;
        let (lo, hi) = light_views::bounds(scene);
        for (_, p) in points {
            // Just off the emitter, so that its own surface is behind the cube's centre.
            let origin = p.position + p.normal * (1e-4 * (hi - lo).length());
            let (faces, texel_scale) = crate::raster::vpl::cube_views(origin, lo, hi, c.size);
            let first_layer = self.clip.len() as u32;
            for (m, (forward, up)) in faces.iter().zip(CUBE_FACES) {
                self.clip.push(*m);
                self.render
                    .push(p.two_sided || faces_front(forward, up, p.normal));
            }
            records.push(SampledLightRaw::Point {
                position: origin,
                first_layer,
                normal: p.normal,
                texel_scale,
                intensity: p.intensity,
                disc_r2: p.area / PI * disc_scale * disc_scale,
                two_sided: p.two_sided,
            });
        }
    }

    /// An orthographic shadow view and a record for each of the sky's directions of `seed`.
    fn sky_records(&mut self, scene: &Scene, seed: u64, records: &mut Vec<SampledLightRaw>) {
        let c = self.counts;
        let area_points = records.len();
        if let Some(env) = scene.environment.as_deref().filter(|_| c.sky > 0) {
            let grow = 1.0 + 2.0 * MARGIN_TEXELS / c.size as f32;
            for d in env.directions(c.sky, seed) {
                // The direct pass computes this layer as 6 × points + k (direct_shade.wgsl).
                debug_assert_eq!(
                    self.clip.len(),
                    6 * area_points + records.len() - area_points
                );
                let (m, side, depth) = orthographic_view(-d.towards, scene.bounds(), grow);
                records.push(SampledLightRaw::Sky {
                    towards: d.towards,
                    layer: self.clip.len() as u32,
                    irradiance: d.irradiance,
                    texel: side / c.size as f32,
                    depth,
                    tan_cone: crate::raster::sky_cone::tan_half_angle(d.solid_angle),
                });
                self.clip.push(m);
                self.render.push(true);
            }
        }
    }

    /// Writes the per-pixel tree of the emitters outside `groups` into its texture; the
    /// (nodes, triangles) written, (0, 0) when there is none or it exceeds the capacity
    /// (those emitters are then lit by the frame's points alone).
    fn write_tree(
        &self,
        ctx: &GpuContext,
        scene: &Scene,
        emitters: &Emitters,
        groups: &PolygonGroups,
    ) -> (u32, u32) {
        let Some(tree) = emitters.pixel_tree(scene, groups) else {
            return (0, 0);
        };
        if tree.entries() > self.tree_capacity {
            return (0, 0);
        }
        let mut texels = tree.texels;
        let row = (TREE_ROW * TREE_ENTRY_TEXELS) as usize;
        texels.resize(texels.len().next_multiple_of(row), [0.0; 4]);
        gpu::write_rows(
            ctx,
            &self.tree,
            "emitter tree",
            TREE_ROW * TREE_ENTRY_TEXELS,
            &texels,
        );
        (tree.nodes, tree.triangles)
    }

    /// Renders the sampled lights' shadow maps if they were drawn anew (each layer only the
    /// triangle runs that reach into its view).
    pub fn record_shadows(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
        geometry: &Geometry,
        cull: &CullUnits,
        masks: Option<&wgpu::BindGroup>,
    ) {
        if !std::mem::take(&mut self.shadows_stale) {
            return;
        }
        let pass = ShadowPass::get(ctx);
        let draws = cull.draws(&self.clip);
        for (layer, view) in self.layer_views.iter().enumerate().take(self.clip.len()) {
            if !self.render[layer] {
                continue;
            }
            let offset = (layer as u64 * VIEW_SIZE) as u32;
            let ts = timer.pass("sampled light shadow maps");
            pass.record(
                encoder,
                view,
                &self.view_group,
                offset,
                geometry,
                draws.get(layer).map(|d| d.as_slice()),
                masks,
                ts,
            );
        }
    }
}

/// A polygon's row of the polygons texture ([`POLYGON_TEXELS`] texels): three corners (w
/// of the first: 1 when two-sided; of the second: 1 for a quad; of the third: its
/// [`EmitterPolygon::in_plane_bound`]), the radiance, and a quad's fourth corner; a round
/// emitter's as `raster::direct::round_texels` writes it.
fn polygon_texels(t: &EmitterPolygon) -> [[f32; 4]; POLYGON_TEXELS as usize] {
    let [a, b, c] = t.corners;
    let side = t.two_sided as u32 as f32;
    if let Some(r) = t.round {
        return crate::raster::direct::round_texels(r, side, t.radiance);
    }
    let quad = t.fourth.is_some() as u32 as f32;
    [
        a.extend(side).to_array(),
        b.extend(quad).to_array(),
        c.extend(t.in_plane_bound()).to_array(),
        t.radiance.extend(0.0).to_array(),
        t.fourth.unwrap_or(c).extend(0.0).to_array(),
    ]
}

/// Whether any of the cube face (`forward`, `up`)'s frustum lies in front of a surface of
/// normal `n` (its corner directions, at the margin's widening, reach dot(·, n) > 0).
fn faces_front(forward: Vec3, up: Vec3, n: Vec3) -> bool {
    let right = forward.cross(up);
    let t = 1.1;
    [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
        .iter()
        .any(|(a, b)| (forward + right * (a * t) + up * (b * t)).dot(n) > 0.0)
}

/// The direct pass's parameters for `area` points and `sky` directions.
fn params_of(scene: &Scene, c: SampleCounts, area: u32, sky: u32) -> DirectParamsRaw {
    let (env_cos, env_sin) = scene
        .environment
        .as_ref()
        .map_or((1.0, 0.0), |e| e.rotation());
    DirectParamsRaw {
        area_count: area,
        sky_count: sky,
        background: c.background as u32,
        ratio: 0,
        env_cos,
        env_sin,
        polygons: 0,
        groups: 0,
        tree_nodes: 0,
        tree_triangles: 0,
        pixel_samples: 0,
        seed: 0,
        group_ranges: [[0; 4]; MAX_GROUPS],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::timer::Timer;
    use std::collections::HashMap;

    /// Every sky direction's shadow layer holds the depth of the scene seen along its own
    /// direction: a floor alone (a 6×6 quad at y = −0.5) under a constant sky, four
    /// directions, each layer's texels against the floor plane's depth along that layer's
    /// view (ray through the texel centre, ndc z where it meets the plane; 1 where it misses
    /// the quad). At or behind it by at most the slope-scaled depth bias on 98% of the
    /// texels (the quad's edge texels are partly covered). On an H100 the sky's layers after the first were falsely shadowed
    /// (docs/gpu-check.md): this tells which layer holds what, and prints for each layer
    /// the view whose depth it matches best.
    #[test]
    fn sky_layers_hold_the_depth_of_their_own_view() {
        let json = r#"{"camera": {"position": [0, 0.8, 3], "look_at": [0, -0.1, 0], "fov": 40, "width": 8, "height": 8},
          "materials": {"m": {"diffuse": [0.5, 0.5, 0.5]}},
          "objects": [{"shape": {"type": "quad", "size": [6, 6]}, "transform": {"translate": [0, -0.5, 0]}, "material": "m"}],
          "environment": {"radiance": [1, 1, 1]}}"#;
        let scene = Scene::from_json(json, "floor", &HashMap::new()).expect("scene");
        let ctx = crate::gpu::context(None).expect("a GPU adapter");
        for (sky, size) in [(4, 64), (16, 256)] {
            check_sky_layers(&ctx, &scene, sky, size);
        }
    }

    fn check_sky_layers(ctx: &GpuContext, scene: &Scene, sky: u32, size: u32) {
        let counts = SampleCounts {
            area: 0,
            sky,
            size,
            background: false,
        };
        let mut samples = LightSamples::new(ctx, scene, counts).expect("samples");
        assert!(samples.prepare(ctx, scene, 1, 1.0, true));
        let cull = CullUnits::of(scene);
        let geometry = Geometry::upload(ctx, scene, &cull);
        let mut timer = Timer::new(ctx, sky);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        samples.record_shadows(ctx, &mut encoder, &mut timer, &geometry, &cull, None);
        let layers = samples.clip.len() as u32;
        let row = (size * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let buffer = crate::gpu::readback_buffer(
            &ctx.device,
            "sky layers",
            row as u64 * size as u64 * layers as u64,
        );
        encoder.copy_texture_to_buffer(
            samples.maps.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(size),
                },
            },
            wgpu::Extent3d {
                width: size,
                height: size,
                depth_or_array_layers: layers,
            },
        );
        ctx.queue.submit([encoder.finish()]);
        let bytes = ctx.read_buffer(&buffer).expect("readback");
        let stored = |k: u32, x: u32, y: u32| -> f32 {
            let at = (k * size + y) as usize * row as usize + x as usize * 4;
            f32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
        };
        // The floor's depth along view `m` through texel (x, y) (1: the ray misses it).
        let expected = |m: &Mat4, x: u32, y: u32| -> f32 {
            let ndc = glam::Vec2::new(
                (x as f32 + 0.5) / size as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / size as f32 * 2.0,
            );
            let inv = m.inverse();
            let a = inv.project_point3(ndc.extend(0.0));
            let b = inv.project_point3(ndc.extend(1.0));
            let t = (-0.5 - a.y) / (b.y - a.y);
            let p = a + (b - a) * t;
            if !(0.0..=1.0).contains(&t) || p.x.abs() > 3.0 || p.z.abs() > 3.0 {
                1.0
            } else {
                t
            }
        };
        // Stored at or behind the plane by at most the slope-scaled bias (2 × the depth's
        // change per texel, plus its constant part).
        let agree = |k: u32, m: &Mat4| -> f64 {
            let mut n = 0;
            for y in 0..size {
                for x in 0..size {
                    let e = expected(m, x, y);
                    let slope = (expected(m, x + 1, y) - e)
                        .abs()
                        .max((expected(m, x, y + 1) - e).abs());
                    let d = stored(k, x, y) - e;
                    n += (d > -1e-4 && d < 2.5 * slope + 1e-4) as u32;
                }
            }
            n as f64 / (size * size) as f64
        };
        let mut worst = 1.0f64;
        for k in 0..layers {
            let own = agree(k, &samples.clip[k as usize]);
            let best = (0..layers)
                .map(|j| (j, agree(k, &samples.clip[j as usize])))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .expect("a layer");
            eprintln!(
                "{sky} directions, {size}²: sky layer {k}: {:.1}% of texels hold its own view's depth; best match: view {} ({:.1}%)",
                100.0 * own,
                best.0,
                100.0 * best.1
            );
            worst = worst.min(own);
        }
        assert!(
            worst > 0.98,
            "{sky} directions: a sky layer holds another depth ({worst})"
        );
    }

    /// A one-sided emitter facing down (−y) renders the five faces that see below it and
    /// skips +y, as one tilted a little; one facing a cube corner needs all six.
    #[test]
    fn faces_behind_a_one_sided_emitter_are_skipped() {
        let faces = |n: Vec3| -> Vec<bool> {
            CUBE_FACES
                .iter()
                .map(|(f, u)| faces_front(*f, *u, n.normalize()))
                .collect()
        };
        let five = [true, true, false, true, true, true];
        assert_eq!(faces(Vec3::NEG_Y), five);
        assert_eq!(faces(Vec3::new(0.3, -1.0, 0.2)), five);
        assert_eq!(faces(Vec3::new(1.0, -1.0, 1.0)), [true; 6]);
    }
}
