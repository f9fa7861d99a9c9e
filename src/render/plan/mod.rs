//! The frame as a plan: what a frame runs, in order, and what it leaves out, as data. [`plan`] is a
//! pure function from what a frame is asked for ([`Request`]: view, size, estimator, samples,
//! progress, the material, the map's key lights, what the view's targets kept from the frame
//! before, the device's choices and the renderer's options) to a [`Plan`]: an ordered list of
//! [`Step`]s, each a [`Pass`] with its pipeline variant, its inputs and outputs and the reason it
//! runs, and a list of what was left out and why. No Vulkan type is in it: it is unit-tested without
//! a device (the tests below name the rule of docs/renderer.md each checks), printed by
//! `brdf-shop render --plan`, carried by `--timings` and `bench` JSON, and followed by the
//! recorder (`render::record`), which decides nothing.

pub mod device;
mod lights;
mod lobes;
mod show;
#[cfg(test)]
mod tests;
pub mod variant;

pub use device::{DevicePlan, ENV};
pub use lights::{Cut, KeyLightSet, TileLights, WideLightSet};
pub use lobes::{LobeLights, LobeStep};

use super::{denoise, key_light_samples, Estimator, View};
use crate::brdf::Material;
use crate::scene::Camera;
use variant::Into;

/// The renderer's choices that a user (`bench`, `report`, the tests) may compare; each default is
/// the measured better one (docs/renderer.md, Alternatives measured and rejected).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Run the lobe passes one sample at a time instead of four (the benchmark's baseline).
    pub scalar_lobes: bool,
    /// Skip the faces a closed mesh hides from an eye outside it (`Mesh::hidden_faces`); the image
    /// is the same either way.
    pub cull_hidden_faces: bool,
    /// Let the `key` lobe passes of narrow lobes skip the key lights at pixels whose lobe cannot
    /// reach them (`lobe::reach_test_pays`); the image is the same either way.
    pub light_reach_test: bool,
    /// Draw every lobe pass with the pipeline of every output (`lobe::Output::Any`): the editor's
    /// stand-in while a view's own pipeline is built.
    pub any_output_lobes: bool,
}

impl Default for Options {
    fn default() -> Options {
        Options { scalar_lobes: false, cull_hidden_faces: true, light_reach_test: true, any_output_lobes: false }
    }
}

/// What the view's targets kept from the frames before, as the renderer found it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Kept {
    /// The G-buffer was rasterised for this mesh, camera and culling and may be reused.
    pub gbuffer: bool,
    /// With it, the lists of shaded pixels (not only the blocks) are written.
    pub pixels_listed: bool,
    /// The saved background and diffuse image (`Targets::base`) is of this map, estimator,
    /// diffuse albedo and backdrop.
    pub base: bool,
}

/// What a frame is asked for.
#[derive(Clone, Copy)]
pub struct Request<'a> {
    pub view: View,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub estimator: Estimator,
    pub camera: &'a Camera,
    /// `Some(n)`: a refinement frame adding to a running sum of `n` `mis` samples.
    pub refine_from: Option<u32>,
    pub material: &'a Material,
    /// The map's key lights, where it has any.
    pub lights: Option<&'a KeyLightSet>,
    pub kept: Kept,
    pub device: DevicePlan,
    pub options: &'a Options,
}

/// The images the lobe passes that the filter takes add into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeImages {
    /// The sparse filter's cells and their light term (`Targets::cells`, `cells_light`).
    Cells,
    /// The dense filter's input (`Targets::rough`).
    Rough,
}

/// How the compact pass starts the listed pixels of the frame's image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    /// (0, 0, 0, 1) plus the diffuse term (`Some`: the albedo, and whether the `key` estimator's
    /// lights are added).
    Here(Option<([f64; 3], bool)>),
    /// (0, 0, 0, 1) from a clear, the diffuse term left to the frame's sparse filter, which reads
    /// and writes every listed pixel anyway: a full-size image store less (`compact.comp` LATER);
    /// the background left to the background pass over the blocks with a pixel off the object.
    /// `pixels`: whether the list of pixels is written too (a frame whose passes all run over the
    /// blocks leaves it empty).
    Later { pixels: bool },
}

