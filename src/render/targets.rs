//! The images a frame renders into, per image size: the G-buffer (the world normal's octahedral
//! code, 0 off the object; depth), the `RGBA32F` accumulation image the shading passes add into, and
//! the running sum of progressive refinement. They persist from frame to frame (per view).

use ash::vk;

use crate::vk::{barrier, Buffer, Context, Image};
use crate::Result;

/// The G-buffer: the world normal's octahedral code, 0 off the object (`gbuffer_code` in
/// `glsl/include/common.glsl`), 4 bytes a pixel.
pub const GBUFFER_FORMAT: vk::Format = vk::Format::R32_UINT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct Targets {
    pub width: u32,
    pub height: u32,
    pub normal: Image,
    pub depth: Image,
    pub accum: Image,
    /// The running sum of progressive refinement frames (see `accumulate`).
    pub sum: Image,
    /// The `key` estimator's filtered lobes before their filter, each shaded pixel marked with its
    /// normal (`denoise`), and the filter's intermediate image.
    pub rough: Image,
    pub mid: Image,
    /// A sparse filtered frame's samples (`denoise::sparse`): one texel per 2 × 2 block of pixels.
    pub cells: Image,
    /// Their light terms (the lights' points), one texel a block, interpolated by the filter.
    pub cells_light: Image,
    /// The shaded pixels of the G-buffer, listed by `compact` (the mesh view's diffuse, lobe and `mis` passes
    /// run over it).
    pub pixels: Buffer,
    /// The 2 × 2 blocks with a shaded pixel, each by its first shaded pixel (`compact`): the sparse
    /// filtered lobe passes run over it.
    pub blocks: Buffer,
    /// The 2 × 2 blocks with a pixel off the object, each by its top-left pixel (`compact` with
    /// `Start::Later`): the background pass of such a frame runs over it (`BackgroundPass::record_blocks`).
    pub background_blocks: Buffer,
    /// What the G-buffer holds — mesh, camera, culling — while it may be reused (`None`: nothing).
    pub gbuffer_of: Option<GBufferKey>,
    /// `pixels` lists the G-buffer's shaded pixels: a frame that rasterises and needs no pass over
    /// them leaves the list empty (`compact::Start`), and the next frame that keeps the G-buffer and
    /// needs it lists them.
    pub pixels_listed: bool,
    /// The accumulation image as the background and diffuse passes left it, kept for frames that
    /// keep the G-buffer (painting: only the lobes change), and what it was made from.
    pub base: Image,
    pub base_of: Option<BaseKey>,
    /// `accum` holds an image (a view was recorded into it, or it was cleared for a view waiting
    /// for its pipelines); false for new targets, whose images are undefined.
    pub drawn: bool,
}

/// What a G-buffer was rasterised from.
pub type GBufferKey = ((String, usize, usize), crate::scene::Camera, bool);

/// What `Targets::base` was drawn from besides the G-buffer: the environment's key, whether the
/// diffuse term is `key`'s (the residual's SH and the lights), the diffuse albedo's bits and the
/// backdrop's mip level's bits.
pub type BaseKey = ((String, usize, usize, u64), bool, [u64; 3], u32);

impl Targets {
    pub fn new(ctx: &Context, width: u32, height: u32) -> Result<Targets> {
        let mut made: Vec<Image> = Vec::new();
        let built = images(ctx, width, height, &mut made).and_then(|()| lists(ctx, width, height));
        let [pixels, blocks, background_blocks] = match built {
            Ok(b) => b,
            Err(e) => {
                for i in made {
                    i.destroy(ctx);
                }
                return Err(e);
            }
        };
        let mut it = made.into_iter();
        let mut next = || it.next().expect("nine images were made");
        Ok(Targets {
            width,
            height,
            normal: next(),
            depth: next(),
            accum: next(),
            base: next(),
            sum: next(),
            rough: next(),
            mid: next(),
            cells: next(),
            cells_light: next(),
            pixels,
            blocks,
            background_blocks,
            gbuffer_of: None,
            pixels_listed: false,
            base_of: None,
            drawn: false,
        })
    }

    /// Makes the accumulation image writable by the compute pass that starts a frame (its old
    /// contents are dropped, after any earlier frame's reads).
    pub fn start_accum(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.accum.discard_to_general(ctx, cmd, barrier::COMPUTE_WRITE);
    }

