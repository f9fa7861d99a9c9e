//! The editor's window on the GPU: the mesh view (its last frame, or the refinement's sum over the
//! sample count) and the canvas, each with its exposure and the sRGB curve, the snap marker, and the
//! window grey, written into an `RGBA8` storage image that is then copied into the swapchain image.
//! The image persists across frames: a frame rewrites only the parts whose inputs changed (the
//! mesh view, the canvas, or everything after a new image or layout), each with a pipeline of its
//! own over its rectangle only (on lavapipe the whole window at every frame is a large share of
//! the frame's time).

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Context, Image};
use crate::Result;

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
    region: [u32; 4],
    sources: [u32; 4],
}
const _: () = assert!(std::mem::size_of::<ComposePush>() == 96);

/// Which parts of the window a frame rewrites.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Parts {
    pub mesh: bool,
    pub canvas: bool,
    /// The grey around the views (and then both views too: a new image or layout).
    pub all: bool,
}

impl Parts {
    pub fn any(&self) -> bool {
        self.mesh || self.canvas || self.all
    }
}

/// Where the views go and how they are scaled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// The mesh view's left edge, width and height (pixels).
    pub mesh: (u32, u32, u32),
    /// The canvas's left edge and side.
    pub canvas: (u32, u32),
    /// Linear scale of the mesh view's object (exposure over the number of summed samples) and of
    /// the canvas.
    pub mesh_scale: f32,
    /// Linear scale of the mesh view's backdrop (the pixels off the object, alpha 0): its own
    /// brightness over the number of summed samples.
    pub backdrop_scale: f32,
    /// The samples the mesh view's image sums (1 for a frame's own image).
    pub summed: u32,
    pub canvas_scale: f32,
    /// The snap marker's pixel, if shown.
    pub marker: Option<(f32, f32)>,
}

pub struct ComposePass {
    /// `compose.comp` for the mesh view, the canvas and the grey (its `PARTS` 1, 2, 4).
    pipelines: [Pipeline; 3],
}

impl ComposePass {
    pub fn new(ctx: &Context) -> Result<ComposePass> {
        let variants = [("compose.mesh", &[1][..]), ("compose.canvas", &[2]), ("compose.grey", &[4])];
        let pipelines = Pipeline::compute_variants(ctx, crate::spirv!("compose.comp"), 96, variants)?;
        Ok(ComposePass { pipelines })
    }

    /// Writes the `parts` of `window` (left in `GENERAL`, ordered before transfer reads) from `mesh`
    /// and `canvas` (`RGBA32F`, in `GENERAL`, written by earlier passes; magnified bilinearly where
    /// smaller than their places in `p`: the editor's previews); the rest of `window` keeps
    /// what earlier frames wrote (`parts.all` drops it and writes everything).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        pool: vk::DescriptorPool,
        window: &Image,
        (mesh, canvas): (&Image, &Image),
        p: &Placement,
        parts: Parts,
    ) -> Result<()> {
        if parts.all {
            window.discard_to_general(ctx, cmd, barrier::COMPUTE_WRITE);
        } else {
            // Earlier frames' copies out of the image come first.
            barrier::memory(ctx, cmd, barrier::TRANSFER_READ, barrier::COMPUTE_WRITE);
        }
        let bindings =
            [Binding::StorageImage(window), Binding::StorageImageRead(mesh), Binding::StorageImageRead(canvas)];
        // The one set serves every pipeline (below), so it is checked against each.
        for pipeline in &self.pipelines[1..] {
            descriptor::check(&pipeline.name, &pipeline.declared, &bindings)?;
        }
        let set = descriptor::allocate(ctx, pool, self.pipelines[0].set_layout)?;
        self.pipelines[0].write_set(ctx, set, &bindings)?;
        let (mx, my) = p.marker.unwrap_or((0.0, 0.0));
        let mut push = ComposePush {
            window_size: [window.width, window.height, p.mesh.2, p.marker.is_some() as u32],
            views: [p.mesh.0, p.mesh.1, p.canvas.0, p.canvas.1],
            scale: [p.mesh_scale, p.canvas_scale, mx, my],
            background: [
                BACKGROUND[0] as f32 / 255.0,
                BACKGROUND[1] as f32 / 255.0,
                BACKGROUND[2] as f32 / 255.0,
                p.backdrop_scale,
            ],
            region: [0; 4],
            sources: [mesh.width, mesh.height, canvas.width, p.summed.max(1)],
        };
        let rects = [
            (parts.mesh || parts.all, [p.mesh.0, 0, p.mesh.1, p.mesh.2]),
            (parts.canvas || parts.all, [p.canvas.0, 0, p.canvas.1, p.canvas.1]),
            (parts.all, [0, 0, window.width, window.height]),
        ];
        for (pipeline, (on, region)) in self.pipelines.iter().zip(rects) {
            if !on || region[2] == 0 || region[3] == 0 {
                continue;
            }
            push.region = region;
            // Every pipeline has the same layout, so the one set serves all three.
            pipeline.bind(ctx, cmd, set, bytemuck::bytes_of(&push));
            ctx.counts.dispatch();
            // SAFETY: `cmd` is recording with the compute pipeline bound.
            unsafe { ctx.raw().cmd_dispatch(cmd, region[2].div_ceil(8), region[3].div_ceil(8), 1) };
        }
        barrier::memory(ctx, cmd, barrier::COMPUTE_WRITE, barrier::TRANSFER_READ);
        Ok(())
    }

    pub fn destroy(self, ctx: &Context) {
        for p in self.pipelines {
            p.destroy(ctx);
        }
    }
}
