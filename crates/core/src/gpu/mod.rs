//! The headless GPU device: adapter choice, one cached context per process and adapter
//! choice, WGSL loading, readback and timestamp helpers.
//!
//! The adapter is a real GPU when one is present, else a CPU implementation (Mesa lavapipe).
//! An explicit choice comes from the `adapter` option (`DirectLightOptions::adapter`) or, failing that, the environment
//! variable `GI_ADAPTER`: `"cpu"`, `"gpu"`, or a case-insensitive substring of the adapter
//! name.

pub mod alloc;
pub mod bvh;
pub mod layout;
pub mod photon;
pub mod pipeline;
pub mod raw;
pub mod shaders;
pub mod timer;

use crate::error::{Error, Result};
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Environment variable naming the adapter when the settings don't.
pub const ADAPTER_ENV: &str = "GI_ADAPTER";

const INSTALL_HINT: &str =
    "install a Vulkan driver; without a GPU use Mesa's CPU driver lavapipe (`apt-get install mesa-vulkan-drivers`)";

/// A device with its queue, created once per process and adapter choice.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Whether timestamp queries are enabled (per-pass GPU timings).
    pub timestamps: bool,
    /// Pipelines and layouts by type, each created on first use ([`GpuContext::pipelines`]).
    pipelines: Mutex<HashMap<TypeId, Arc<dyn Any + Send + Sync>>>,
}

/// A pass's pipelines and bind-group layouts: created once per device (a new pipeline
/// costs 20–360 ms on lavapipe) and shared by every frame ([`GpuContext::pipelines`]).
pub trait Pipelines: Any + Send + Sync + Sized {
    /// Compiles the pipelines on `ctx` (may ask `ctx` for the pipelines it builds on).
    fn create(ctx: &GpuContext) -> Self;

    /// The pipelines of `ctx`, created on first use.
    fn get(ctx: &GpuContext) -> Arc<Self> {
        ctx.pipelines::<Self>()
    }
}

/// How the user chose the adapter.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Choice {
    Auto,
    Cpu,
    Gpu,
    Name(String),
}

impl Choice {
    /// The setting wins over the environment variable's value `env`.
    fn parse(setting: Option<&str>, env: Option<&str>) -> Choice {
        match setting.or(env).map(|s| s.trim().to_lowercase()) {
            None => Choice::Auto,
            Some(s) if s.is_empty() || s == "auto" => Choice::Auto,
            Some(s) if s == "cpu" => Choice::Cpu,
            Some(s) if s == "gpu" => Choice::Gpu,
            Some(s) => Choice::Name(s),
        }
    }

    /// Rank of an adapter under this choice; `None` = not acceptable. Lower is better.
    fn rank(&self, name: &str, device_type: wgpu::DeviceType) -> Option<u32> {
        use wgpu::DeviceType::*;
        let gpu_rank = match device_type {
            DiscreteGpu => 0,
            IntegratedGpu => 1,
            VirtualGpu => 2,
            Cpu => 3,
            Other => 4,
        };
        match self {
            Choice::Auto => Some(gpu_rank),
            Choice::Cpu => (device_type == Cpu).then_some(0),
            Choice::Gpu => (gpu_rank <= 2).then_some(gpu_rank),
            Choice::Name(s) => name.to_lowercase().contains(s.as_str()).then_some(gpu_rank),
        }
    }
}

fn instance() -> &'static wgpu::Instance {
    static INSTANCE: OnceLock<wgpu::Instance> = OnceLock::new();
    INSTANCE.get_or_init(|| {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::PRIMARY;
        wgpu::Instance::new(desc)
    })
}

