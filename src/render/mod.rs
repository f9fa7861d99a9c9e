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
pub mod compact;
pub mod compensation;
pub mod compose;
pub mod denoise;
pub mod diffuse;
pub mod environment;
pub mod eval;
pub mod gbuffer;
pub mod gpu;
pub mod lobe;
pub mod mesh;
pub mod mis;
pub mod peak;
pub mod plan;
mod record;
mod settings;
pub mod targets;
pub mod zero;

use ash::vk;
use glam::DVec3;

use crate::brdf::Material;
use crate::error::{Error, Result};
use crate::reference::Image;
use crate::scene::{Environment, Mesh};
use crate::vk::frame::{Finished, FrameRing};
use crate::vk::{readback, Buffer, Context};

use environment::GpuEnvironment;
use mesh::GpuMesh;
use targets::Targets;

pub use record::Recording;
pub use settings::{
    check_limits, key_light_samples, Estimator, Frame, Progress, Recorded, Settings, View, MAX_PIXELS, MAX_SPP,
};

pub(crate) struct Passes {
    gbuffer: gbuffer::GBufferPass,
    background: background::BackgroundPass,
    compact: compact::CompactPass,
    diffuse: diffuse::DiffusePass,
    denoise: denoise::DenoisePass,
    lobe: lobe::LobePass,
    mis: mis::MisPass,
    compensation: compensation::CompensationPass,
    canvas: canvas::CanvasPass,
    eval: eval::EvalPass,
    accumulate: accumulate::AccumulatePass,
    compose: compose::ComposePass,
    zero: zero::ZeroPass,
}

impl Passes {
    fn new(ctx: &Context) -> Result<Passes> {
        Ok(Passes {
            gbuffer: gbuffer::GBufferPass::new(ctx)?,
            background: background::BackgroundPass::new(ctx)?,
            compact: compact::CompactPass::new(ctx)?,
            diffuse: diffuse::DiffusePass::new(ctx)?,
            denoise: denoise::DenoisePass::new(ctx)?,
            lobe: lobe::LobePass::new(),
            mis: mis::MisPass::new(ctx)?,
            compensation: compensation::CompensationPass::new(ctx)?,
            canvas: canvas::CanvasPass::new(ctx)?,
            eval: eval::EvalPass::new(ctx)?,
            accumulate: accumulate::AccumulatePass::new(ctx)?,
            compose: compose::ComposePass::new(ctx)?,
            zero: zero::ZeroPass::new(ctx)?,
        })
    }

    fn destroy(self, ctx: &Context) {
        self.gbuffer.destroy(ctx);
        self.background.destroy(ctx);
        self.compact.destroy(ctx);
        self.diffuse.destroy(ctx);
        self.denoise.destroy(ctx);
        self.lobe.destroy(ctx);
        self.mis.destroy(ctx);
        self.compensation.destroy(ctx);
        self.canvas.destroy(ctx);
        self.eval.destroy(ctx);
        self.accumulate.destroy(ctx);
        self.compose.destroy(ctx);
        self.zero.destroy(ctx);
    }
}

/// Owns the context and every GPU object of the renderer; dropped passes first, context last.
pub struct Renderer {
    /// Time each pass of a frame (`Frame::timings`, `--timings`, `bench`, the editor's panel) besides
    /// the whole frame; false times the whole frame alone (`Frame::timings` empty), as the
    /// error-vs-time sweep does: two timestamps a frame instead of two a pass (each a wait for the
    /// queue on lavapipe, `vk::query`).
    pub time_passes: bool,
    /// The choices a user may compare (`plan::Options`); the defaults are the measured better ones.
    pub options: plan::Options,
    /// Build new lobe pipelines on threads of their own, calling this when one is ready (the
    /// editor); `None` builds them at once (headless commands).
    pub build_in_background: Option<lobe::Notify>,
    /// How frames start and zero their images on this device (`plan::DevicePlan::from_env`); a test
    /// forces the GPU plan on lavapipe and compares the images.
    pub device_plan: plan::DevicePlan,
    /// The `key` estimator's frame seed: frames with different seeds rotate their sequences
    /// differently, so their mean converges (progressive refinement).
    pub seed: u32,
    passes: Option<Passes>,
    env: Option<GpuEnvironment>,
    mesh: Option<GpuMesh>,
    /// The persistent targets of each view (indexed by `View as usize`), and each view's spare
    /// targets of the sizes it had before, most recent first (`record::targets_for`).
    views: [Option<Targets>; 2],
    spare: [Vec<Targets>; 2],
    /// `mis` samples summed in the mesh view's refinement.
    refined: u32,
    /// The headless path's readback buffer (sized to its last image).
    readback: Option<Buffer>,
    ring: Option<FrameRing>,
    halton: Option<(u32, Buffer)>,
    sequence: Option<(u32, Buffer)>,
    /// What the frames' buffers hold for the material's compensation terms.
    tables: compensation::Tables,
    pub ctx: Context,
}

