//! Pipelines with their layout and their one descriptor set layout: compute pipelines with
//! specialisation constants (ids `0..n`, all `u32`), and the rasterising pipeline of the G-buffer
//! (dynamic rendering, no render-pass objects). Each one's set layout is made from its shaders'
//! bindings ([`reflect::layout`]); it keeps them, with which ones its shaders may write, to check
//! each list of resources written to one of its sets ([`Pipeline::write_set`]).

use ash::vk;

use super::descriptor::{Binding, Declared};
use super::{descriptor, reflect, shader, vk_err, Context};
use crate::error::Result;

pub struct Pipeline {
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pub bind_point: vk::PipelineBindPoint,
    pub push_stages: vk::ShaderStageFlags,
    /// The name it was made with, for the errors of [`Pipeline::write_set`].
    pub name: String,
    /// Its set's bindings as its shaders declare them ([`reflect::layout`]).
    pub declared: Vec<Option<Declared>>,
}

/// The set layout and pipeline layout, unnamed (see [`Pipeline::name`]).
fn layouts(
    raw: &ash::Device,
    declared: &[Option<Declared>],
    stages: vk::ShaderStageFlags,
    push_size: u32,
) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout)> {
    let set_layout = descriptor::layout_on(raw, declared, stages)?;
    let set_layouts = [set_layout];
    let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_size }];
    let info = vk::PipelineLayoutCreateInfo::default()
        .set_layouts(&set_layouts)
        .push_constant_ranges(if push_size > 0 { &ranges[..] } else { &[] });
    // SAFETY: the set layout is live; the pipeline layout is destroyed with the pipeline.
    match unsafe { raw.create_pipeline_layout(&info, None) } {
        Ok(l) => Ok((set_layout, l)),
        Err(result) => {
            // SAFETY: unused.
            unsafe { raw.destroy_descriptor_set_layout(set_layout, None) };
            Err(vk_err("vkCreatePipelineLayout")(result))
        }
    }
}

/// The pipeline of a `vkCreate*Pipelines` result, or its layouts destroyed and the error.
fn finish(
    raw: &ash::Device,
    created: std::result::Result<Vec<vk::Pipeline>, (Vec<vk::Pipeline>, vk::Result)>,
    shell: Pipeline,
    call: &'static str,
) -> Result<Pipeline> {
    match created {
        Ok(p) => Ok(Pipeline { raw: p[0], ..shell }),
        Err((_, result)) => {
            // SAFETY: the layouts were never used by a pipeline.
            unsafe { shell.destroy_on(raw) };
            Err(vk_err(call)(result))
        }
    }
}

impl Pipeline {
    /// A compute pipeline from `spv` whose specialisation constant `i` is `spec[i]`, its one set's
    /// layout the shader's bindings.
    pub fn compute(ctx: &Context, spv: &[u8], name: &str, push_size: u32, spec: &[u32]) -> Result<Pipeline> {
        let p = Pipeline::compute_on(ctx.raw(), ctx.pipeline_cache.raw, spv, name, push_size, spec)?;
        p.name(ctx, name);
        Ok(p)
    }

    /// Variants of one compute shader, [`Pipeline::compute`] each with its name and specialisation
    /// constants; none is left when one fails.
    pub fn compute_variants<const N: usize>(
        ctx: &Context,
        spv: &[u8],
        push_size: u32,
        variants: [(&str, &[u32]); N],
    ) -> Result<[Pipeline; N]> {
        let mut made = Vec::with_capacity(N);
        for (name, spec) in variants {
            match Pipeline::compute(ctx, spv, name, push_size, spec) {
                Ok(p) => made.push(p),
                Err(e) => {
                    for p in made {
                        p.destroy(ctx);
                    }
                    return Err(e);
                }
            }
        }
        match made.try_into() {
            Ok(all) => Ok(all),
            Err(_) => unreachable!("one pipeline a variant, made above"),
        }
    }

