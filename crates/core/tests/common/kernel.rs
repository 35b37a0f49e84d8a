//! A test kernel on the GPU: the test's WGSL computes one vec4 per input record
//! (`kernel.wgsl`: `Item`, `evaluate`), run over `n` records (64 a workgroup) from storage
//! binding 0 into binding 1 of group 0, with group 1 bound where the kernel needs it (the
//! scene's textures).

use gi_core::gpu::{self, shaders, GpuContext};
use wgpu::util::DeviceExt;

/// Runs the kernel of `parts` (the shared sources it needs, then its own) on `ctx` over `n`
/// records packed in `input`; `group1`: a layout and group for group 1. Returns the `n`
/// results.
pub fn run(
    ctx: &GpuContext,
    parts: &[&str],
    input: &[u8],
    n: usize,
    group1: Option<(&wgpu::BindGroupLayout, &wgpu::BindGroup)>,
) -> Vec<[f32; 4]> {
    let device = &ctx.device;
    let parts = [parts, &[include_str!("kernel.wgsl")]].concat();
    let module = &shaders::module(device, "test kernel", &parts);
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("kernel input"),
        contents: input,
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = n as u64 * 16;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("kernel results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = gpu::readback_buffer(device, "kernel readback", size);
    let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let layout = gpu::pipeline::bind_group_layout(
        device,
        "kernel layout",
        &[storage(0, true), storage(1, false)],
    );
    let mut groups = vec![&layout];
    groups.extend(group1.map(|(l, _)| l));
    let pipeline_layout = gpu::pipeline::pipeline_layout(device, "kernel pipeline layout", &groups);
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("kernel pipeline"),
        layout: Some(&pipeline_layout),
        module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("kernel bind group"),
        layout: &layout,
        entries: &[
            gpu::layout::buffer(0, &input),
            gpu::layout::buffer(1, &output),
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        if let Some((_, group1)) = group1 {
            pass.set_bind_group(1, group1, &[]);
        }
        pass.dispatch_workgroups((n as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, size);
    ctx.queue.submit([encoder.finish()]);
    let bytes = ctx.read_buffer(&readback).expect("readback");
    bytemuck::cast_slice::<u8, [f32; 4]>(&bytes).to_vec()
}
