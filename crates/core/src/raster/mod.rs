//! GPU rasterization passes and the `direct` frame: shadow maps, then per sub-pixel sample an
//! eye G-buffer and deferred direct lighting accumulated into one image.

pub mod direct;
pub mod gbuffer;
pub mod ispm;
pub mod shadow;
mod specular;
mod timer;
pub mod volume_shape;

use crate::error::{Error, Result};
use crate::gpu::raw::{VertexRaw, ViewRaw};
use crate::gpu::{self, GpuContext};
use crate::image::Image;
use crate::render::{Progress, RenderOutput, RenderStats, Settings};
use crate::scene::Scene;
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::time::Instant;
use timer::Timer;
use wgpu::util::DeviceExt;

/// Every pipeline of the raster methods, compiled once per device.
pub struct Passes {
    pub gbuffer: gbuffer::GBufferPass,
    pub shadow: shadow::ShadowPass,
    pub direct: direct::DirectPass,
}

impl Passes {
    pub fn get(ctx: &GpuContext) -> &Passes {
        ctx.passes.get_or_init(|| Passes {
            gbuffer: gbuffer::GBufferPass::new(&ctx.device),
            shadow: shadow::ShadowPass::new(&ctx.device),
            direct: direct::DirectPass::new(&ctx.device),
        })
    }
}

/// The scene's triangles on the GPU: a non-indexed list of [`VertexRaw`].
pub struct Geometry {
    pub vertices: wgpu::Buffer,
    pub count: u32,
}

impl Geometry {
    /// Uploads the scene's triangles.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Self {
        let verts = vertices(scene);
        Geometry {
            vertices: buffer_init(
                ctx,
                "scene vertices",
                bytemuck::cast_slice(&verts),
                wgpu::BufferUsages::VERTEX,
            ),
            count: verts.len() as u32,
        }
    }
}

/// A `View` uniform picked by dynamic offset.
pub(crate) fn view_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ViewRaw>() as u64),
        },
        count: None,
    }
}

pub(crate) fn storage_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Eye samples per submission (bounds the timestamp queries of one submission).
const SAMPLES_PER_SUBMIT: u32 = 256;

const VIEW_SIZE: u64 = std::mem::size_of::<ViewRaw>() as u64;

/// Sub-pixel sample positions in [0, 1)²: a stratified grid when `spp` is a square, else
/// the Halton (2, 3) sequence. Their mean over the pixel is a box filter, like the path
/// tracer's uniform jitter.
pub fn sample_positions(spp: u32) -> Vec<Vec2> {
    let n = (spp as f64).sqrt().round() as u32;
    if n * n == spp {
        return (0..spp)
            .map(|i| Vec2::new((i % n) as f32 + 0.5, (i / n) as f32 + 0.5) / n as f32)
            .collect();
    }
    let halton = |mut i: u32, b: u32| {
        let (mut f, mut r) = (1.0f32, 0.0f32);
        while i > 0 {
            f /= b as f32;
            r += f * (i % b) as f32;
            i /= b;
        }
        r
    };
    (1..=spp)
        .map(|i| Vec2::new(halton(i, 2), halton(i, 3)))
        .collect()
}

/// World -> view for an eye at `eye` looking along `dir` (right-handed, looking down −z).
pub(crate) fn look_to(eye: Vec3, dir: Vec3, up: Vec3) -> Mat4 {
    let f = dir.normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-eye.dot(s), -eye.dot(u), eye.dot(f), 1.0),
    )
}

/// View -> clip with depth in [0, 1] (WebGPU), vertical field of view `fov_y` in radians.
pub(crate) fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let h = 1.0 / (0.5 * fov_y).tan();
    let r = far / (near - far);
    Mat4::from_cols(
        Vec4::new(h / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, -1.0),
        Vec4::new(0.0, 0.0, r * near, 0.0),
    )
}

/// The camera's world -> clip transform with the image shifted so that the pixel centre
/// sees image position `pixel + jitter`.
fn camera_view(scene: &Scene, jitter: Vec2, weight: f32) -> ViewRaw {
    let cam = &scene.camera;
    let (lo, hi) = shadow::bounds(scene);
    let far = (lo - cam.position)
        .abs()
        .max((hi - cam.position).abs())
        .length()
        * 1.01
        + 1e-3;
    let proj = perspective(cam.fov_y.to_radians(), cam.aspect(), far * 1e-5, far);
    let shift = Vec3::new(
        2.0 * (0.5 - jitter.x) / cam.width as f32,
        -2.0 * (0.5 - jitter.y) / cam.height as f32,
        0.0,
    );
    let view = look_to(cam.position, cam.forward, cam.up);
    ViewRaw::new(
        Mat4::from_translation(shift) * proj * view,
        cam.position,
        weight,
    )
}

