//! The real-time renderer of paper §4 on Vulkan: per frame, the passes the scene needs —
//!
//! * mesh views: G-buffer → background → SH diffuse (when `ρ_d ≠ 0`) → one pass per lobe with
//!   non-zero albedo (`fis`, `plain`), or G-buffer → background → `mis` (the whole material);
//! * canvas views: the canvas pass alone.
//!
//! Each pass lives in its own file with `new / record / destroy`; this module decides which run,
//! owns the per-size targets and the per-environment and per-mesh GPU data (rebuilt only when they
//! change), times every pass with timestamp queries, and reads the image back.

pub mod background;
pub mod canvas;
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
use crate::vk::pipeline::Pipeline;
use crate::vk::query::{PassTime, Timestamps};
use crate::vk::{readback, vk_err, Buffer, Context};

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
    /// (prefiltered, rotated Halton points, lod bias [`lobe::KEY_LOD_BIAS`]) and the lobe under the
    /// lights (light and BRDF samples, balance heuristic); the diffuse pass takes the residual's SH9
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

/// The most pixels a GPU frame has: 8192×4096 (twice 8K UHD). Every pixel costs 48 bytes of render
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
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE)];
        let dep = vk::DependencyInfo::default().memory_barriers(&b);
        // SAFETY: `cmd` is recording.
        unsafe { self.ctx.raw().cmd_pipeline_barrier2(self.cmd, &dep) };
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
    }
}