fn pick_adapter(choice: &Choice) -> Result<wgpu::Adapter> {
    let adapters = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::PRIMARY));
    let names: Vec<String> = adapters
        .iter()
        .map(|a| a.get_info())
        .map(|i| format!("{} ({:?})", i.name, i.device_type))
        .collect();
    adapters
        .into_iter()
        .filter_map(|a| {
            let info = a.get_info();
            choice.rank(&info.name, info.device_type).map(|r| (r, a))
        })
        .min_by_key(|(r, _)| *r)
        .map(|(_, a)| a)
        .ok_or_else(|| {
            let found = if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            };
            Error::Gpu(format!(
                "no GPU adapter matches {choice:?} (adapters found: {found}); {INSTALL_HINT}"
            ))
        })
}

/// The features gi needs; `FLOAT32_BLENDABLE` accumulates supersamples in an `Rgba32Float`.
const REQUIRED: wgpu::Features = wgpu::Features::FLOAT32_BLENDABLE;

fn create_context(choice: &Choice) -> Result<GpuContext> {
    let adapter = pick_adapter(choice)?;
    let info = adapter.get_info();
    let missing = REQUIRED - adapter.features();
    if !missing.is_empty() {
        return Err(Error::Gpu(format!(
            "adapter `{}` lacks features {missing:?}",
            info.name
        )));
    }
    let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
    let features = REQUIRED
        | if timestamps {
            wgpu::Features::TIMESTAMP_QUERY
        } else {
            wgpu::Features::empty()
        };
    // The adapter's own limits: the defaults cap textures at 8192 and color targets at 32 bytes.
    let desc = wgpu::DeviceDescriptor {
        label: Some("gi device"),
        required_features: features,
        required_limits: adapter.limits(),
        ..Default::default()
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&desc))
        .map_err(|e| Error::Gpu(format!("cannot open device on `{}`: {e}", info.name)))?;
    // Errors inside a frame are caught by error scopes; anything else is reported, not a panic.
    device.on_uncaptured_error(Arc::new(|e| eprintln!("gi: uncaptured GPU error: {e}")));
    Ok(GpuContext {
        adapter,
        device,
        queue,
        info,
        timestamps,
        pipelines: Mutex::new(HashMap::new()),
    })
}

/// The process's contexts, one per adapter choice; they live until the process exits.
fn contexts() -> std::sync::MutexGuard<'static, HashMap<Choice, Arc<GpuContext>>> {
    static CONTEXTS: OnceLock<Mutex<HashMap<Choice, Arc<GpuContext>>>> = OnceLock::new();
    CONTEXTS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|p| p.into_inner())
}

/// Waits until every context's submitted work has finished (errors of lost devices are
/// ignored: their work is gone). A frame that fails half-way leaves work in flight on the
/// cached devices; lavapipe runs it on its own threads, compiling shader variants with
/// LLVM, and a process that exits meanwhile crashes in LLVM as its static destructors run
/// (SIGSEGV or SIGABRT after the error was reported). The Python package waits here at
/// interpreter exit (`atexit`), which runs before the C exit handlers.
pub fn wait_idle_all() {
    let all: Vec<Arc<GpuContext>> = contexts().values().cloned().collect();
    for ctx in all {
        let _ = ctx.wait();
    }
}

/// The context for an adapter choice (`None` = `GI_ADAPTER` or automatic), created on first use.
pub fn context(adapter: Option<&str>) -> Result<Arc<GpuContext>> {
    let choice = Choice::parse(adapter, std::env::var(ADAPTER_ENV).ok().as_deref());
    let mut map = contexts();
    if let Some(ctx) = map.get(&choice) {
        return Ok(ctx.clone());
    }
    let ctx = Arc::new(create_context(&choice)?);
    map.insert(choice, ctx.clone());
    Ok(ctx)
}