    /// [`Pipeline::compute`] through a device handle and the pipeline cache alone, unnamed: what a
    /// thread that compiles pipelines in the background calls (the caller names it with
    /// [`Pipeline::name`]). The cache may be null.
    pub fn compute_on(
        raw: &ash::Device,
        cache: vk::PipelineCache,
        spv: &[u8],
        name: &str,
        push_size: u32,
        spec: &[u32],
    ) -> Result<Pipeline> {
        let declared = reflect::layout(name, &[spv])?;
        let stages = vk::ShaderStageFlags::COMPUTE;
        let module = shader::module_on(raw, spv, name)?;
        let (set_layout, layout) = match layouts(raw, &declared, stages, push_size) {
            Ok(l) => l,
            Err(e) => {
                // SAFETY: unused.
                unsafe { raw.destroy_shader_module(module, None) };
                return Err(e);
            }
        };
        let entries: Vec<vk::SpecializationMapEntry> = (0..spec.len())
            .map(|i| vk::SpecializationMapEntry { constant_id: i as u32, offset: 4 * i as u32, size: 4 })
            .collect();
        let data: Vec<u8> = spec.iter().flat_map(|v| v.to_ne_bytes()).collect();
        let spec_info = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(stages)
            .module(module)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout)];
        // SAFETY: module and layout are live; the infos outlive the call.
        // The cache is internally synchronised: threads building at once may share it.
        let created = unsafe { raw.create_compute_pipelines(cache, &info, None) };
        // SAFETY: a module may be destroyed once the pipeline is created.
        unsafe { raw.destroy_shader_module(module, None) };
        let p = Pipeline {
            raw: vk::Pipeline::null(),
            layout,
            set_layout,
            bind_point: vk::PipelineBindPoint::COMPUTE,
            push_stages: stages,
            name: name.to_string(),
            declared,
        };
        finish(raw, created, p, "vkCreateComputePipelines")
    }

    /// Names the pipeline and its layouts for the validation layer and debuggers.
    pub fn name(&self, ctx: &Context, name: &str) {
        ctx.device.set_name(self.raw, name);
        ctx.device.set_name(self.layout, &format!("{name}.layout"));
        ctx.device.set_name(self.set_layout, &format!("{name}.set"));
    }

    /// The G-buffer pipeline: vertex buffer of `stride` bytes with `attributes` (location, format,
    /// offset), triangle lists, no culling, depth test `LESS`, writes to `colors` and `depth`.
    #[allow(clippy::too_many_arguments)]
    pub fn raster(
        ctx: &Context,
        (vert, frag): (&[u8], &[u8]),
        name: &str,
        push_size: u32,
        stride: u32,
        attributes: &[(u32, vk::Format, u32)],
        colors: &[vk::Format],
        depth: vk::Format,
    ) -> Result<Pipeline> {
        let declared = reflect::layout(name, &[vert, frag])?;
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let vs = shader::module(ctx, vert, &format!("{name}.vert"))?;
        let fs = match shader::module(ctx, frag, &format!("{name}.frag")) {
            Ok(m) => m,
            Err(e) => {
                // SAFETY: unused.
                unsafe { ctx.raw().destroy_shader_module(vs, None) };
                return Err(e);
            }
        };
        let destroy_modules = || {
            // SAFETY: modules may be destroyed once the pipeline is created (or failed).
            unsafe {
                ctx.raw().destroy_shader_module(vs, None);
                ctx.raw().destroy_shader_module(fs, None);
            }
        };
        let (set_layout, layout) = match layouts(ctx.raw(), &declared, stages, push_size) {
            Ok(l) => l,
            Err(e) => {
                destroy_modules();
                return Err(e);
            }
        };
        let shader_stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vs).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(fs).name(c"main"),
        ];
        let vb = [vk::VertexInputBindingDescription { binding: 0, stride, input_rate: vk::VertexInputRate::VERTEX }];
        let va: Vec<_> = attributes
            .iter()
            .map(|&(location, format, offset)| vk::VertexInputAttributeDescription {
                location,
                binding: 0,
                format,
                offset,
            })
            .collect();
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vb)
            .vertex_attribute_descriptions(&va);
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let ms = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let ds = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS);
        let blend: Vec<_> = colors
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let cb = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend);
        // Culling is per mesh (which faces it hides), so it is set when drawing.
        let dynamic_states = [
            vk::DynamicState::VIEWPORT,
            vk::DynamicState::SCISSOR,
            vk::DynamicState::CULL_MODE,
            vk::DynamicState::FRONT_FACE,
        ];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering =
            vk::PipelineRenderingCreateInfo::default().color_attachment_formats(colors).depth_attachment_format(depth);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&shader_stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&ms)
            .depth_stencil_state(&ds)
            .color_blend_state(&cb)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering)];
        // SAFETY: modules and layout are live; the infos outlive the call.
        let created = unsafe { ctx.raw().create_graphics_pipelines(ctx.pipeline_cache.raw, &info, None) };
        destroy_modules();
        let p = Pipeline {
            raw: vk::Pipeline::null(),
            layout,
            set_layout,
            bind_point: vk::PipelineBindPoint::GRAPHICS,
            push_stages: stages,
            name: name.to_string(),
            declared,
        };
        let p = finish(ctx.raw(), created, p, "vkCreateGraphicsPipelines")?;
        p.name(ctx, name);
        Ok(p)
    }

    /// Points `set`, of this pipeline's set layout, at `bindings` (binding `i` at `bindings[i]`),
    /// once they are checked against its shaders' bindings ([`descriptor::check`]).
    pub fn write_set(&self, ctx: &Context, set: vk::DescriptorSet, bindings: &[Binding<'_>]) -> Result<()> {
        descriptor::check(&self.name, &self.declared, bindings)?;
        descriptor::write(ctx, set, &self.declared, bindings);
        Ok(())
    }

    /// Binds the pipeline, its descriptor set and the push constants.
    pub fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer, set: vk::DescriptorSet, push: &[u8]) {
        // SAFETY: `cmd` is recording; pipeline, layout and set are live and compatible.
        unsafe {
            ctx.raw().cmd_bind_pipeline(cmd, self.bind_point, self.raw);
            ctx.raw().cmd_bind_descriptor_sets(cmd, self.bind_point, self.layout, 0, &[set], &[]);
            if !push.is_empty() {
                ctx.raw().cmd_push_constants(cmd, self.layout, self.push_stages, 0, push);
            }
        }
    }

    pub fn destroy(self, ctx: &Context) {
        // SAFETY: the GPU is done with the pipeline (work is waited on).
        unsafe { self.destroy_on(ctx.raw()) };
    }

    /// Destroys the pipeline and its layouts, each once.
    ///
    /// # Safety
    /// `raw` is the device the pipeline was made on, and no pending GPU work uses the pipeline.
    pub unsafe fn destroy_on(self, raw: &ash::Device) {
        // SAFETY: the caller's contract; each object is destroyed once (the pipeline by value).
        unsafe {
            if self.raw != vk::Pipeline::null() {
                raw.destroy_pipeline(self.raw, None);
            }
            raw.destroy_pipeline_layout(self.layout, None);
            raw.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