impl Start {
    /// Whether the pass lists the pixels (it always lists the blocks).
    pub fn lists_pixels(self) -> bool {
        !matches!(self, Start::Later { pixels: false })
    }
}

/// One pass of a frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Pass {
    /// The spherical canvas under the canvas light.
    Canvas,
    /// Rasterise the G-buffer (back faces culled with `cull`), list the shaded pixels and blocks and
    /// start the image (`compact.comp`), and with `background_blocks` draw the background over the
    /// blocks off the object.
    GBuffer { cull: bool, start: Start, background_blocks: bool },
    /// Copy the saved background and diffuse image back (`Targets::base`).
    RestoreBase,
    /// List the kept G-buffer's pixels and start the image (`compact.comp`, `Start::Here`).
    Compact { diffuse: Option<([f64; 3], bool)> },
    /// The environment behind the object (alpha 0) and (0, 0, 0, 1) on it.
    Background,
    /// The SH diffuse term (plus the key lights for `key`).
    Diffuse { albedo: [f64; 3], key: bool },
    /// Save the background and diffuse image for the frames that keep the G-buffer.
    SaveBase,
    /// Zero the images the filtered lobes add into: by a compute pass (`zero.comp`) or a transfer
    /// clear (`by_compute` false).
    Zero { images: LobeImages, by_compute: bool },
    /// One lobe's specular term.
    Lobe(LobeStep),
    /// The rough lobes' filter: sparse or dense, over lobes of `min(α)` ≥ `min_alpha`, adding the
    /// deferred diffuse term where the compact pass left it.
    Denoise { min_alpha: f64, sparse: bool, diffuse: Option<([f64; 3], bool)> },
    /// The lobes' energy compensation terms (an energy-preserving material), over the listed pixels;
    /// `lights`: the map has key lights, which the pass takes as distant sources over the residual
    /// map's coefficients, whatever the estimator.
    Compensation { lights: bool },
    /// The whole material by multiple importance sampling, samples `offset..offset + samples`.
    Mis { offset: u32, samples: u32 },
    /// Add the frame into the refinement's running sum (`first`: start it).
    Accumulate { first: bool, samples: u32 },
}

/// A pass and why the frame runs it.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub pass: Pass,
    pub why: String,
}

/// Something a frame of this kind may run that this one does not, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct LeftOut {
    pub what: String,
    pub why: String,
}

/// A frame's plan: its passes in order, what it leaves out, and what the recorder keeps for the
/// next frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub view: View,
    pub steps: Vec<Step>,
    pub left_out: Vec<LeftOut>,
    /// Whether the frame rasterises its G-buffer.
    pub raster: bool,
    /// Whether the filtered lobes are sampled once per 2 × 2 block (`denoise::sparse`).
    pub sparse: bool,
    /// How many light samples the frame draws (`key_light_samples`), where a lobe takes them by MIS.
    pub light_samples: Option<u32>,
    /// After the frame: whether the G-buffer's pixels are listed (`None`: as they were).
    pub pixels_listed: Option<bool>,
    /// Whether the frame's start draws or restores the saved base image (`Targets::base`): a
    /// frame that keeps the G-buffer on a device that copies (`DevicePlan::copy_base`).
    pub base_used: bool,
}

impl Plan {
    /// The lobe passes, in order.
    pub fn lobes(&self) -> impl Iterator<Item = &LobeStep> {
        self.steps.iter().filter_map(|s| match &s.pass {
            Pass::Lobe(l) => Some(l),
            _ => None,
        })
    }

    fn run(&mut self, pass: Pass, why: impl std::fmt::Display) {
        self.steps.push(Step { pass, why: why.to_string() });
    }

    fn leave_out(&mut self, what: impl std::fmt::Display, why: impl std::fmt::Display) {
        self.left_out.push(LeftOut { what: what.to_string(), why: why.to_string() });
    }
}