/// The scene's triangles as a non-indexed vertex list.
fn vertices(scene: &Scene) -> Vec<VertexRaw> {
    let mut out = Vec::with_capacity(scene.triangles.len() * 3);
    for (t, tri) in scene.triangles.iter().enumerate() {
        let [p0, p1, p2] = scene.triangle(t);
        let ng = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        for &i in tri {
            out.push(VertexRaw {
                position: scene.positions[i as usize].into(),
                normal: scene.normals[i as usize].into(),
                geometric_normal: ng.into(),
                material: scene.triangle_materials[t],
            });
        }
    }
    out
}

fn buffer_init(
    ctx: &GpuContext,
    label: &str,
    bytes: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    // Zero-sized bindings are invalid: pad empty data to one 256-byte block.
    let zeros = [0u8; 256];
    let contents = if bytes.is_empty() { &zeros[..] } else { bytes };
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
}

fn view_binding(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: wgpu::BufferSize::new(VIEW_SIZE),
    })
}

/// Copies a 16-byte-per-texel texture to a mapped buffer and returns its rows unpadded.
fn read_texture(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<Vec4>> {
    let (w, h) = (texture.width(), texture.height());
    let row = (w * 16).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: row as u64 * h as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let bytes = ctx.read_buffer(&buffer)?;
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h as usize {
        let start = y * row as usize;
        out.extend_from_slice(bytemuck::cast_slice::<u8, Vec4>(
            &bytes[start..start + w as usize * 16],
        ));
    }
    Ok(out)
}

/// Decodes `oct_encode` of `types.wgsl`.
fn oct_decode(e: Vec2) -> Vec3 {
    let mut n = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    let t = (-n.z).max(0.0);
    n.x += if n.x >= 0.0 { -t } else { t };
    n.y += if n.y >= 0.0 { -t } else { t };
    n.normalize_or_zero()
}

/// Samples per submission: up to [`SAMPLES_PER_SUBMIT`], fewer for large images so that
/// one submission stays short (about 2¹⁸ pixel samples, about 0.1 s on
/// lavapipe) and cancellation, checked between submissions, stays prompt.
fn samples_per_submit(w: u32, h: u32) -> u32 {
    let pixels = (w as u64 * h as u64).max(1);
    ((1u64 << 18) / pixels).clamp(1, SAMPLES_PER_SUBMIT as u64) as u32
}

fn check_limits(ctx: &GpuContext, scene: &Scene, settings: &Settings, layers: u32) -> Result<()> {
    let l = ctx.device.limits();
    let max = l.max_texture_dimension_2d;
    if scene.camera.width > max || scene.camera.height > max {
        return Err(Error::setting(
            "width",
            format!("the GPU allows images up to {max} pixels a side"),
        ));
    }
    if settings.shadow_map_size > max {
        return Err(Error::setting(
            "shadow_map_size",
            format!("the GPU allows at most {max}"),
        ));
    }
    if layers > l.max_texture_array_layers {
        return Err(Error::Gpu(format!(
            "{layers} shadow-map layers exceed the GPU's {}",
            l.max_texture_array_layers
        )));
    }
    Ok(())
}

/// Fails with a GPU error when the scene's vertex buffer exceeds the adapter's limits.
pub(crate) fn check_scene_buffers(ctx: &GpuContext, scene: &Scene) -> Result<()> {
    let bytes = scene.triangles.len() as u64 * 3 * std::mem::size_of::<VertexRaw>() as u64;
    ctx.check_buffer("scene vertices", bytes)
}

/// Method `direct`: direct light from point and spot lights with shadow maps, rasterized.
pub fn render_direct(
    scene: &Scene,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<RenderOutput> {
    let t0 = Instant::now();
    let ctx = gpu::context(settings.adapter.as_deref())?;
    ctx.scoped("direct frame", || {
        frame(&ctx, scene, settings, None, progress, t0)
    })
}

/// The direct-light frame; `geometry` is the scene already on the GPU, if it is.
fn frame(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &Settings,
    geometry: Option<&Geometry>,
    progress: &dyn Progress,
    t0: Instant,
) -> Result<RenderOutput> {
    let passes = Passes::get(ctx);
    let device = &ctx.device;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let spp = settings.spp;
    let size = settings.shadow_map_size;
    let shadows = shadow::ShadowViews::new(scene, size);
    let layers = (shadows.matrices.len() as u32).max(1);
    check_limits(ctx, scene, settings, layers)?;
    let mut stats = RenderStats {
        triangles: scene.triangles.len() as u64,
        samples_per_pixel: spp,
        ..Default::default()
    };

    // Upload the scene, views and lights.
    let t = Instant::now();
    let storage = wgpu::BufferUsages::STORAGE;
    let uploaded;
    let geometry = match geometry {
        Some(g) => g,
        None => {
            check_scene_buffers(ctx, scene)?;
            uploaded = Geometry::upload(ctx, scene);
            &uploaded
        }
    };
    let materials: Vec<_> = scene.materials.iter().map(|m| m.to_raw()).collect();
    let material_buffer = buffer_init(ctx, "materials", bytemuck::cast_slice(&materials), storage);
    let light_buffer = buffer_init(
        ctx,
        "lights",
        bytemuck::cast_slice(&shadows.lights),
        storage,
    );
    let matrices: Vec<[f32; 16]> = shadows.matrices.iter().map(|m| m.to_cols_array()).collect();
    let matrix_buffer = buffer_init(
        ctx,
        "shadow matrices",
        bytemuck::cast_slice(&matrices),
        storage,
    );
    let shadow_views = shadow::ShadowPass::views(&shadows);
    let shadow_view_buffer = buffer_init(
        ctx,
        "shadow views",
        bytemuck::cast_slice(&shadow_views),
        wgpu::BufferUsages::UNIFORM,
    );
    // Eye views: the pixel centre (for the AOVs), then the samples of one submission,
    // rewritten for each.
    let sample_views: Vec<ViewRaw> = sample_positions(spp)
        .into_iter()
        .map(|j| camera_view(scene, j, 1.0 / spp as f32))
        .collect();
    let mut eye_views = vec![camera_view(scene, Vec2::splat(0.5), 0.0)];
    eye_views.extend_from_slice(&sample_views[..SAMPLES_PER_SUBMIT.min(spp) as usize]);
    let eye_buffer = buffer_init(
        ctx,
        "eye views",
        bytemuck::cast_slice(&eye_views),
        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    );

    // Render targets.
    let shadow_maps = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shadow maps"),
        size: wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: shadow::FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let layer_view = |i| {
        shadow_maps.create_view(&wgpu::TextureViewDescriptor {
            label: Some("shadow map layer"),
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: i,
            array_layer_count: Some(1),
            ..Default::default()
        })
    };
    let shadow_array = shadow_maps.create_view(&wgpu::TextureViewDescriptor {
        label: Some("shadow map array"),
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let gbuf = gbuffer::GBuffer::new(device, w, h);
    let accum = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("direct accumulation"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: direct::ACCUM,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let accum_view = accum.create_view(&Default::default());

    // Bind groups.
    let gbuffer_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gbuffer bind group"),
        layout: &passes.gbuffer.layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: view_binding(&eye_buffer),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: material_buffer.as_entire_binding(),
            },
        ],
    });
    let shadow_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("shadow bind group"),
        layout: &passes.shadow.layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: view_binding(&shadow_view_buffer),
        }],
    });
    let direct_scene_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("direct scene bind group"),
        layout: &passes.direct.scene_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: view_binding(&eye_buffer),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: light_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: matrix_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 3,
                resource: wgpu::BindingResource::TextureView(&shadow_array),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(&passes.direct.shadow_sampler),
            },
        ],
    });
    let direct_gbuffer_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("direct gbuffer bind group"),
        layout: &passes.direct.gbuffer_layout,
        entries: &gbuf
            .lighting_inputs()
            .iter()
            .enumerate()
            .map(|(i, v)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: wgpu::BindingResource::TextureView(v),
            })
            .collect::<Vec<_>>(),
    });
    stats
        .stages
        .push(("upload".into(), t.elapsed().as_secs_f64()));

    // Shadow maps.
    let mut timer = Timer::new(ctx, layers + 1 + 2 * SAMPLES_PER_SUBMIT.min(spp));
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("shadow maps"),
    });
    for layer in 0..shadows.matrices.len() as u32 {
        let view = layer_view(layer);
        let offset = (layer as u64 * VIEW_SIZE) as u32;
        let ts = timer.pass("shadow maps");
        passes
            .shadow
            .record(&mut encoder, &view, &shadow_group, offset, geometry, ts);
    }
    timer.resolve(&mut encoder);
    ctx.queue.submit([encoder.finish()]);
    timer.collect(ctx)?;

    // Per sample: G-buffer at the jittered view, then lighting added into the accumulator.
    let mut done = 0;
    let per_submit = samples_per_submit(w, h);
    while done < spp {
        let batch = per_submit.min(spp - done);
        let views = &sample_views[done as usize..(done + batch) as usize];
        ctx.queue
            .write_buffer(&eye_buffer, VIEW_SIZE, bytemuck::cast_slice(views));
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("direct samples"),
        });
        for s in done..done + batch {
            let offset = ((s - done + 1) as u64 * VIEW_SIZE) as u32;
            let ts = timer.pass("gbuffer");
            passes
                .gbuffer
                .record(&mut encoder, &gbuf, &gbuffer_group, offset, geometry, ts);
            let ts = timer.pass("direct light");
            passes.direct.record(
                &mut encoder,
                &accum_view,
                s == 0,
                [&direct_scene_group, &direct_gbuffer_group],
                offset,
                ts,
            );
        }
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        timer.collect(ctx)?;
        done += batch;
        if !progress.update("direct", done as f64 / spp as f64) {
            return Err(Error::Cancelled);
        }
    }
    // The AOVs come from a G-buffer at the pixel centres: the single sample's when spp = 1.
    if spp > 1 {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("aov gbuffer"),
        });
        let ts = timer.pass("gbuffer");
        passes
            .gbuffer
            .record(&mut encoder, &gbuf, &gbuffer_group, 0, geometry, ts);
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        timer.collect(ctx)?;
    }
    let t = Instant::now();
    let [position, normals, albedo] = [0, 1, 4].map(|i| read_texture(ctx, &gbuf.textures[i]));
    let (position, normals, albedo) = (position?, normals?, albedo?);
    let radiance = read_texture(ctx, &accum)?;
    let readback = t.elapsed().as_secs_f64();
    stats.stages.extend(timer.totals);
    stats.stages.push(("readback".into(), readback));

    // Assemble the images.
    let cam = &scene.camera;
    let mut out = RenderOutput {
        radiance: Image::new(w, h),
        albedo: Image::new(w, h),
        normal: Image::new(w, h),
        position: Image::new(w, h),
        depth: vec![0.0; (w * h) as usize],
        caustics: Image::new(w, h),
        stats,
        aovs: Vec::new(),
    };
    for i in 0..(w * h) as usize {
        let r = radiance[i];
        out.radiance.pixels[i] = if r.w > 0.0 {
            r.truncate() / r.w
        } else {
            Vec3::ZERO
        };
        if position[i].w > 0.0 {
            let p = position[i].truncate();
            out.position.pixels[i] = p;
            out.normal.pixels[i] = oct_decode(Vec2::new(normals[i].x, normals[i].y));
            out.albedo.pixels[i] = albedo[i].truncate();
            out.depth[i] = (p - cam.position).dot(cam.forward);
        }
    }
    out.stats.total_seconds = t0.elapsed().as_secs_f64();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_positions_average_to_the_pixel_centre() {
        for spp in [1, 4, 16, 7, 100, 33] {
            let p = sample_positions(spp);
            assert_eq!(p.len(), spp as usize);
            assert!(p
                .iter()
                .all(|s| s.cmpge(Vec2::ZERO).all() && s.cmplt(Vec2::ONE).all()));
            let mean = p.iter().copied().sum::<Vec2>() / spp as f32;
            assert!(
                (mean - Vec2::splat(0.5)).abs().max_element() < 0.5 / (spp as f32).sqrt() + 1e-6,
                "{spp}: {mean}"
            );
        }
    }

    /// The jittered camera maps the point seen through image position `pixel + jitter` to
    /// the centre of `pixel`.
    #[test]
    fn camera_view_matches_camera_rays() {
        let scene = crate::scene::builtin::load("cornell").expect("built-in scene");
        let cam = scene.camera.with_size(64, 48);
        let scene = Scene {
            camera: cam,
            ..scene
        };
        let jitter = Vec2::new(0.2, 0.9);
        let m = Mat4::from_cols_array_2d(&camera_view(&scene, jitter, 1.0).view_proj);
        for (x, y) in [(0u32, 0u32), (10, 40), (63, 47)] {
            let p = cam.position + cam.direction(x as f32 + jitter.x, y as f32 + jitter.y) * 2.0;
            let c = m * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            let px = Vec2::new((ndc.x + 1.0) * 0.5 * 64.0, (1.0 - ndc.y) * 0.5 * 48.0);
            assert!(
                (px - Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                    .abs()
                    .max_element()
                    < 1e-3,
                "{px}"
            );
            assert!((0.0..=1.0).contains(&ndc.z));
        }
    }

    #[test]
    fn octahedral_decode_inverts_encode() {
        let mut rng = crate::sampling::Rng::new(1, 2, 3);
        for _ in 0..1000 {
            let n = crate::sampling::uniform_sphere(rng.next_2d());
            // The WGSL encoder, transcribed.
            let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
            let e = if n.z >= 0.0 {
                p
            } else {
                (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs()))
                    * Vec2::new(
                        if p.x >= 0.0 { 1.0 } else { -1.0 },
                        if p.y >= 0.0 { 1.0 } else { -1.0 },
                    )
            };
            assert!((oct_decode(e) - n).length() < 1e-5);
        }
    }
}