/// A human-readable description of the adapter an adapter choice selects: name, backend,
/// device type, driver and the limits gi cares about.
pub fn adapter_report(adapter: Option<&str>) -> Result<String> {
    let ctx = context(adapter)?;
    let i = &ctx.info;
    let l = ctx.device.limits();
    Ok(format!(
        "adapter: {}\nbackend: {:?}\ndevice type: {:?}\ndriver: {} {}\ntimestamp queries: {}\n\
         max texture 2d: {}\nmax texture array layers: {}\nmax color attachments: {}\n\
         max color attachment bytes per sample: {}\nmax storage buffer binding: {} bytes\n\
         max compute workgroup invocations: {}",
        i.name,
        i.backend,
        i.device_type,
        i.driver,
        i.driver_info,
        if ctx.timestamps { "yes" } else { "no" },
        l.max_texture_dimension_2d,
        l.max_texture_array_layers,
        l.max_color_attachments,
        l.max_color_attachment_bytes_per_sample,
        l.max_storage_buffer_binding_size,
        l.max_compute_invocations_per_workgroup,
    ))
}

impl GpuContext {
    /// The pipelines of type `P` on this device, created on first use. The cache is keyed
    /// by type, so the device layer names no technique.
    pub fn pipelines<P: Pipelines>(&self) -> Arc<P> {
        let key = TypeId::of::<P>();
        let lock = || self.pipelines.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(p) = lock().get(&key).cloned() {
            return downcast(p);
        }
        // Created without the lock held: `create` may ask for the pipelines it builds on.
        let made: Arc<dyn Any + Send + Sync> = Arc::new(P::create(self));
        downcast(lock().entry(key).or_insert(made).clone())
    }

    /// Whether the pipelines `P` were created on this device (a scene that does not use a
    /// feature must not compile its pipelines).
    pub fn has_pipelines<P: Pipelines>(&self) -> bool {
        let lock = self.pipelines.lock().unwrap_or_else(|p| p.into_inner());
        lock.contains_key(&TypeId::of::<P>())
    }

    /// Runs `f` inside a validation and out-of-memory error scope; a GPU error becomes `Error::Gpu`.
    pub fn scoped<T>(&self, what: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        let oom = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let out = f();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v.or(o) {
            return Err(Error::Gpu(format!("{what}: {e}")));
        }
        out
    }

    /// Fails with [`Error::Gpu`] when a buffer of `bytes` exceeds the adapter's largest
    /// buffer (checked before creating it, instead of a wgpu validation panic), and with
    /// [`Error::OutOfMemory`] when the process can't hold its staging copy.
    pub fn check_buffer(&self, what: &str, bytes: u64) -> Result<()> {
        let max = self.device.limits().max_buffer_size;
        if bytes > max {
            return Err(Error::Gpu(format!(
                "{what} need a {} buffer; the adapter allows at most {}",
                crate::error::human(bytes),
                crate::error::human(max)
            )));
        }
        crate::memory::check(|| what.to_string(), bytes)
    }

    /// Waits for all submitted work.
    pub fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| Error::Gpu(e.to_string()))
    }

    /// Maps `buffers` (with `MAP_READ` usage) once the submission `after` is done (`None`:
    /// all submitted work) and copies out their bytes; later submissions are not waited on.
    pub fn read_buffers(
        &self,
        buffers: &[&wgpu::Buffer],
        after: Option<wgpu::SubmissionIndex>,
    ) -> Result<Vec<Vec<u8>>> {
        self.read_buffers_with(buffers, after, |_, bytes| bytes.to_vec())
    }

    /// As [`Self::read_buffers`], but `f(i, bytes)` reads buffer `i`'s mapped bytes in place
    /// (no copy of the whole buffer first) and its results are returned.
    pub fn read_buffers_with<R>(
        &self,
        buffers: &[&wgpu::Buffer],
        after: Option<wgpu::SubmissionIndex>,
        mut f: impl FnMut(usize, &[u8]) -> R,
    ) -> Result<Vec<R>> {
        let (tx, rx) = std::sync::mpsc::channel();
        for (i, b) in buffers.iter().enumerate() {
            let tx = tx.clone();
            b.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send((i, r));
            });
        }
        drop(tx);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: after,
                timeout: None,
            })
            .map_err(|e| Error::Gpu(e.to_string()))?;
        for _ in 0..buffers.len() {
            let (_, r) = rx.recv().map_err(|e| Error::Gpu(e.to_string()))?;
            r.map_err(|e| Error::Gpu(format!("buffer mapping failed: {e}")))?;
        }
        buffers
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let out = {
                    let bytes = b
                        .slice(..)
                        .get_mapped_range()
                        .map_err(|e| Error::Gpu(e.to_string()))?;
                    f(i, &bytes)
                };
                b.unmap();
                Ok(out)
            })
            .collect()
    }

    /// Maps `buffer` (with `MAP_READ` usage) after the queue's work and copies out its bytes.
    pub fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait()?;
        rx.recv()
            .map_err(|e| Error::Gpu(e.to_string()))?
            .map_err(|e| Error::Gpu(format!("buffer mapping failed: {e}")))?;
        let bytes = slice
            .get_mapped_range()
            .map_err(|e| Error::Gpu(e.to_string()))?
            .to_vec();
        buffer.unmap();
        Ok(bytes)
    }
}