/// Owns the context and every GPU object of the renderer; dropped passes first, context last.
pub struct Renderer {
    /// Run the lobe passes one sample at a time instead of four (the benchmark's baseline).
    pub scalar_lobes: bool,
    /// Where in its sequence the `mis` estimator starts: successive frames with offsets 0, N, 2N …
    /// are independent parts of one long estimate (the editor's progressive refinement).
    pub mis_offset: u32,
    /// The `key` estimator's frame seed: frames with different seeds rotate their sequences
    /// differently, so their mean converges (progressive refinement).
    pub seed: u32,
    passes: Option<Passes>,
    env: Option<GpuEnvironment>,
    mesh: Option<GpuMesh>,
    targets: Option<Targets>,
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
        Ok(Renderer {
            scalar_lobes: false,
            mis_offset: 0,
            seed: 0,
            passes: Some(passes),
            env: None,
            mesh: None,
            targets: None,
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
        // The editor's refinement adds frames of samples; their sum stays within the table's limit.
        if self.mis_offset.saturating_add(s.spp) > MAX_SPP {
            return Err(Error::input(
                "--spp",
                format!("{} samples after {} is more than the limit of {MAX_SPP}", s.spp, self.mis_offset),
            ));
        }
        Ok(())
    }

    fn buffers_for(&mut self, spp: u32, estimator: Estimator) -> Result<()> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        if estimator == Estimator::Mis {
            let spp = self.mis_offset.saturating_add(spp).next_power_of_two();
            if self.sequence.as_ref().is_none_or(|s| s.0 < spp) {
                if let Some((_, b)) = self.sequence.take() {
                    b.destroy(&self.ctx);
                }
                let seq = gpu::mis_sequence(spp);
                self.sequence =
                    Some((spp, Buffer::upload(&self.ctx, bytemuck::cast_slice(&seq), usage, "mis.sequence")?));
            }
        }
        // The lobe passes bind the table (the `key` variant computes its points and ignores it).
        if estimator != Estimator::Mis && self.halton.as_ref().is_none_or(|s| s.0 != spp) {
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

    /// Renders one frame of `material` as `settings` say.
    pub fn render(&mut self, material: &Material, settings: &Settings) -> Result<Frame> {
        self.check_size(settings)?;
        let (w, h) = (settings.width, settings.height);
        let mesh_view = settings.view == View::Mesh;
        if mesh_view && (self.env.is_none() || self.mesh.is_none()) {
            return Err(Error::input("render", "a mesh view needs an environment and a mesh"));
        }
        if self.targets.as_ref().is_none_or(|t| (t.width, t.height) != (w, h)) {
            if let Some(old) = self.targets.take() {
                old.destroy(&self.ctx);
            }
            self.targets = Some(Targets::new(&self.ctx, w, h)?);
        }
        // Which lobes get a pass: non-zero albedo only.
        let prefilter = matches!(settings.estimator, Estimator::Fis | Estimator::Key);
        let key = settings.estimator == Estimator::Key;
        let lights = key && self.env.as_ref().is_some_and(|e| e.keys.is_some());
        let lobes: Vec<(u32, lobe::Variant)> = material
            .lobes
            .iter()
            .enumerate()
            .filter(|(_, l)| l.albedo.iter().any(|&a| a != 0.0))
            .map(|(i, l)| {
                (
                    i as u32,
                    lobe::Variant {
                        vec4: !self.scalar_lobes,
                        key,
                        lights,
                        ..lobe::Variant::of(material, l, prefilter)
                    },
                )
            })
            .collect();
        if mesh_view {
            self.buffers_for(settings.spp, settings.estimator)?;
            if settings.estimator != Estimator::Mis {
                let variants: Vec<_> = lobes.iter().map(|l| l.1).collect();
                self.passes.as_mut().expect("passes live until drop").lobe.prepare(&self.ctx, &variants)?;
            }
        }

        let ctx = &self.ctx;
        let material_buf =
            Buffer::upload(ctx, &gpu::material_bytes(material), vk::BufferUsageFlags::STORAGE_BUFFER, "material")?;
        let mut frame_objects =
            FrameObjects { material: Some(material_buf), lights: None, readback: None, pool: None, timestamps: None };
        let result = (|| -> Result<Frame> {
            let targets = self.targets.as_ref().expect("made above");
            frame_objects.readback = Some(readback::buffer_for(ctx, &targets.accum)?);
            if let (true, Some(keys)) = (lights, self.env.as_ref().and_then(|e| e.keys.as_ref())) {
                let m = key_light_samples(settings.spp);
                let samples = keys.frame_samples(m, self.seed);
                let buffer = Buffer::upload(
                    ctx,
                    bytemuck::cast_slice(&samples),
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    "keylights.frame",
                )?;
                let counts = [m as f32, keys.sampling.dark_samples(m) as f32];
                frame_objects.lights = Some((buffer, samples.len() as u32, counts));
            }
            frame_objects.pool = Some(descriptor::pool(ctx, 8 + lobes.len() as u32, "frame.descriptors")?);
            frame_objects.timestamps = Some(Timestamps::new(ctx, 5 + lobes.len() as u32)?);
            let passes = self.passes.as_ref().expect("passes live until drop");
            let mut push = Push::default();
            camera_push(&settings.camera, w, h, &mut push);
            let (ew, eh) = self.env.as_ref().map_or((1, 1), |e| (e.width, e.height));
            push.size = [w, h, ew, eh];
            push.light = gpu::vec4(settings.light, settings.intensity as f32);
            let rec_base = Recording {
                ctx,
                cmd: ctx.commands.buffer,
                pool: frame_objects.pool.expect("made above"),
                push,
                targets,
                env: self.env.as_ref(),
            };
            let material_buf = frame_objects.material.as_ref().expect("made above");
            let frame_objects_lights = frame_objects.lights.as_ref().map(|(b, n, c)| (b, *n, *c));
            let readback_buf = frame_objects.readback.as_ref().expect("made above");
            let ts = frame_objects.timestamps.as_mut().expect("made above");
            ctx.commands.run(&ctx.device, |cmd| {
                let rec = Recording { cmd, ..rec_base };
                ts.reset(ctx, cmd);
                if !mesh_view {
                    ts.time(ctx, cmd, "canvas", || passes.canvas.record(&rec, material_buf))?;
                } else {
                    let mesh = self.mesh.as_ref().expect("checked above");
                    let vp = settings.camera.view_proj(w, h);
                    ts.time(ctx, cmd, "gbuffer", || {
                        passes.gbuffer.record(ctx, cmd, targets, mesh, &vp);
                        Ok(())
                    })?;
                    ts.time(ctx, cmd, "background", || passes.background.record(&rec))?;
                    match settings.estimator {
                        Estimator::Mis => {
                            let seq = &self.sequence.as_ref().expect("made above").1;
                            ts.time(ctx, cmd, "mis", || {
                                passes.mis.record(&rec, self.mis_offset, settings.spp, material_buf, seq)
                            })?;
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
                                        light_samples: frame_objects_lights,
                                    };
                                    passes.lobe.record(&rec, v, &job)
                                })?;
                            }
                        }
                    }
                }
                readback::record(ctx, cmd, &targets.accum, vk::ImageLayout::GENERAL, readback_buf);
                Ok(())
            })?;
            let timings = ts.read(ctx)?;
            let pixels = readback::pixels(readback_buf);
            Ok(Frame { image: Image { width: w, height: h, pixels }, timings })
        })();
        frame_objects.destroy(ctx);
        let frame = result?;
        ctx.check_validation()?;
        Ok(frame)
    }
}

/// The objects of one frame, destroyed after it whatever happened.
struct FrameObjects {
    material: Option<Buffer>,
    /// The key lights' samples of this frame, how many, and the bright and dark sets' counts.
    lights: Option<(Buffer, u32, [f32; 2])>,
    readback: Option<Buffer>,
    pool: Option<vk::DescriptorPool>,
    timestamps: Option<Timestamps>,
}

impl FrameObjects {
    fn destroy(self, ctx: &Context) {
        // SAFETY: `Commands::run` waited for the submission (or nothing was submitted).
        let _ = unsafe { ctx.raw().device_wait_idle() }.map_err(vk_err("vkDeviceWaitIdle"));
        for b in [self.material, self.lights.map(|l| l.0)].into_iter().flatten() {
            b.destroy(ctx);
        }
        if let Some(b) = self.readback {
            b.destroy(ctx);
        }
        if let Some(p) = self.pool {
            // SAFETY: no pending work uses the pool's sets.
            unsafe { ctx.raw().destroy_descriptor_pool(p, None) };
        }
        if let Some(t) = self.timestamps {
            t.destroy(ctx);
        }
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
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
        if let Some(t) = self.targets.take() {
            t.destroy(&self.ctx);
        }
        for b in [self.halton.take(), self.sequence.take()].into_iter().flatten() {
            b.1.destroy(&self.ctx);
        }
    }
}
