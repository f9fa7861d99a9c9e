//! The real-time renderer of paper §4 on Vulkan: per frame, the passes the scene needs —
//!
//! * mesh views: G-buffer → background → SH diffuse (when `ρ_d ≠ 0`) → one pass per lobe with
//!   non-zero albedo (`fis`, `plain`), or G-buffer → background → `mis` (the whole material);
//! * canvas views: the canvas pass alone.
//!
//! Each pass lives in its own file with `new / record / destroy`; this module decides which run,
//! owns each view's persistent targets and the per-environment and per-mesh GPU data (rebuilt only
//! when they change), and records into the frames of a ring (`vk::frame`), timing every pass with
//! timestamp queries. The editor records both views, the refinement's accumulation and the compose
//! pass into one frame and never reads it back; the headless [`Renderer::render`] records one view,
//! submits, waits and reads the image back.

pub mod accumulate;
pub mod background;
pub mod canvas;
pub mod compose;
pub mod diffuse;
pub mod environment;
pub mod eval;
pub mod gbuffer;
pub mod gpu;
pub mod lobe;
pub mod mesh;
pub mod mis;
pub mod targets;

use ash::vk;
use glam::DVec3;

use crate::brdf::Material;
use crate::error::{Error, Result};
use crate::reference::Image;
use crate::scene::{Camera, Environment, Mesh};
use crate::vk::descriptor::{self, Binding};
use crate::vk::frame::{Finished, FrameRing};
use crate::vk::pipeline::Pipeline;
use crate::vk::query::PassTime;
use crate::vk::{barrier, readback, Buffer, Context};

use environment::GpuEnvironment;
use gpu::Push;
use mesh::GpuMesh;
use targets::Targets;

/// How the specular part (or, for `mis`, the whole material) is estimated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    /// The paper's: Halton BRDF sampling of each lobe reading the prefiltered environment.
    Fis,
    /// The same samples reading level 0 only.
    Plain,
    /// Environment and BRDF sampling combined by the balance heuristic, diffuse included.
    Mis,
    /// Issue 10's default: the map's key lights split off; each lobe pass integrates the residual map
    /// (prefiltered, a Hammersley set shifted per frame, lod bias [`lobe::KEY_LOD_BIAS`]) and the lobe
    /// under the lights (light and BRDF samples, balance heuristic, or the lights' quadrature points
    /// for a lobe much wider than them); the diffuse pass takes the residual's SH9
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

/// The light samples the `key` estimator's lobe passes take per pixel for `spp` BRDF samples per
/// component.
pub fn key_light_samples(spp: u32) -> u32 {
    spp.max(1)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    Mesh,
    Canvas,
}

/// The most samples per pixel (per lobe for `fis`/`plain`, per pixel for `mis`) a frame takes. The
/// sample tables are uploaded whole (16 bytes a sample for the lobe passes, 32 for `mis`, rounded
/// up to a power of two) and `mis` records one dispatch per 32 samples: 65536 keeps the table at
/// 2 MiB and a frame at 2048 dispatches, 16× the 4096 spp at which `mis` is converged to 1 %
/// (README).
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
}

/// A rendered frame: the linear image (alpha = coverage) and the GPU time of every pass that ran.
pub struct Frame {
    pub image: Image,
    pub timings: Vec<PassTime>,
}

/// What a pass records with: the command buffer, this frame's descriptor pool, the shared push
/// constants, the targets and the environment.
pub struct Recording<'a> {
    pub ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
    pub pool: vk::DescriptorPool,
    pub push: Push,
    pub targets: &'a Targets,
    pub env: Option<&'a GpuEnvironment>,
}