impl Renderer {
    pub fn new(ctx: Context) -> Result<Renderer> {
        let range = ctx.device.limits.max_uniform_buffer_range as usize;
        for (what, needs) in
            [("the material", gpu::MATERIAL_UNIFORM_BYTES), ("the key lights' points", gpu::LIGHT_SET_UNIFORM_BYTES)]
        {
            if range < needs {
                return Err(Error::NoDevice(format!(
                    "{}: uniform buffers of {range} bytes; {what} needs {needs}",
                    ctx.device.name
                )));
            }
        }
        let passes = Passes::new(&ctx)?;
        let ring = match FrameRing::new(&ctx) {
            Ok(r) => r,
            Err(e) => {
                passes.destroy(&ctx);
                return Err(e);
            }
        };
        Ok(Renderer {
            time_passes: true,
            options: plan::Options::default(),
            seed: 0,
            device_plan: plan::DevicePlan::from_env(ctx.device.kind),
            build_in_background: None,
            passes: Some(passes),
            env: None,
            mesh: None,
            views: [None, None],
            spare: [Vec::new(), Vec::new()],
            refined: 0,
            readback: None,
            ring: Some(ring),
            halton: None,
            sequence: None,
            tables: compensation::Tables::default(),
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
        // A headless frame bakes its tables and builds its pipelines at once (it has no later frame
        // to wait for).
        let background = self.build_in_background.take();
        if let Err(e) = self.begin_frame(material) {
            self.build_in_background = background;
            return Err(e);
        }
        let before = self.ctx.counts.now();
        let recorded = self.record_view(material, settings, Progress::Fresh, false);
        let commands = self.ctx.counts.now().since(before);
        self.build_in_background = background;
        let recorded = recorded.and_then(|_| {
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
            let frame = self.ring.as_mut().expect("ring lives until drop").current();
            let cmd = frame.cmd;
            // The frame's time ends with its passes: the readback copy is the tool's, not the frame's.
            frame.timestamps.end_frame(&self.ctx, cmd);
            let buffer = self.readback.as_ref().expect("made above");
            readback::record(&self.ctx, cmd, &targets.accum, vk::ImageLayout::GENERAL, buffer);
            Ok(())
        });
        if let Err(e) = recorded {
            let _ = self.ring.as_mut().expect("ring lives until drop").abandon(&self.ctx);
            return Err(e);
        }
        self.submit_frame(None, None)?;
        let times = self.ring.as_mut().expect("ring lives until drop").wait(&self.ctx)?;
        let pixels = readback::pixels(self.readback.as_ref().expect("made above"));
        self.ctx.check_validation()?;
        let image = Image { width: settings.width, height: settings.height, pixels };
        Ok(Frame { image, timings: times.passes, frame_ms: times.frame_ms, commands })
    }

    /// Reads the mesh view back as it is shown: the refinement's mean when refining, else its last
    /// frame (waits for the frames in flight; one frame of its own).
    pub fn read_mesh_view(&mut self) -> Result<Image> {
        let Some(t) = self.views[View::Mesh as usize].as_ref() else {
            return Err(Error::Bug("no mesh view was rendered".into()));
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
        ring.begin(&self.ctx, 1, 1, self.time_passes)?;
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
        let n = if self.refined > 0 { self.refined as f32 } else { 1.0 };
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
    /// `material` into the frame's buffers, with its compensation tables: baked now, or with
    /// [`Renderer::build_in_background`] on a thread of their own (a lobe whose table is not there
    /// yet draws without its term; [`Renderer::tables_complete`] says). That earlier frame's GPU
    /// times join the finished ones ([`Renderer::take_finished`]).
    pub fn begin_frame(&mut self, material: &Material) -> Result<()> {
        let n = material.lobes.len() as u32;
        let (words, kernels) = self.tables.update(material, self.build_in_background.as_ref());
        let ring = self.ring.as_mut().expect("ring lives until drop");
        // Passes: G-buffer, background, diffuse, a pass per lobe, denoise, compensation, canvas,
        // compose, and the caller's window copy and panel (refinement frames have fewer).
        ring.begin(&self.ctx, 9 + n, 11 + n, self.time_passes)?;
        let frame = ring.current();
        let uploaded = frame
            .upload(&self.ctx, "material", &gpu::material_bytes(material))
            .and_then(|()| frame.upload(&self.ctx, "tables", words))
            .and_then(|()| frame.upload(&self.ctx, "kernels", kernels));
        if let Err(e) = uploaded {
            let _ = ring.abandon(&self.ctx);
            return Err(e);
        }
        Ok(())
    }

    /// Whether the frame begun last had every compensation table of its material (a lobe's table
    /// is baked on a thread of its own with [`Renderer::build_in_background`]).
    pub fn tables_complete(&self) -> bool {
        self.tables.complete()
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

    /// Ends the frame begun by [`Renderer::begin_frame`] without running it. What its recording
    /// marked as kept (the G-buffer, `Targets::base`) was never drawn, so nothing is kept.
    pub fn abandon_frame(&mut self) -> Result<()> {
        self.forget_kept();
        self.ring.as_mut().expect("ring lives until drop").abandon(&self.ctx)
    }

    fn forget_kept(&mut self) {
        for t in self.views.iter_mut().flatten() {
            t.gbuffer_of = None;
            t.base_of = None;
        }
    }

    /// Ends the frame being recorded without running it after a swapchain acquire signalled
    /// `acquired` (see [`crate::vk::frame::FrameRing::abandon_acquired`]).
    pub fn abandon_acquired_frame(&mut self, acquired: vk::Semaphore) -> Result<()> {
        self.forget_kept();
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

    /// Records the caller's own commands into the frame being recorded (the window's copy, the tool
    /// panel), timed as a pass named `name`.
    pub fn time<T>(&mut self, name: &str, f: impl FnOnce(&Context, vk::CommandBuffer) -> Result<T>) -> Result<T> {
        let ring = self.ring.as_mut().expect("ring lives until drop");
        let frame = ring.current();
        let cmd = frame.cmd;
        frame.timestamps.time(&self.ctx, cmd, name, || f(&self.ctx, cmd))
    }

    /// The number of the frame being recorded.
    pub fn frame_number(&self) -> u64 {
        self.ring.as_ref().expect("ring lives until drop").number()
    }

    /// Samples of `mis` summed in the mesh view's refinement (0: the view shows its last frame).
    pub fn refined_samples(&self) -> u32 {
        self.refined
    }
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
        for t in self.spare.iter_mut().flat_map(std::mem::take) {
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