    /// Copies the accumulation image, as the background and diffuse passes wrote it, into `base`.
    pub fn save_base(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        let general = vk::ImageLayout::GENERAL;
        self.accum.barrier(ctx, cmd, general, general, barrier::COMPUTE_WRITE, barrier::TRANSFER_READ);
        self.base.discard_to_general(ctx, cmd, barrier::TRANSFER_WRITE);
        self.accum.record_copy_to(ctx, cmd, &self.base);
        // The lobe passes write `accum` after the copy has read it.
        self.accum.barrier(ctx, cmd, general, general, barrier::TRANSFER_READ, barrier::COMPUTE_READ_WRITE);
    }

    /// Starts the accumulation image from `base` instead of the background and diffuse passes.
    pub fn restore_base(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        let general = vk::ImageLayout::GENERAL;
        self.base.barrier(ctx, cmd, general, general, barrier::TRANSFER_WRITE, barrier::TRANSFER_READ);
        self.accum.discard_to_general(ctx, cmd, barrier::TRANSFER_WRITE);
        self.base.record_copy_to(ctx, cmd, &self.accum);
        self.accum.barrier(ctx, cmd, general, general, barrier::TRANSFER_WRITE, barrier::ANY);
    }

    pub fn destroy(self, ctx: &Context) {
        for i in [
            self.normal,
            self.depth,
            self.accum,
            self.base,
            self.sum,
            self.rough,
            self.mid,
            self.cells,
            self.cells_light,
        ] {
            i.destroy(ctx);
        }
        self.pixels.destroy(ctx);
        self.blocks.destroy(ctx);
        self.background_blocks.destroy(ctx);
    }
}

/// The view's nine images, in the order of [`Targets`]' fields, pushed onto `made` as they are made
/// (so that the caller frees them if a later one fails).
fn images(ctx: &Context, width: u32, height: u32, made: &mut Vec<Image>) -> Result<()> {
    let gbuf = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::STORAGE;
    made.push(Image::new(ctx, (width, height), GBUFFER_FORMAT, 1, gbuf, "gbuffer.normal")?);
    let depth = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT;
    made.push(Image::new(ctx, (width, height), DEPTH_FORMAT, 1, depth, "gbuffer.depth")?);
    // The shading images: RGBA32F storage images with `usage` besides.
    let rgba = |usage: vk::ImageUsageFlags, name: &str| {
        let usage = vk::ImageUsageFlags::STORAGE | usage;
        Image::new(ctx, (width, height), vk::Format::R32G32B32A32_SFLOAT, 1, usage, name)
    };
    let (src, dst) = (vk::ImageUsageFlags::TRANSFER_SRC, vk::ImageUsageFlags::TRANSFER_DST);
    made.push(rgba(src | dst, "accum")?);
    made.push(rgba(src | dst, "accum.base")?);
    made.push(rgba(src, "refinement.sum")?);
    made.push(rgba(dst, "rough")?);
    made.push(rgba(vk::ImageUsageFlags::empty(), "rough.mid")?);
    // A sparse frame's images: one texel a 2 × 2 block, cleared each frame.
    let half = (width.div_ceil(2), height.div_ceil(2));
    let cells = |name: &str| {
        let usage = vk::ImageUsageFlags::STORAGE | dst;
        Image::new(ctx, half, vk::Format::R32G32B32A32_SFLOAT, 1, usage, name)
    };
    made.push(cells("rough.cells")?);
    made.push(cells("rough.cells_light")?);
    Ok(())
}

/// The lists of shaded pixels, of blocks, and of blocks with a pixel off the object.
fn lists(ctx: &Context, width: u32, height: u32) -> Result<[Buffer; 3]> {
    let mut lists = Vec::new();
    let pixels = u64::from(width) * u64::from(height);
    let blocks = u64::from(width.div_ceil(2)) * u64::from(height.div_ceil(2));
    for (name, entries) in [("pixels", pixels), ("blocks", blocks), ("background.blocks", blocks)] {
        match super::compact::list_buffer(ctx, entries, name) {
            Ok(list) => lists.push(list),
            Err(e) => {
                for list in lists {
                    list.destroy(ctx);
                }
                return Err(e);
            }
        }
    }
    match <[Buffer; 3]>::try_from(lists) {
        Ok(lists) => Ok(lists),
        Err(_) => unreachable!("three lists made above"),
    }
}