/// The plan of the frame `r` asks for.
pub fn plan(r: &Request) -> Plan {
    let mut p = Plan {
        view: r.view,
        steps: Vec::new(),
        left_out: Vec::new(),
        raster: false,
        sparse: false,
        light_samples: None,
        pixels_listed: None,
        base_used: false,
    };
    if r.view == View::Canvas {
        p.run(Pass::Canvas, "the canvas view: the material under the canvas light, evaluated exactly");
        return p;
    }
    p.sparse = denoise::sparse(r.spp, r.width, r.height);
    let lobes = if r.estimator == Estimator::Mis { Vec::new() } else { lobes::choose(r, p.sparse, &mut p) };
    if lobes.iter().any(|l| matches!(l.variant.lights, variant::KeyLights::Samples { .. })) {
        p.light_samples = Some(key_light_samples(r.spp));
    }
    start(r, &lobes, &mut p);
    match r.estimator {
        Estimator::Mis => {
            let offset = r.refine_from.unwrap_or(0);
            p.run(Pass::Mis { offset, samples: r.spp }, "the `mis` estimator: the whole material, diffuse included");
        }
        _ => shade(r, lobes, &mut p),
    }
    match r.refine_from {
        Some(offset) => p.run(
            Pass::Accumulate { first: offset == 0, samples: r.spp },
            "a refinement frame adds its samples to the running sum",
        ),
        None => p.leave_out("accumulate", "a fresh frame: the refinement restarts"),
    }
    p
}

/// The diffuse term a frame of `r` draws, where it has one: its albedo, and whether the `key`
/// estimator's lights are added.
fn diffuse_term(r: &Request) -> Option<([f64; 3], bool)> {
    (r.estimator != Estimator::Mis && r.material.diffuse.iter().any(|&d| d != 0.0))
        .then_some((r.material.diffuse, r.estimator == Estimator::Key))
}

/// Whether a frame of `r` draws the lobes' energy compensation terms (`mis` evaluates them with the
/// whole material).
fn compensated(r: &Request) -> bool {
    r.estimator != Estimator::Mis && r.material.compensated() && r.material.lobes.iter().any(|l| l.albedo != [0.0; 3])
}

/// Whether the G-buffer's pass may cull back faces: exact only for an eye outside the mesh's
/// bounding sphere (radius 1, the mesh is normalised) by more than the farthest point of the
/// frustum in front of the near plane.
pub fn culls(camera: &Camera, width: u32, height: u32, options: &Options) -> bool {
    let (tx, ty) = camera.half_extents(width, height);
    let near_reach = crate::scene::camera::NEAR * (1.0 + tx * tx + ty * ty).sqrt();
    options.cull_hidden_faces && camera.eye.length() > 1.0 + near_reach
}