fn downcast<P: Pipelines>(p: Arc<dyn Any + Send + Sync>) -> Arc<P> {
    match p.downcast::<P>() {
        Ok(p) => p,
        Err(_) => unreachable!("the pipeline cache is keyed by type"),
    }
}

/// `Device::create_buffer`, counted ([`alloc::counters`]).
pub fn create_buffer(device: &wgpu::Device, desc: &wgpu::BufferDescriptor) -> wgpu::Buffer {
    alloc::note(alloc::Created::Buffer);
    device.create_buffer(desc)
}

/// A colour attachment of `view` cleared to transparent black and stored.
pub fn cleared(view: &wgpu::TextureView) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
            store: wgpu::StoreOp::Store,
        },
    }
}

/// A mappable buffer of `size` bytes that copies from the GPU land in, for reading back
/// (counted).
pub fn readback_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    create_buffer(
        device,
        &wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        },
    )
}

/// `DeviceExt::create_buffer_init`, counted.
pub fn create_buffer_init(
    device: &wgpu::Device,
    desc: &wgpu::util::BufferInitDescriptor,
) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    alloc::note(alloc::Created::Buffer);
    device.create_buffer_init(desc)
}

/// `Device::create_texture`, counted.
pub fn create_texture(device: &wgpu::Device, desc: &wgpu::TextureDescriptor) -> wgpu::Texture {
    alloc::note(alloc::Created::Texture);
    device.create_texture(desc)
}

/// A 2D texture of `width × height` texels in `format` with one mip level and one layer
/// (counted): the textures the passes render to, read and upload into.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    let size = wgpu::Extent3d {
        width,
        height,
        depth_or_array_layers: 1,
    };
    texture_array(device, label, size, format, usage)
}

/// A 2D texture (`size.depth_or_array_layers` layers) in `format` with one mip level
/// (counted).
pub fn texture_array(
    device: &wgpu::Device,
    label: &str,
    size: wgpu::Extent3d,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    create_texture(
        device,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        },
    )
}

/// `Device::create_bind_group`, counted.
pub fn create_bind_group(
    device: &wgpu::Device,
    desc: &wgpu::BindGroupDescriptor,
) -> wgpu::BindGroup {
    alloc::note(alloc::Created::BindGroup);
    device.create_bind_group(desc)
}

/// `Device::create_render_pipeline`, counted.
pub fn create_render_pipeline(
    device: &wgpu::Device,
    desc: &wgpu::RenderPipelineDescriptor,
) -> wgpu::RenderPipeline {
    alloc::note(alloc::Created::Pipeline);
    device.create_render_pipeline(desc)
}

