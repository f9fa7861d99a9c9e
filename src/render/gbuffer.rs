//! Pass 0: rasterises the mesh into the G-buffer (the world normal's octahedral code, 0 off the object;
//! the passes take ω_o from the pixel's camera ray), so that every shading pass costs the same
//! whatever the triangle count.

use ash::vk;

use super::mesh::{GpuMesh, VERTEX_STRIDE};
use super::targets::{Targets, DEPTH_FORMAT, GBUFFER_FORMAT};
use crate::scene::mesh::Hidden;
use crate::vk::pipeline::Pipeline;
use crate::vk::Context;
use crate::Result;

pub struct GBufferPass {
    pipeline: Pipeline,
}

impl GBufferPass {
    pub fn new(ctx: &Context) -> Result<GBufferPass> {
        let pipeline = Pipeline::raster(
            ctx,
            (crate::spirv!("gbuffer.vert"), crate::spirv!("gbuffer.frag")),
            "gbuffer",
            64,
            VERTEX_STRIDE,
            &[(0, vk::Format::R32G32B32_SFLOAT, 0), (1, vk::Format::R32G32B32_SFLOAT, 12)],
            &[GBUFFER_FORMAT],
            DEPTH_FORMAT,
        )?;
        Ok(GBufferPass { pipeline })
    }

    /// Records the pass; leaves the normal in `GENERAL` for the compute passes. With `cull`,
    /// the faces the mesh hides from an eye outside it are skipped (the caller checks the eye).
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        targets: &Targets,
        mesh: &GpuMesh,
        view_proj: &glam::Mat4,
        cull: bool,
    ) {
        // Vulkan judges the winding on the framebuffer (y down), where `view_proj` (view space with
        // y down the image) keeps the winding seen from the eye: a face counter-clockwise from the eye
        // is counter-clockwise there.
        let (cull_mode, front) = match (cull, mesh.hidden) {
            (true, Hidden::Clockwise) => (vk::CullModeFlags::BACK, vk::FrontFace::COUNTER_CLOCKWISE),
            (true, Hidden::CounterClockwise) => (vk::CullModeFlags::BACK, vk::FrontFace::CLOCKWISE),
            _ => (vk::CullModeFlags::NONE, vk::FrontFace::CLOCKWISE),
        };
        to_attachments(ctx, cmd, targets);
        self.draw(ctx, cmd, targets, mesh, view_proj, (cull_mode, front));
        let color = (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
        let read = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_READ);
        let general = (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::GENERAL);
        targets.normal.barrier(ctx, cmd, general.0, general.1, color, read);
    }

    /// Clears the attachments and draws the mesh's triangles into them.
    fn draw(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        targets: &Targets,
        mesh: &GpuMesh,
        view_proj: &glam::Mat4,
        (cull_mode, front): (vk::CullModeFlags, vk::FrontFace),
    ) {
        let normal = &targets.normal;
        let clear = vk::ClearValue { color: vk::ClearColorValue { uint32: [0; 4] } };
        let colors = [vk::RenderingAttachmentInfo::default()
            .image_view(normal.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(clear)];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(targets.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D { width: targets.width, height: targets.height },
        };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: targets.width as f32,
            height: targets.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let raw = ctx.raw();
        // SAFETY: `cmd` is recording; every handle is live; the attachments are in the layouts named.
        unsafe {
            raw.cmd_begin_rendering(cmd, &info);
            raw.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline.raw);
            raw.cmd_set_viewport(cmd, 0, &[viewport]);
            raw.cmd_set_scissor(cmd, 0, &[area]);
            raw.cmd_set_cull_mode(cmd, cull_mode);
            raw.cmd_set_front_face(cmd, front);
            raw.cmd_push_constants(
                cmd,
                self.pipeline.layout,
                self.pipeline.push_stages,
                0,
                bytemuck::bytes_of(&view_proj.to_cols_array()),
            );
            raw.cmd_bind_vertex_buffers(cmd, 0, &[mesh.vertices.raw], &[0]);
            raw.cmd_bind_index_buffer(cmd, mesh.indices.raw, 0, vk::IndexType::UINT32);
            raw.cmd_draw_indexed(cmd, mesh.index_count, 1, 0, 0, 0);
            raw.cmd_end_rendering(cmd);
        }
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}

/// The normal and depth images as attachments, after the earlier frame's reads and depth tests.
fn to_attachments(ctx: &Context, cmd: vk::CommandBuffer, targets: &Targets) {
    let none = crate::vk::barrier::EARLIER_READS;
    let color = (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
    let depth_access = (
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
    );
    targets.normal.barrier(
        ctx,
        cmd,
        vk::ImageLayout::UNDEFINED,
        vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        none,
        color,
    );
    targets.depth.barrier(
        ctx,
        cmd,
        vk::ImageLayout::UNDEFINED,
        vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
        depth_access, // the previous frame's depth tests
        depth_access,
    );
}
