// The direct passes' material records (exact_models.wgsl): group 1 beside the G-buffer.
@group(1) @binding(5) var<storage, read> model_materials: array<ModelMaterial>;