impl Recording<'_> {
    pub fn env(&self) -> Result<&GpuEnvironment> {
        self.env.ok_or_else(|| Error::input("render", "a mesh view needs an environment map (--env)"))
    }

    /// A descriptor set of `pipeline`'s layout pointing at `bindings`.
    pub fn set(&self, pipeline: &Pipeline, bindings: &[Binding<'_>]) -> Result<vk::DescriptorSet> {
        let set = descriptor::allocate(self.ctx, self.pool, pipeline.set_layout)?;
        descriptor::write(self.ctx, set, bindings);
        Ok(set)
    }

    /// Dispatches 8×8 groups over the image, then orders the accumulation image's writes before the
    /// next pass's reads and writes.
    pub fn dispatch(&self, pipeline: &Pipeline, set: vk::DescriptorSet, push: &Push) {
        pipeline.bind(self.ctx, self.cmd, set, bytemuck::bytes_of(push));
        let (w, h) = (self.targets.width, self.targets.height);
        // SAFETY: `cmd` is recording with a compute pipeline bound.
        unsafe { self.ctx.raw().cmd_dispatch(self.cmd, w.div_ceil(8), h.div_ceil(8), 1) };
        crate::vk::barrier::memory(self.ctx, self.cmd, barrier::COMPUTE_WRITE, barrier::COMPUTE_READ_WRITE);
    }
}

struct Passes {
    gbuffer: gbuffer::GBufferPass,
    background: background::BackgroundPass,
    diffuse: diffuse::DiffusePass,
    lobe: lobe::LobePass,
    mis: mis::MisPass,
    canvas: canvas::CanvasPass,
    eval: eval::EvalPass,
    accumulate: accumulate::AccumulatePass,
    compose: compose::ComposePass,
}

impl Passes {
    fn new(ctx: &Context) -> Result<Passes> {
        Ok(Passes {
            gbuffer: gbuffer::GBufferPass::new(ctx)?,
            background: background::BackgroundPass::new(ctx)?,
            diffuse: diffuse::DiffusePass::new(ctx)?,
            lobe: lobe::LobePass::new(),
            mis: mis::MisPass::new(ctx)?,
            canvas: canvas::CanvasPass::new(ctx)?,
            eval: eval::EvalPass::new(ctx)?,
            accumulate: accumulate::AccumulatePass::new(ctx)?,
            compose: compose::ComposePass::new(ctx)?,
        })
    }

    fn destroy(self, ctx: &Context) {
        self.gbuffer.destroy(ctx);
        self.background.destroy(ctx);
        self.diffuse.destroy(ctx);
        self.lobe.destroy(ctx);
        self.mis.destroy(ctx);
        self.canvas.destroy(ctx);
        self.eval.destroy(ctx);
        self.accumulate.destroy(ctx);
        self.compose.destroy(ctx);
    }
}

/// Owns the context and every GPU object of the renderer; dropped passes first, context last.
pub struct Renderer {
    /// Run the lobe passes one sample at a time instead of four (the benchmark's baseline).
    pub scalar_lobes: bool,
    /// Skip the faces a closed mesh hides from an eye outside it (`Mesh::hidden_faces`); the image
    /// is the same either way (tests compare the two).
    pub cull_hidden_faces: bool,
    /// Let the `key` lobe passes of narrow lobes skip the key lights at pixels whose lobe cannot
    /// reach them (`lobe::reach_test_pays`); the image is the same either way (a test compares).
    pub light_reach_test: bool,
    /// The `key` estimator's frame seed: frames with different seeds rotate their sequences
    /// differently, so their mean converges (progressive refinement).
    pub seed: u32,
    passes: Option<Passes>,
    env: Option<GpuEnvironment>,
    mesh: Option<GpuMesh>,
    /// The persistent targets of each view (indexed by `View as usize`).
    views: [Option<Targets>; 2],
    /// `mis` samples summed in the mesh view's refinement, and in how many frames.
    refined: u32,
    refine_frames: u32,
    /// The headless path's readback buffer (sized to its last image).
    readback: Option<Buffer>,
    ring: Option<FrameRing>,
    halton: Option<(u32, Buffer)>,
    sequence: Option<(u32, Buffer)>,
    pub ctx: Context,
}

/// The camera's basis for `camera_ray` in `pass.glsl`.
fn camera_push(camera: &Camera, width: u32, height: u32, push: &mut Push) {
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    let t = (camera.fov_deg.to_radians() / 2.0).tan();
    let aspect = width as f64 / height as f64;
    push.eye = gpu::vec4(camera.eye, 1.0);
    push.right = gpu::vec4(right * t * aspect, 0.0);
    push.up = gpu::vec4(up * t, 0.0);
    push.forward = gpu::vec4(forward, 0.0);
}