/// A full-screen pass's pipeline, counted: vertex entry `vs_main` without vertex buffers
/// (one triangle covering the target), fragment entry `entry` of the same `module` writing
/// one colour target, no depth.
pub fn create_fullscreen_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    target: wgpu::ColorTargetState,
) -> wgpu::RenderPipeline {
    let options = Default::default();
    create_fullscreen_pipeline_with(device, label, layout, module, (entry, options), target)
}

/// [`create_fullscreen_pipeline`] with the fragment stage's compilation options (override
/// constants).
pub fn create_fullscreen_pipeline_with(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    (entry, options): (&str, wgpu::PipelineCompilationOptions),
    target: wgpu::ColorTargetState,
) -> wgpu::RenderPipeline {
    pipeline::RenderSpec {
        fragment_options: options,
        targets: &[Some(target)],
        ..pipeline::RenderSpec::new(label, layout, module, "vs_main", Some(entry))
    }
    .create(device)
}

/// `Device::create_compute_pipeline`, counted.
pub fn create_compute_pipeline(
    device: &wgpu::Device,
    desc: &wgpu::ComputePipelineDescriptor,
) -> wgpu::ComputePipeline {
    alloc::note(alloc::Created::Pipeline);
    device.create_compute_pipeline(desc)
}

/// The compute pipeline of `module`'s entry point `entry` over `layout`, with default
/// compilation options (counted; labelled `entry`).
pub fn compute_pipeline_of(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    create_compute_pipeline(
        device,
        &wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(layout),
            module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        },
    )
}

/// `Queue::write_buffer`, counted as an upload of `label`.
pub fn write_buffer(
    queue: &wgpu::Queue,
    label: &str,
    buffer: &wgpu::Buffer,
    offset: u64,
    bytes: &[u8],
) {
    alloc::note_upload(label, bytes.len() as u64);
    queue.write_buffer(buffer, offset, bytes);
}

/// A `w`×`h` `Rgba32Float` texture (sampled, counted) holding `texels` (row-major), their
/// upload counted as `label`'s.
pub fn float_texture_of(
    ctx: &GpuContext,
    label: &str,
    (w, h): (u32, u32),
    texels: &[[f32; 4]],
) -> wgpu::Texture {
    let texture = texture_2d(
        &ctx.device,
        label,
        w,
        h,
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    write_rows(ctx, &texture, label, w, texels);
    texture
}

/// Writes `data` into the first rows of `texture` (`w` texels a row), counted as an upload
/// of `label`.
pub fn write_rows(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    label: &str,
    w: u32,
    data: &[[f32; 4]],
) {
    if data.is_empty() {
        return;
    }
    let rows = data.len() as u32 / w;
    alloc::note_upload(label, data.len() as u64 * 16);
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 16),
            rows_per_image: Some(rows),
        },
        wgpu::Extent3d {
            width: w,
            height: rows,
            depth_or_array_layers: 1,
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adapter_choice() {
        assert_eq!(Choice::parse(None, None), Choice::Auto);
        assert_eq!(Choice::parse(None, Some(" CPU ")), Choice::Cpu);
        assert_eq!(Choice::parse(Some("gpu"), Some("cpu")), Choice::Gpu);
        assert_eq!(
            Choice::parse(Some("LLVMpipe"), None),
            Choice::Name("llvmpipe".into())
        );
        let cpu = ("llvmpipe (LLVM 15.0.6, 256 bits)", wgpu::DeviceType::Cpu);
        let gpu = ("NVIDIA H100", wgpu::DeviceType::DiscreteGpu);
        assert!(Choice::Auto.rank(gpu.0, gpu.1) < Choice::Auto.rank(cpu.0, cpu.1));
        assert_eq!(Choice::Gpu.rank(cpu.0, cpu.1), None);
        assert_eq!(Choice::Cpu.rank(gpu.0, gpu.1), None);
        assert!(Choice::Name("llvm".into()).rank(cpu.0, cpu.1).is_some());
        assert_eq!(Choice::Name("llvm".into()).rank(gpu.0, gpu.1), None);
    }
}