/// The passes that start a mesh view's image: the G-buffer's, or on a kept G-buffer the copy of the
/// saved base, the compact pass or the background.
fn start(r: &Request, lobes: &[LobeStep], p: &mut Plan) {
    let diffuse = diffuse_term(r);
    let mis = r.estimator == Estimator::Mis;
    let cells = |l: &LobeStep| matches!(l.into, Into::Cells { .. });
    p.raster = !r.kept.gbuffer;
    // A frame that rasterises and filters sparsely leaves the diffuse term to the filter, which reads
    // and writes every listed pixel anyway.
    let later = p.raster && r.device.clear_then_later && p.sparse && !mis && lobes.iter().any(cells);
    // Whether a pass of this frame runs over the list of pixels (the others run over the blocks).
    let over_pixels = mis || lobes.iter().any(|l| !cells(l)) || compensated(r);
    let start = if later { Start::Later { pixels: over_pixels } } else { Start::Here(diffuse) };
    if p.raster {
        let cull = culls(r.camera, r.width, r.height, r.options);
        let why = "no G-buffer of this mesh, camera and size is kept";
        p.run(Pass::GBuffer { cull, start, background_blocks: later }, why);
        p.pixels_listed = Some(start.lists_pixels());
        if later {
            p.leave_out("diffuse", "drawn by the sparse filter, which reads every listed pixel anyway");
        } else if diffuse.is_some() {
            p.leave_out("diffuse", "drawn by the G-buffer's pass as it starts the image");
        }
        return;
    }
    p.leave_out("gbuffer", "the G-buffer of this mesh, camera and size is kept");
    // A kept G-buffer whose pixels are not listed lists them, in the pass that starts the image as the
    // background and diffuse passes would (bit for bit); so does every such frame where the device
    // draws that image again rather than copying it.
    let copy_base = r.device.copy_base;
    let relist = !r.kept.pixels_listed || (!copy_base && !mis);
    p.base_used = !mis && copy_base;
    let restored = p.base_used && r.kept.base && !relist;
    if restored {
        p.run(Pass::RestoreBase, "the saved background and diffuse image is this frame's");
        p.leave_out("background, diffuse", "copied from the saved base image");
    } else if relist {
        let why = if r.kept.pixels_listed {
            "this device draws the kept image's start again rather than copying it"
        } else {
            "the kept G-buffer's pixels are not listed yet"
        };
        p.run(Pass::Compact { diffuse }, why);
        p.pixels_listed = Some(true);
    } else {
        p.run(Pass::Background, "a kept G-buffer: the environment behind the object");
    }
    if let Some((albedo, key)) = diffuse.filter(|_| !restored && !relist) {
        p.run(Pass::Diffuse { albedo, key }, "the material's diffuse term (SH9 irradiance)");
    }
    if !restored && p.base_used {
        p.run(Pass::SaveBase, "later frames on this G-buffer copy the start back");
    }
}

/// The lobe passes and the filter of an `fis`, `plain` or `key` frame.
fn shade(r: &Request, lobes: Vec<LobeStep>, p: &mut Plan) {
    if diffuse_term(r).is_none() {
        p.leave_out("diffuse", "the diffuse albedo is 0");
    }
    // The smallest α among the lobes the filter takes.
    let min_alpha = lobes
        .iter()
        .filter(|l| l.into != Into::Accum)
        .map(|l| {
            let lobe = &r.material.lobes[l.index as usize];
            lobe.alpha_x.min(lobe.alpha_y)
        })
        .fold(f64::INFINITY, f64::min);
    let filtered = min_alpha.is_finite();
    if filtered {
        let images = if p.sparse { LobeImages::Cells } else { LobeImages::Rough };
        let by_compute = r.device.zero_by_compute;
        p.run(Pass::Zero { images, by_compute }, "the filtered lobe passes add into zeroed images");
    }
    for l in lobes {
        let why = format!("lobe {} has non-zero albedo", l.index);
        p.run(Pass::Lobe(l), why);
    }
    if filtered {
        let deferred = match p.steps.iter().find(|s| matches!(s.pass, Pass::GBuffer { .. })) {
            Some(Step { pass: Pass::GBuffer { background_blocks: true, .. }, .. }) => diffuse_term(r),
            _ => None,
        };
        let (sparse, why) = if p.sparse {
            (true, "rough lobes sampled once a 2 × 2 block, filtered over their window")
        } else {
            (false, "rough lobes' per-pixel noise, filtered by normal")
        };
        p.run(Pass::Denoise { min_alpha, sparse, diffuse: deferred }, why);
    } else {
        let why = match r.estimator {
            Estimator::Key => "no lobe is rough enough for the filter",
            _ => "only the `key` estimator filters",
        };
        p.leave_out("zero, denoise", why);
    }
    if compensated(r) {
        let why = "the material preserves energy: each lobe's compensation term (SH9 of the map)";
        p.run(Pass::Compensation { lights: r.lights.is_some() }, why);
    } else if r.material.normalization == crate::brdf::Normalization::Reciprocal {
        let why =
            if r.material.preserve_energy { "no lobe has albedo" } else { "the material does not preserve energy" };
        p.leave_out("compensation", why);
    }
}