impl Renderer {
    pub fn new(ctx: Context) -> Result<Renderer> {
        let passes = Passes::new(&ctx)?;
        let ring = match FrameRing::new(&ctx) {
            Ok(r) => r,
            Err(e) => {
                passes.destroy(&ctx);
                return Err(e);
            }
        };
        Ok(Renderer {
            scalar_lobes: false,
            cull_hidden_faces: true,
            light_reach_test: true,
            seed: 0,
            passes: Some(passes),
            env: None,
            mesh: None,
            views: [None, None],
            refined: 0,
            refine_frames: 0,
            readback: None,
            ring: Some(ring),
            halton: None,
            sequence: None,
            ctx,
        })
    }

    pub fn device_name(&self) -> &str {
        &self.ctx.device.name
    }

    /// Uploads the environment (mips, SH, sampling tables) unless it is the one already there.
    pub fn set_environment(&mut self, env: &Environment) -> Result<()> {
        if self.env.as_ref().is_some_and(|e| e.key == environment::key(env)) {
            return Ok(());
        }
        let limit = self.ctx.device.limits.max_image_dimension2_d as usize;
        if env.width > limit || env.height > limit {
            return Err(Error::input(
                env.origin.clone(),
                format!("{}x{} exceeds the device's largest image ({limit})", env.width, env.height),
            ));
        }
        self.idle()?;
        if let Some(old) = self.env.take() {
            old.destroy(&self.ctx);
        }
        self.env = Some(GpuEnvironment::new(&self.ctx, env)?);
        Ok(())
    }

    /// Uploads the mesh unless it is the one already there.
    pub fn set_mesh(&mut self, mesh: &Mesh) -> Result<()> {
        if self.mesh.as_ref().is_some_and(|m| m.key == mesh::key(mesh)) {
            return Ok(());
        }
        self.idle()?;
        if let Some(old) = self.mesh.take() {
            old.destroy(&self.ctx);
        }
        self.mesh = Some(GpuMesh::new(&self.ctx, mesh)?);
        Ok(())
    }

    /// The key lights found in the current environment (what the `key` estimator splits off).
    pub fn key_lights(&self) -> Option<&environment::KeyLightSummary> {
        self.env.as_ref().map(|e| &e.key_summary)
    }

    /// Whether the environment texture is filtered linearly (false only on devices without linear
    /// filtering of `RGBA32F`).
    pub fn linear_filtering(&self) -> bool {
        self.env.as_ref().is_none_or(|e| e.linear)
    }

    fn check_size(&self, s: &Settings) -> Result<()> {
        let limit = self.ctx.device.limits.max_image_dimension2_d;
        check_limits(s.width, s.height, s.spp)?;
        if s.width > limit || s.height > limit {
            return Err(Error::input(
                "--size",
                format!("{}x{} exceeds the device's largest image ({limit}x{limit})", s.width, s.height),
            ));
        }
        Ok(())
    }

