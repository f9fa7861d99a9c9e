//! What a frame is asked for and what it returns: the estimator, the view, the size and sample
//! limits, the settings, the frame, and how a mesh view frame relates to the ones before it.

use glam::DVec3;

use crate::error::Result;
use crate::reference::Image;
use crate::scene::Camera;
use crate::vk::query::PassTime;

/// How the specular part (or, for `mis`, the whole material) is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    /// The paper's: Halton BRDF sampling of each lobe reading the prefiltered environment.
    Fis,
    /// The same samples reading level 0 only.
    Plain,
    /// Environment and BRDF sampling combined by the balance heuristic, diffuse included.
    Mis,
    /// The default: the map's key lights split off; each lobe pass integrates the residual map
    /// (prefiltered, a Hammersley set shifted per frame, lod bias [`lobe::KEY_LOD_BIAS`]) and the lobe
    /// under the lights (light and BRDF samples, balance heuristic, or the quadrature points of the
    /// lights or of their tiles for a lobe wider than those); the diffuse pass takes the residual's SH9
    /// and the lights as distant sources.
    Key,
}

impl Estimator {
    pub fn parse(s: &str) -> Option<Estimator> {
        match s {
            "fis" => Some(Estimator::Fis),
            "plain" => Some(Estimator::Plain),
            "mis" => Some(Estimator::Mis),
            "key" => Some(Estimator::Key),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Estimator::Fis => "fis",
            Estimator::Plain => "plain",
            Estimator::Mis => "mis",
            Estimator::Key => "key",
        }
    }

    /// Every estimator, the default first.
    pub const ALL: [Estimator; 4] = [Estimator::Key, Estimator::Fis, Estimator::Plain, Estimator::Mis];

    /// The names `--estimator` accepts, for messages: `key|fis|plain|mis`.
    pub fn names() -> String {
        Estimator::ALL.map(Estimator::name).join("|")
    }
}

/// The bright light samples the `key` estimator's lobe passes take per pixel for `spp` BRDF
/// samples per component: as many, at most [`MAX_LIGHT_SAMPLES`]. (Four per BRDF sample lower the
/// error of the lobes that take them, but cost as much as doubling the BRDF samples, which does as
/// well: docs/renderer.md, Alternatives measured and rejected.)
pub fn key_light_samples(spp: u32) -> u32 {
    spp.clamp(1, MAX_LIGHT_SAMPLES)
}

/// The most bright light samples a frame takes: 408 and the dark set's 102 fill the lobe pass's
/// uniform block of 512 (`gpu::LIGHT_SET_MAX`).
pub const MAX_LIGHT_SAMPLES: u32 = 408;
// The bright set and the dark one (a quarter of it, `keylight::LightSampling::dark_samples`) fit the block;
// past it the binding's range would cut samples off without a word.
const _: () = assert!((MAX_LIGHT_SAMPLES + MAX_LIGHT_SAMPLES / 4) as usize <= super::gpu::LIGHT_SET_MAX);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Mesh,
    Canvas,
}

/// The most samples per pixel (per lobe for `fis`/`plain`, per pixel for `mis`) a frame takes. The
/// sample tables are uploaded whole (16 bytes a sample for the lobe passes, 32 for `mis`, rounded
/// up to a power of two) and `mis` records one dispatch per 32 samples: 65536 keeps the table at
/// 2 MiB and a frame at 2048 dispatches, 16× the 4096 spp at which `mis` is within about 1 % relative
/// L1 of the CPU reference (studio, sky; docs/renderer.md).
pub const MAX_SPP: u32 = 1 << 16;

/// The most pixels a GPU frame has: 8192×4096 (twice 8K UHD). Every pixel costs 64 bytes of render
/// targets, 16 of readback buffer and 16 of host image, so the largest frame needs about 2.7 GB
/// (a frame of the device's largest image, 16384², would need 21 GB).
pub const MAX_PIXELS: u64 = 8192 * 4096;

/// Refuses (naming the flag) an image size or sample count beyond the limits, before anything is
/// allocated: the sizes of [`Renderer::render`] and of `render`'s flags.
pub fn check_limits(width: u32, height: u32, spp: u32) -> Result<()> {
    crate::imageio::check_image_limits((width, height, spp), (MAX_PIXELS, MAX_SPP), "8192x4096", "a GPU frame")
}

/// What one frame renders.
#[derive(Clone, Debug)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel per lobe (`fis`, `plain`) or per pixel (`mis`).
    pub spp: u32,
    pub estimator: Estimator,
    pub view: View,
    pub camera: Camera,
    /// The canvas light (unit) and its intensity.
    pub light: DVec3,
    pub intensity: f64,
    /// The mesh view's backdrop: the level of the environment's mip chain it shows (0 the map
    /// itself; fractional levels blend the two nearest, the last level is the map's mean).
    pub backdrop_blur: f64,
}

/// A rendered frame: the linear image (alpha = coverage), the GPU time of every pass that ran and
/// of the whole frame (first command to last: the passes, the clears and copies between them, and
/// the image's copy into the readback buffer).
pub struct Frame {
    pub image: Image,
    pub timings: Vec<PassTime>,
    pub frame_ms: f64,
    /// The pipeline barriers and dispatches the frame's passes recorded (the readback's copy not
    /// included).
    pub commands: crate::vk::counts::Counted,
}

impl Frame {
    /// The sum of the timed passes.
    pub fn passes_ms(&self) -> f64 {
        self.timings.iter().map(|t| t.ms).sum::<f64>() + 0.0
    }

    /// The whole frame less its timed passes (`vk::query::untimed_ms`).
    pub fn untimed_ms(&self) -> f64 {
        crate::vk::query::untimed_ms(self.frame_ms, self.passes_ms())
    }
}

/// What [`super::Renderer::record`] put in the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[must_use]
pub enum Recorded {
    /// The view's passes.
    Done,
    /// Nothing: a lobe pipeline the view needs is being built in the background; the view keeps its
    /// last image.
    Waiting,
}

/// How a mesh view frame relates to the ones before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// A new image (the refinement restarts).
    Fresh,
    /// More `mis` samples added to the running sum.
    Refine,
}
