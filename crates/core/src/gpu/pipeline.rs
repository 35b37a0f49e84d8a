//! Layouts, render pipelines and full-screen draws as every pass builds them: labelled
//! bind-group and pipeline layouts, one module's vertex and fragment stages without
//! multisampling, additive targets, one triangle over a cleared target.

/// `Device::create_bind_group_layout` of `entries`, labelled.
pub fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    })
}

/// A pipeline layout of `groups` (group 0 first), without immediates.
pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// A colour target of `format` to which every fragment adds its colour and alpha.
pub fn additive_target(format: wgpu::TextureFormat) -> wgpu::ColorTargetState {
    let add = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    wgpu::ColorTargetState {
        format,
        blend: Some(wgpu::BlendState {
            color: add,
            alpha: add,
        }),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// A render pipeline whose stages both come from `module`: [`RenderSpec::new`] gives no
/// vertex buffers, triangle lists, no depth and no colour targets; set the fields that differ.
pub struct RenderSpec<'a> {
    pub label: &'a str,
    pub layout: &'a wgpu::PipelineLayout,
    pub module: &'a wgpu::ShaderModule,
    pub vertex_entry: &'a str,
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub primitive: wgpu::PrimitiveState,
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    /// The fragment stage's entry point; `None`: depth only.
    pub fragment_entry: Option<&'a str>,
    /// The fragment stage's compilation options (override constants).
    pub fragment_options: wgpu::PipelineCompilationOptions<'a>,
    pub targets: &'a [Option<wgpu::ColorTargetState>],
}

impl<'a> RenderSpec<'a> {
    pub fn new(
        label: &'a str,
        layout: &'a wgpu::PipelineLayout,
        module: &'a wgpu::ShaderModule,
        vertex_entry: &'a str,
        fragment_entry: Option<&'a str>,
    ) -> Self {
        RenderSpec {
            label,
            layout,
            module,
            vertex_entry,
            buffers: &[],
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            fragment_entry,
            fragment_options: Default::default(),
            targets: &[],
        }
    }

    /// The pipeline, counted ([`super::create_render_pipeline`]).
    pub fn create(self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        let module = self.module;
        super::create_render_pipeline(
            device,
            &wgpu::RenderPipelineDescriptor {
                label: Some(self.label),
                layout: Some(self.layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(self.vertex_entry),
                    compilation_options: Default::default(),
                    buffers: self.buffers,
                },
                primitive: self.primitive,
                depth_stencil: self.depth_stencil,
                multisample: Default::default(),
                fragment: self.fragment_entry.map(|entry| wgpu::FragmentState {
                    module,
                    entry_point: Some(entry),
                    compilation_options: self.fragment_options,
                    targets: self.targets,
                }),
                multiview_mask: None,
                cache: None,
            },
        )
    }
}

/// Records one full-screen draw of `pipeline` (one triangle, no vertex buffers) into
/// `target`, cleared first, with `groups` bound from group 0.
pub fn draw_fullscreen(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    target: &wgpu::TextureView,
    pipeline: &wgpu::RenderPipeline,
    groups: &[&wgpu::BindGroup],
    timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(super::cleared(target))],
        depth_stencil_attachment: None,
        timestamp_writes: timestamps,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    for (i, group) in groups.iter().enumerate() {
        pass.set_bind_group(i as u32, *group, &[]);
    }
    pass.draw(0..3, 0..1);
}