    /// The sample tables for `spp` samples per lobe, or `mis`'s sequence up to sample `end`
    /// (replaced only after the frames in flight that read them).
    fn buffers_for(&mut self, end: u32, spp: u32, estimator: Estimator) -> Result<()> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        if estimator == Estimator::Mis {
            let len = end.next_power_of_two();
            if self.sequence.as_ref().is_none_or(|s| s.0 < len) {
                self.idle()?;
                if let Some((_, b)) = self.sequence.take() {
                    b.destroy(&self.ctx);
                }
                let seq = gpu::mis_sequence(len);
                self.sequence =
                    Some((len, Buffer::upload(&self.ctx, bytemuck::cast_slice(&seq), usage, "mis.sequence")?));
            }
        }
        // The lobe passes bind the table (the `key` variant computes its points and ignores it).
        if estimator != Estimator::Mis && self.halton.as_ref().is_none_or(|s| s.0 != spp) {
            self.idle()?;
            if let Some((_, b)) = self.halton.take() {
                b.destroy(&self.ctx);
            }
            let groups = gpu::halton_groups(spp);
            self.halton = Some((spp, Buffer::upload(&self.ctx, bytemuck::cast_slice(&groups), usage, "halton")?));
        }
        Ok(())
    }

    /// `f(ω_i, ω_o)` in `f32` on the GPU for each pair (local frame), checked for validation errors.
    pub fn eval(&self, material: &Material, pairs: &[(DVec3, DVec3)]) -> Result<Vec<[f32; 3]>> {
        let out = self.passes.as_ref().expect("passes live until drop").eval.run(&self.ctx, material, pairs)?;
        self.ctx.check_validation()?;
        Ok(out)
    }

    /// Renders one frame of `material` as `settings` say and reads it back: the headless path, on
    /// the same frame ring as the editor's frames, waiting for its one frame.
    pub fn render(&mut self, material: &Material, settings: &Settings) -> Result<Frame> {
        self.check_size(settings)?;
        self.begin_frame(material)?;
        let recorded = self.record_view(material, settings, Progress::Fresh, false).and_then(|()| {
            let (w, h) = (settings.width, settings.height);
            if self.readback.as_ref().is_none_or(|b| b.size != w as u64 * h as u64 * 16) {
                self.idle()?;
                if let Some(b) = self.readback.take() {
                    b.destroy(&self.ctx);
                }
                let targets = self.views[settings.view as usize].as_ref().expect("made by record");
                self.readback = Some(readback::buffer_for(&self.ctx, &targets.accum)?);
            }
            let targets = self.views[settings.view as usize].as_ref().expect("made by record");
            let cmd = self.ring.as_ref().expect("ring lives until drop").current_ref().cmd;
            let buffer = self.readback.as_ref().expect("made above");
            readback::record(&self.ctx, cmd, &targets.accum, vk::ImageLayout::GENERAL, buffer);
            Ok(())
        });
        if let Err(e) = recorded {
            let _ = self.ring.as_mut().expect("ring lives until drop").abandon(&self.ctx);
            return Err(e);
        }
        self.submit_frame(None, None)?;
        let timings = self.ring.as_mut().expect("ring lives until drop").wait(&self.ctx)?;
        let pixels = readback::pixels(self.readback.as_ref().expect("made above"));
        self.ctx.check_validation()?;
        Ok(Frame { image: Image { width: settings.width, height: settings.height, pixels }, timings })
    }

    /// Reads the mesh view back as it is shown: the refinement's mean when refining, else its last
    /// frame (waits for the frames in flight; one frame of its own).
    pub fn read_mesh_view(&mut self) -> Result<Image> {
        let Some(t) = self.views[View::Mesh as usize].as_ref() else {
            return Err(Error::Validation("no mesh view was rendered".into()));
        };
        let (w, h) = (t.width, t.height);
        self.idle()?;
        if self.readback.as_ref().is_none_or(|b| b.size != w as u64 * h as u64 * 16) {
            if let Some(b) = self.readback.take() {
                b.destroy(&self.ctx);
            }
            let t = self.views[View::Mesh as usize].as_ref().expect("checked above");
            self.readback = Some(readback::buffer_for(&self.ctx, &t.accum)?);
        }
        let ring = self.ring.as_mut().expect("ring lives until drop");
        ring.begin(&self.ctx, 1, 1)?;
        let t = self.views[View::Mesh as usize].as_ref().expect("checked above");
        let image = if self.refined > 0 { &t.sum } else { &t.accum };
        readback::record(
            &self.ctx,
            ring.current_ref().cmd,
            image,
            vk::ImageLayout::GENERAL,
            self.readback.as_ref().expect("made above"),
        );
        ring.submit(&self.ctx, None, None)?;
        ring.wait(&self.ctx)?;
        let n = if self.refined > 0 { self.refine_frames.max(1) as f32 } else { 1.0 };
        let pixels = readback::pixels(self.readback.as_ref().expect("made above"))
            .into_iter()
            .map(|p| p.map(|v| v / n))
            .collect();
        self.ctx.check_validation()?;
        Ok(Image { width: w, height: h, pixels })
    }

    /// Waits for every frame in flight (before objects they use are replaced).
    fn idle(&mut self) -> Result<()> {
        if let Some(r) = self.ring.as_mut() {
            r.wait_all(&self.ctx)?;
        }
        Ok(())
    }

    /// Starts a frame on the ring (waiting only for the frame that last used its slot) and writes
    /// `material` into the frame's buffer. That earlier frame's GPU times join the finished ones
    /// ([`Renderer::take_finished`]).
    pub fn begin_frame(&mut self, material: &Material) -> Result<()> {
        let n = material.lobes.len() as u32;
        let ring = self.ring.as_mut().expect("ring lives until drop");
        ring.begin(&self.ctx, 8 + n, 8 + n)?;
        if let Err(e) = ring.current().upload(&self.ctx, "material", &gpu::material_bytes(material)) {
            let _ = ring.abandon(&self.ctx);
            return Err(e);
        }
        Ok(())
    }

    /// Submits the frame begun by [`Renderer::begin_frame`] (waiting on `wait` at its stage,
    /// signalling `signal`); returns without waiting for the GPU.
    pub fn submit_frame(
        &mut self,
        wait: Option<(vk::Semaphore, vk::PipelineStageFlags)>,
        signal: Option<vk::Semaphore>,
    ) -> Result<()> {
        self.ring.as_mut().expect("ring lives until drop").submit(&self.ctx, wait, signal)
    }

    /// Ends the frame begun by [`Renderer::begin_frame`] without running it.
    pub fn abandon_frame(&mut self) -> Result<()> {
        self.ring.as_mut().expect("ring lives until drop").abandon(&self.ctx)
    }

    /// Ends the frame being recorded without running it after a swapchain acquire signalled
    /// `acquired` (see [`crate::vk::frame::FrameRing::abandon_acquired`]).
    pub fn abandon_acquired_frame(&mut self, acquired: vk::Semaphore) -> Result<()> {
        self.ring.as_mut().expect("ring lives until drop").abandon_acquired(&self.ctx, acquired)
    }

    /// Waits for the frames in flight (their GPU times join the finished ones).
    pub fn finish_frames(&mut self) -> Result<()> {
        self.ring.as_mut().expect("ring lives until drop").wait_all(&self.ctx)
    }

    /// The GPU times of every frame finished since the last call, oldest first (frames are settled
    /// whenever their slot is reused or the renderer waits for the frames in flight).
    pub fn take_finished(&mut self) -> Vec<Finished> {
        self.ring.as_mut().expect("ring lives until drop").take_finished()
    }

    /// The command buffer and the acquire semaphore of the frame being recorded, for the caller's
    /// own commands (the window's copy and the tool panel).
    pub fn frame_commands(&self) -> (vk::CommandBuffer, vk::Semaphore) {
        let f = self.ring.as_ref().expect("ring lives until drop").current_ref();
        (f.cmd, f.acquired)
    }

    /// The number of the frame being recorded.
    pub fn frame_number(&self) -> u64 {
        self.ring.as_ref().expect("ring lives until drop").number()
    }

    /// Samples of `mis` summed in the mesh view's refinement (0: the view shows its last frame).
    pub fn refined_samples(&self) -> u32 {
        self.refined
    }

    /// Records, into the current frame, the composed window image `window`: the mesh view (the
    /// refinement's mean when refining, else its last frame) and the canvas placed as `placement`
    /// says (its `mesh_scale` is multiplied by 1 / frames here).
    pub fn record_compose(&mut self, window: &crate::vk::Image, placement: &compose::Placement) -> Result<()> {
        let (Some(mesh), Some(canvas)) =
            (self.views[View::Mesh as usize].as_ref(), self.views[View::Canvas as usize].as_ref())
        else {
            return Err(Error::Validation("compose before both views were rendered".into()));
        };
        let (image, frames) = if self.refined > 0 { (&mesh.sum, self.refine_frames) } else { (&mesh.accum, 1) };
        let p = compose::Placement { mesh_scale: placement.mesh_scale / frames.max(1) as f32, ..*placement };
        let passes = self.passes.as_ref().expect("passes live until drop");
        let ring = self.ring.as_mut().expect("ring lives until drop");
        let f = ring.current();
        let (cmd, pool) = (f.cmd, f.pool);
        f.timestamps.time(&self.ctx, cmd, "compose", || {
            passes.compose.record(&self.ctx, cmd, pool, window, (image, &canvas.accum), &p)
        })
    }

    /// Records one view of `material` into the current frame (begun by [`Renderer::begin_frame`]),
    /// into that view's persistent targets. `Progress::Refine` adds `settings.spp` more `mis` samples
    /// to the mesh view's running sum (continuing its sequence); `Fresh` restarts it.
    pub fn record(&mut self, material: &Material, settings: &Settings, progress: Progress) -> Result<()> {
        self.record_view(material, settings, progress, true)
    }

    /// [`Renderer::record`]; with `reuse`, a mesh view whose mesh, camera and size are unchanged keeps
    /// its G-buffer (the headless `render` always rasterises: a frame of its own, timed whole).
    fn record_view(&mut self, material: &Material, settings: &Settings, progress: Progress, reuse: bool) -> Result<()> {
        self.check_size(settings)?;
        let refine = matches!(progress, Progress::Refine) && settings.view == View::Mesh;
        if refine && settings.estimator != Estimator::Mis {
            return Err(Error::Validation("refinement frames are mis frames".into()));
        }
        let offset = if refine { self.refined } else { 0 };
        if refine && offset.saturating_add(settings.spp) > MAX_SPP {
            return Err(Error::input(
                "--spp",
                format!("{} samples after {offset} is more than the limit of {MAX_SPP}", settings.spp),
            ));
        }
        let (w, h) = (settings.width, settings.height);
        let mesh_view = settings.view == View::Mesh;
        if mesh_view && (self.env.is_none() || self.mesh.is_none()) {
            return Err(Error::input("render", "a mesh view needs an environment and a mesh"));
        }
        let slot = settings.view as usize;
        if self.views[slot].as_ref().is_none_or(|t| (t.width, t.height) != (w, h)) {
            self.idle()?;
            if let Some(old) = self.views[slot].take() {
                old.destroy(&self.ctx);
            }
            self.views[slot] = Some(Targets::new(&self.ctx, w, h)?);
            if mesh_view {
                self.refined = 0;
            }
        }
        // Which lobes get a pass: non-zero albedo only.
        let prefilter = matches!(settings.estimator, Estimator::Fis | Estimator::Key);
        let key = settings.estimator == Estimator::Key;
        let key_lights = self.env.as_ref().and_then(|e| e.keys.as_ref()).filter(|_| key);
        let lights = key_lights.is_some();
        let lobes: Vec<(u32, lobe::Variant)> = material
            .lobes
            .iter()
            .enumerate()
            .filter(|(_, l)| l.albedo.iter().any(|&a| a != 0.0))
            .map(|(i, l)| {
                let points = key_lights
                    .is_some_and(|k| crate::scene::keylight::quadrature_fits(&k.lights, l.alpha_x, l.alpha_y));
                (
                    i as u32,
                    lobe::Variant {
                        vec4: !self.scalar_lobes,
                        key,
                        lights,
                        points,
                        reach: self.light_reach_test && lights && !points && lobe::reach_test_pays(material, l),
                        ..lobe::Variant::of(material, l, prefilter)
                    },
                )
            })
            .collect();
        if mesh_view {
            self.buffers_for(offset.saturating_add(settings.spp), settings.spp, settings.estimator)?;
            if settings.estimator != Estimator::Mis {
                let variants: Vec<_> = lobes.iter().map(|l| l.1).collect();
                self.passes.as_mut().expect("passes live until drop").lobe.prepare(&self.ctx, &variants)?;
            }
        }
        let ctx = &self.ctx;
        let ring = self.ring.as_mut().expect("ring lives until drop");
        let mut light_counts = None;
        let sampled = lobes.iter().any(|l| l.1.lights && !l.1.points);
        if let (true, true, Some(keys)) = (mesh_view, sampled, self.env.as_ref().and_then(|e| e.keys.as_ref())) {
            let m = key_light_samples(settings.spp);
            let samples = keys.frame_samples(m, self.seed);
            ring.current().upload(ctx, "keylights.frame", bytemuck::cast_slice(&samples))?;
            light_counts = Some((samples.len() as u32, [m as f32, keys.sampling.dark_samples(m) as f32]));
        }
        let frame = ring.current();
        let (cmd, pool) = (frame.cmd, frame.pool);
        let (ts, buffers) = frame.parts();
        let material_buf = buffers.get("material").expect("written by begin_frame");
        let light_samples = light_counts.map(|(n, c)| (buffers.get("keylights.frame").expect("written above"), n, c));
        let key_lights = self.env.as_ref().and_then(|e| e.keys.as_ref()).filter(|_| key);
        let light_points = key_lights.map(|k| (&k.points, 4 * k.count, [0.0; 2]));
        let passes = self.passes.as_ref().expect("passes live until drop");
        // Culling is exact only for an eye outside the mesh's bounding sphere (radius 1) by more than
        // the farthest point of the frustum in front of the near plane.
        let (tx, ty) = settings.camera.half_extents(w, h);
        let near_reach = crate::scene::camera::NEAR * (1.0 + tx * tx + ty * ty).sqrt();
        let cull = self.cull_hidden_faces && settings.camera.eye.length() > 1.0 + near_reach;
        let gbuffer_key = mesh_view.then(|| {
            let mesh = self.mesh.as_ref().expect("checked above");
            (mesh.key.clone(), settings.camera.clone(), cull)
        });
        let targets = self.views[slot].as_mut().expect("made above");
        let raster = !reuse || targets.gbuffer_of != gbuffer_key;
        if raster {
            // Set again once the whole view is recorded (an error leaves nothing to reuse).
            targets.gbuffer_of = None;
        }
        let targets = self.views[slot].as_ref().expect("made above");
        let mut push = Push::default();
        camera_push(&settings.camera, w, h, &mut push);
        let (ew, eh) = self.env.as_ref().map_or((1, 1), |e| (e.width, e.height));
        push.size = [w, h, ew, eh];
        push.light = gpu::vec4(settings.light, settings.intensity as f32);
        let rec = Recording { ctx, cmd, pool, push, targets, env: self.env.as_ref() };
        if !mesh_view {
            return ts.time(ctx, cmd, "canvas", || passes.canvas.record(&rec, material_buf));
        }
        let mesh = self.mesh.as_ref().expect("checked above");
        let vp = settings.camera.view_proj(w, h);
        if raster {
            ts.time(ctx, cmd, "gbuffer", || {
                passes.gbuffer.record(ctx, cmd, targets, mesh, &vp, cull);
                Ok(())
            })?;
        }
        ts.time(ctx, cmd, "background", || passes.background.record(&rec))?;
        match settings.estimator {
            Estimator::Mis => {
                let seq = &self.sequence.as_ref().expect("made above").1;
                ts.time(ctx, cmd, "mis", || passes.mis.record(&rec, offset, settings.spp, material_buf, seq))?;
            }
            Estimator::Fis | Estimator::Plain | Estimator::Key => {
                if material.diffuse.iter().any(|&d| d != 0.0) {
                    ts.time(ctx, cmd, "diffuse", || passes.diffuse.record(&rec, material.diffuse, key))?;
                }
                let halton = &self.halton.as_ref().expect("made above").1;
                for &(i, v) in &lobes {
                    let name = format!("lobe{i}[{}]", v.tag());
                    ts.time(ctx, cmd, &name, || {
                        let job = lobe::Job {
                            index: i,
                            samples: settings.spp,
                            seed: self.seed,
                            material: material_buf,
                            halton,
                            light_samples: if v.points { light_points } else { light_samples },
                        };
                        passes.lobe.record(&rec, v, &job)
                    })?;
                }
            }
        }
        if refine {
            ts.time(ctx, cmd, "accumulate", || passes.accumulate.record(ctx, cmd, pool, targets, offset == 0))?;
            self.refined = offset + settings.spp;
            self.refine_frames = if offset == 0 { 1 } else { self.refine_frames + 1 };
        } else {
            self.refined = 0;
        }
        self.views[slot].as_mut().expect("made above").gbuffer_of = gbuffer_key;
        Ok(())
    }
}

/// How a mesh view frame relates to the ones before it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// A new image (the refinement restarts).
    Fresh,
    /// More `mis` samples added to the running sum.
    Refine,
}

impl Drop for Renderer {
    fn drop(&mut self) {
        if let Some(r) = self.ring.take() {
            r.destroy(&self.ctx);
        }
        // SAFETY: nothing else submits work; everything below is destroyed once.
        let _ = unsafe { self.ctx.raw().device_wait_idle() };
        if let Some(p) = self.passes.take() {
            p.destroy(&self.ctx);
        }
        if let Some(e) = self.env.take() {
            e.destroy(&self.ctx);
        }
        if let Some(m) = self.mesh.take() {
            m.destroy(&self.ctx);
        }
        for t in self.views.iter_mut().filter_map(Option::take) {
            t.destroy(&self.ctx);
        }
        if let Some(b) = self.readback.take() {
            b.destroy(&self.ctx);
        }
        for b in [self.halton.take(), self.sequence.take()].into_iter().flatten() {
            b.1.destroy(&self.ctx);
        }
    }
}
