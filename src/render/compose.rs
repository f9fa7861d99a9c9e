//! The editor's window on the GPU: the mesh view (its last frame, or the refinement's sum over the
//! frame count) and the canvas, each with its exposure and the sRGB curve, the snap marker, and the
//! window grey, written into an `RGBA8` storage image that is then copied into the swapchain image.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Context, Image};
use crate::Result;

const BINDINGS: [vk::DescriptorType; 3] =
    [vk::DescriptorType::STORAGE_IMAGE, vk::DescriptorType::STORAGE_IMAGE, vk::DescriptorType::STORAGE_IMAGE];

/// The format of the composed window image.
pub const WINDOW_FORMAT: vk::Format = vk::Format::R8G8B8A8_UNORM;

/// The window grey behind and between the views (sRGB 8-bit).
pub const BACKGROUND: [u8; 3] = [32, 32, 36];

/// The snap marker's colour (sRGB 8-bit).
pub const MARKER: [u8; 3] = [255, 210, 60];

/// `Push` of `compose.comp`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct ComposePush {
    window_size: [u32; 4],
    views: [u32; 4],
    scale: [f32; 4],
    background: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<ComposePush>() == 64);

/// Where the views go and how they are scaled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The mesh view's left edge, width and height (pixels).
    pub mesh: (u32, u32, u32),
    /// The canvas's left edge and side.
    pub canvas: (u32, u32),
    /// Linear scale of the mesh view (exposure over the number of summed frames) and of the canvas.
    pub mesh_scale: f32,
    pub canvas_scale: f32,
    /// The snap marker's pixel, if shown.
    pub marker: Option<(f32, f32)>,
}

pub struct ComposePass {
    pipeline: Pipeline,
}

impl ComposePass {
    pub fn new(ctx: &Context) -> Result<ComposePass> {
        let pipeline = Pipeline::compute(ctx, crate::spirv!("compose.comp"), "compose", &BINDINGS, 64, &[])?;
        Ok(ComposePass { pipeline })
    }

    /// Writes `window` (any earlier contents dropped; left in `GENERAL`, ordered before transfer
    /// reads) from `mesh` and `canvas` (`RGBA32F`, in `GENERAL`, written by earlier passes).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        pool: vk::DescriptorPool,
        window: &Image,
        (mesh, canvas): (&Image, &Image),
        p: &Placement,
    ) -> Result<()> {
        window.discard_to_general(ctx, cmd, barrier::COMPUTE_WRITE);
        let set = descriptor::allocate(ctx, pool, self.pipeline.set_layout)?;
        descriptor::write(
            ctx,
            set,
            &[Binding::StorageImage(window.view), Binding::StorageImage(mesh.view), Binding::StorageImage(canvas.view)],
        );
        let (mx, my) = p.marker.unwrap_or((0.0, 0.0));
        let push = ComposePush {
            window_size: [window.width, window.height, p.mesh.2, p.marker.is_some() as u32],
            views: [p.mesh.0, p.mesh.1, p.canvas.0, p.canvas.1],
            scale: [p.mesh_scale, p.canvas_scale, mx, my],
            background: [BACKGROUND[0] as f32 / 255.0, BACKGROUND[1] as f32 / 255.0, BACKGROUND[2] as f32 / 255.0, 1.0],
        };
        self.pipeline.bind(ctx, cmd, set, bytemuck::bytes_of(&push));
        // SAFETY: `cmd` is recording with the compute pipeline bound.
        unsafe { ctx.raw().cmd_dispatch(cmd, window.width.div_ceil(8), window.height.div_ceil(8), 1) };
        barrier::memory(ctx, cmd, barrier::COMPUTE_WRITE, barrier::TRANSFER_READ);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        self.pipeline.destroy(ctx);
    }
}
