//! Recording a frame: the view's plan (`render::plan`: which passes it needs, each one's variant)
//! made from what the view's targets kept, then its steps in order into the current frame of the
//! ring, each timed (`steps`); and the compose pass that places both views in the window image.

use std::cell::RefCell;

use ash::vk;
use bytemuck::Pod;

use super::environment::GpuEnvironment;
use super::gpu::{self, Push};
use super::plan::{self, Kept, LobeLights, Plan, Request};
use super::targets::{BaseKey, GBufferKey, Targets};
use super::{compact, compose, Estimator, Progress, Recorded, Renderer, Settings, View, MAX_SPP};
use crate::brdf::Material;
use crate::error::{Error, Result};
use crate::scene::keylight::tiles::TileSet;
use crate::scene::Camera;
use crate::vk::descriptor::{self, Binding};
use crate::vk::hazards::{self, Access, Hazards, Resource};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Buffer, Context};

mod steps;

/// How many sizes of targets a view keeps: the full size and two preview steps (the editor's
/// preview may change its step without dropping the full size's G-buffer).
const SIZES_KEPT: usize = 3;

/// What a pass records with: the command buffer, this frame's descriptor pool, the shared push
/// constants, the targets and the environment; and what the view's dispatches have read and
/// written, from which the barriers between them are derived (`vk::hazards`).
pub struct Recording<'a> {
    pub ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
    pub pool: vk::DescriptorPool,
    pub push: Push,
    pub targets: &'a Targets,
    pub env: Option<&'a GpuEnvironment>,
    pub hazards: Hazards,
    /// The accesses of each descriptor set made by [`Self::set`].
    sets: RefCell<Vec<(vk::DescriptorSet, Vec<Access>)>>,
}

impl<'a> Recording<'a> {
    pub fn new(
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        pool: vk::DescriptorPool,
        push: Push,
        targets: &'a Targets,
        env: Option<&'a GpuEnvironment>,
    ) -> Recording<'a> {
        Recording { ctx, cmd, pool, push, targets, env, hazards: Hazards::default(), sets: RefCell::default() }
    }

    pub fn env(&self) -> Result<&GpuEnvironment> {
        self.env.ok_or_else(|| Error::input("render", "a mesh view needs an environment map (--env)"))
    }

    /// A descriptor set of `pipeline`'s layout pointing at `bindings` (checked against its shaders'
    /// bindings: [`Pipeline::write_set`]), whose accesses the dispatches that bind it are ordered
    /// by.
    pub fn set(&self, pipeline: &Pipeline, bindings: &[Binding<'_>]) -> Result<vk::DescriptorSet> {
        let set = descriptor::allocate(self.ctx, self.pool, pipeline.set_layout)?;
        pipeline.write_set(self.ctx, set, bindings)?;
        self.sets.borrow_mut().push((set, hazards::accesses(bindings)));
        Ok(set)
    }

    /// The accesses of `set` (made by [`Self::set`]) and, for an indirect dispatch, of its list.
    fn accesses(&self, set: vk::DescriptorSet, list: Option<&Buffer>) -> Vec<Access> {
        let sets = self.sets.borrow();
        let mut a = sets.iter().find(|(s, _)| *s == set).map(|(_, a)| a.clone()).unwrap_or_default();
        a.extend(list.map(|l| Access { resource: Resource::Buffer(l.raw), write: false, indirect: true }));
        a
    }

    /// Dispatches 8×8 groups over the image.
    pub fn dispatch(&self, pipeline: &Pipeline, set: vk::DescriptorSet, push: &impl Pod) {
        let (w, h) = (self.targets.width, self.targets.height);
        self.dispatch_groups(pipeline, set, push, (w.div_ceil(8), h.div_ceil(8)));
    }

    /// Dispatches `groups` workgroups, after the barrier its conflicts with earlier dispatches need.
    pub fn dispatch_groups(&self, pipeline: &Pipeline, set: vk::DescriptorSet, push: &impl Pod, groups: (u32, u32)) {
        self.hazards.before_dispatch(self.ctx, self.cmd, &self.accesses(set, None));
        pipeline.bind(self.ctx, self.cmd, set, bytemuck::bytes_of(push));
        self.ctx.counts.dispatch();
        // SAFETY: `cmd` is recording with a compute pipeline bound.
        unsafe { self.ctx.raw().cmd_dispatch(self.cmd, groups.0, groups.1, 1) };
    }

    /// Dispatches groups of [`compact::GROUP`] over the targets' list of shaded pixels (as many as
    /// `compact.comp` wrote into its header).
    pub fn dispatch_listed(&self, pipeline: &Pipeline, set: vk::DescriptorSet, push: &impl Pod) {
        self.dispatch_over(&self.targets.pixels, pipeline, set, push);
    }

    /// The same over `list`, the targets' list of pixels or of blocks (`compact.comp` writes both).
    pub fn dispatch_over(&self, list: &Buffer, pipeline: &Pipeline, set: vk::DescriptorSet, push: &impl Pod) {
        self.hazards.before_dispatch(self.ctx, self.cmd, &self.accesses(set, Some(list)));
        pipeline.bind(self.ctx, self.cmd, set, bytemuck::bytes_of(push));
        self.ctx.counts.dispatch();
        // SAFETY: `cmd` is recording with a compute pipeline bound; the list buffer has INDIRECT_BUFFER
        // usage and its header, written by the compact pass of this G-buffer, holds the groups.
        unsafe { self.ctx.raw().cmd_dispatch_indirect(self.cmd, list.raw, compact::GROUPS_OFFSET) };
    }
}

/// The mip level the backdrop is read at: `blur` where it is a finite number ≥ 0, else 0 (the
/// sampler clamps it to the chain's last level, the map's mean).
fn backdrop_lod(blur: f64) -> f32 {
    if blur.is_finite() && blur > 0.0 {
        blur as f32
    } else {
        0.0
    }
}

/// The camera's basis for `camera_ray` in `pass.glsl`.
fn camera_push(camera: &Camera, width: u32, height: u32, push: &mut Push) {
    let forward = (camera.target - camera.eye).normalize();
    let right = forward.cross(camera.up).normalize();
    let up = right.cross(forward);
    let t = (camera.fov_deg.to_radians() / 2.0).tan();
    let aspect = width as f64 / height as f64;
    push.frame.eye = gpu::vec4(camera.eye, 1.0);
    push.frame.right = gpu::vec4(right * t * aspect, 0.0);
    push.frame.up = gpu::vec4(up * t, 0.0);
    push.frame.forward = gpu::vec4(forward, 0.0);
}

impl Renderer {
    /// Makes `views[slot]` the targets of a `w`×`h` image: the current ones, spare ones of that size
    /// (the editor alternates between the full size and its previews' sizes, each keeping its
    /// G-buffer), or new ones. The replaced current targets become the most recent spare; past
    /// [`SIZES_KEPT`] sizes the least recently used are freed after the frames in flight. A mesh
    /// view's refinement restarts on a switch (a mesh view that then waits for its lobe pipelines
    /// switches back: `record_view`). Returns whether the current targets were replaced and became
    /// the first spare ones (false: unchanged, or the view's first targets).
    fn targets_for(&mut self, slot: usize, w: u32, h: u32) -> Result<bool> {
        let fits = |t: &Targets| (t.width, t.height) == (w, h);
        if self.views[slot].as_ref().is_some_and(fits) {
            return Ok(false);
        }
        let targets = match self.spare[slot].iter().position(fits) {
            Some(i) => self.spare[slot].remove(i),
            None => {
                if self.spare[slot].len() + 1 >= SIZES_KEPT {
                    self.idle()?;
                    if let Some(old) = self.spare[slot].pop() {
                        old.destroy(&self.ctx);
                    }
                }
                Targets::new(&self.ctx, w, h)?
            }
        };
        let switched = match self.views[slot].replace(targets) {
            Some(old) => {
                self.spare[slot].insert(0, old);
                true
            }
            None => false,
        };
        if slot == View::Mesh as usize {
            self.refined = 0;
        }
        Ok(switched)
    }

    /// Records, into the current frame, the composed window image `window`: the mesh view (the
    /// refinement's mean when refining, else its last frame) and the canvas placed as `placement`
    /// says (its `mesh_scale` and `backdrop_scale` are multiplied by 1 / samples here).
    /// Only the `parts` that changed are written (`compose::Parts`); nothing when none did.
    pub fn record_compose(
        &mut self,
        window: &crate::vk::Image,
        placement: &compose::Placement,
        parts: compose::Parts,
    ) -> Result<()> {
        if !parts.any() {
            return Ok(());
        }
        let (Some(mesh), Some(canvas)) =
            (self.views[View::Mesh as usize].as_ref(), self.views[View::Canvas as usize].as_ref())
        else {
            return Err(Error::Bug("compose before both views were rendered".into()));
        };
        let (image, samples) = if self.refined > 0 { (&mesh.sum, self.refined) } else { (&mesh.accum, 1) };
        let p = compose::Placement {
            mesh_scale: placement.mesh_scale / samples as f32,
            backdrop_scale: placement.backdrop_scale / samples as f32,
            summed: samples,
            ..*placement
        };
        let passes = self.passes.as_ref().expect("passes live until drop");
        let ring = self.ring.as_mut().expect("ring lives until drop");
        let f = ring.current();
        let (cmd, pool) = (f.cmd, f.pool);
        f.timestamps.time(&self.ctx, cmd, "compose", || {
            passes.compose.record(&self.ctx, cmd, pool, window, (image, &canvas.accum), &p, parts)
        })
    }

    /// Records one view of `material` into the current frame (begun by [`Renderer::begin_frame`]),
    /// into that view's persistent targets. `Progress::Refine` adds `settings.spp` more `mis` samples
    /// to the mesh view's running sum (continuing its sequence); `Fresh` restarts it.
    /// With [`Renderer::build_in_background`] set, a mesh view whose lobe pipelines are still being
    /// built records nothing and keeps its last image ([`Recorded::Waiting`]).
    pub fn record(&mut self, material: &Material, settings: &Settings, progress: Progress) -> Result<Recorded> {
        self.record_view(material, settings, progress, true)
    }

    /// The plan of the frame [`Renderer::record`] would record for `settings` now (what the view's
    /// targets kept included; `reuse` false: a frame that rasterises, as the headless `render`'s),
    /// without recording anything.
    pub fn plan(&self, material: &Material, settings: &Settings, progress: Progress, reuse: bool) -> Plan {
        let refine = matches!(progress, Progress::Refine) && settings.view == View::Mesh;
        let targets = self.views[settings.view as usize]
            .as_ref()
            .filter(|t| (t.width, t.height) == (settings.width, settings.height));
        let kept = match targets {
            Some(t) if reuse && settings.view == View::Mesh => Kept {
                gbuffer: t.gbuffer_of.is_some() && t.gbuffer_of == self.gbuffer_key(settings),
                pixels_listed: t.pixels_listed,
                base: t.base_of.is_some() && t.base_of == Some(self.base_key(material, settings)),
            },
            _ => Kept::default(),
        };
        plan::plan(&Request {
            view: settings.view,
            width: settings.width,
            height: settings.height,
            spp: settings.spp,
            estimator: settings.estimator,
            camera: &settings.camera,
            refine_from: refine.then_some(self.refined),
            material,
            lights: self.env.as_ref().and_then(|e| e.keys.as_ref()).map(|k| &k.set),
            kept,
            device: self.device_plan,
            options: &self.options,
        })
    }

    /// What a mesh view's G-buffer is of: the mesh, the camera and whether back faces are culled.
    fn gbuffer_key(&self, s: &Settings) -> Option<GBufferKey> {
        let mesh = self.mesh.as_ref()?;
        Some((mesh.key.clone(), s.camera.clone(), plan::culls(&s.camera, s.width, s.height, &self.options)))
    }

    /// What the saved background and diffuse image of a frame of `s` is of: the map, the estimator's
    /// diffuse term, the diffuse albedo and the backdrop's blur.
    fn base_key(&self, material: &Material, s: &Settings) -> BaseKey {
        let env = self.env.as_ref().map(|e| e.key.clone()).unwrap_or_default();
        let key = s.estimator == Estimator::Key;
        (env, key, material.diffuse.map(f64::to_bits), backdrop_lod(s.backdrop_blur).to_bits())
    }

    /// [`Renderer::record`]; with `reuse`, a mesh view whose mesh, camera and size are unchanged keeps
    /// its G-buffer (the headless `render` always rasterises: a frame of its own, timed whole).
    pub(super) fn record_view(
        &mut self,
        material: &Material,
        settings: &Settings,
        progress: Progress,
        reuse: bool,
    ) -> Result<Recorded> {
        self.check_size(settings)?;
        let refine = matches!(progress, Progress::Refine) && settings.view == View::Mesh;
        if refine && settings.estimator != Estimator::Mis {
            return Err(Error::Bug("refinement frames are mis frames".into()));
        }
        let mesh_view = settings.view == View::Mesh;
        if mesh_view && (self.env.is_none() || self.mesh.is_none()) {
            return Err(Error::input("render", "a mesh view needs an environment and a mesh"));
        }
        let slot = settings.view as usize;
        let refined_before = self.refined;
        let switched = self.targets_for(slot, settings.width, settings.height)?;
        let offset = if refine { self.refined } else { 0 };
        if refine && offset.saturating_add(settings.spp) > MAX_SPP {
            return Err(Error::input(
                "--spp",
                format!("{} samples after {offset} is more than the limit of {MAX_SPP}", settings.spp),
            ));
        }
        let plan = self.plan(material, settings, progress, reuse);
        if mesh_view && !self.prepare_lobes(&plan, settings, offset)? {
            self.keep_shown(slot, switched, refined_before);
            return Ok(Recorded::Waiting);
        }
        let gbuffer_key = self.gbuffer_key(settings).filter(|_| mesh_view);
        let base_key = plan.base_used.then(|| self.base_key(material, settings));
        let targets = self.views[slot].as_mut().expect("made by targets_for");
        if plan.raster {
            // Set again once the whole view is recorded (an error leaves nothing to reuse).
            targets.gbuffer_of = None;
            targets.pixels_listed = false;
        }
        // Set again at the end, the same way (a frame that saves it may stop half-recorded).
        let base_of = targets.base_of.take();
        self.record_plan(settings, &plan)?;
        self.refined = if refine { offset + settings.spp } else { 0 };
        let targets = self.views[slot].as_mut().expect("made by targets_for");
        if mesh_view {
            targets.gbuffer_of = gbuffer_key;
        }
        if let Some(listed) = plan.pixels_listed {
            targets.pixels_listed = listed;
        }
        // A `mis` frame leaves `base` as it was.
        targets.base_of = if plan.raster { None } else { base_key.or(base_of) };
        targets.drawn = true;
        Ok(Recorded::Done)
    }

    /// Makes the sample tables of a mesh view's frame and its lobe pipelines: at once, or with
    /// [`Renderer::build_in_background`] on threads of their own; false while those are being built.
    fn prepare_lobes(&mut self, plan: &Plan, settings: &Settings, offset: u32) -> Result<bool> {
        self.buffers_for(offset.saturating_add(settings.spp), settings.spp, settings.estimator)?;
        if settings.estimator == Estimator::Mis {
            return Ok(true);
        }
        let variants: Vec<_> = plan.lobes().map(|l| l.variant).collect();
        let lobe = &mut self.passes.as_mut().expect("passes live until drop").lobe;
        match &self.build_in_background {
            Some(notify) => lobe.ready(&self.ctx, &variants, notify),
            None => lobe.prepare(&self.ctx, &variants).map(|()| true),
        }
    }

    /// A mesh view that waits for its lobe pipelines keeps showing what it showed: back to the
    /// targets it had; new targets show black until the view is drawn (compose reads them).
    fn keep_shown(&mut self, slot: usize, switched: bool, refined_before: u32) {
        if switched {
            let shown = self.spare[slot].remove(0);
            let new = self.views[slot].replace(shown).expect("made by targets_for");
            self.spare[slot].insert(0, new);
            self.refined = refined_before;
        }
        let targets = self.views[slot].as_mut().expect("made by targets_for");
        if !targets.drawn {
            let cmd = self.ring.as_mut().expect("ring lives until drop").current().cmd;
            targets.accum.clear_to_general(&self.ctx, cmd, barrier::COMPUTE_READ_WRITE);
            targets.drawn = true;
        }
    }

    /// Uploads what the plan's passes read from this frame's buffers (the light samples, the lobes'
    /// tiles) and records its steps in order, each timed.
    fn record_plan(&mut self, settings: &Settings, plan: &Plan) -> Result<()> {
        let ctx = &self.ctx;
        let ring = self.ring.as_mut().expect("ring lives until drop");
        let keys = self.env.as_ref().and_then(|e| e.keys.as_ref());
        let mut light_counts = None;
        if let (Some(m), Some(keys)) = (plan.light_samples, keys) {
            let samples = keys.frame_samples(m, self.seed);
            ring.current().upload(ctx, "keylights.frame", &gpu::light_set_bytes(&samples))?;
            light_counts = Some((samples.len() as u32, [m as f32, keys.sampling.dark_samples(m) as f32]));
        }
        let tiles: Vec<&TileSet> = plan
            .lobes()
            .filter_map(|l| match &l.lights {
                LobeLights::Tiles(t) => Some(t),
                _ => None,
            })
            .collect();
        if !tiles.is_empty() {
            let bytes: Vec<u8> = tiles.iter().flat_map(|t| gpu::light_set_bytes(&t.rows)).collect();
            ring.current().upload(ctx, "keylights.tiles", &bytes)?;
        }
        let frame = ring.current();
        let (cmd, pool) = (frame.cmd, frame.pool);
        let (ts, buffers) = frame.parts();
        let (w, h) = (settings.width, settings.height);
        let mut push = Push::default();
        camera_push(&settings.camera, w, h, &mut push);
        let (ew, eh) = self.env.as_ref().map_or((1, 1), |e| (e.width, e.height));
        push.frame.size = [w, h, ew, eh];
        push.light = gpu::vec4(settings.light, settings.intensity as f32);
        // The backdrop's mip level (`backdrop_lod` in pass.glsl) travels in the forward vector's
        // unused fourth component.
        push.frame.forward[3] = backdrop_lod(settings.backdrop_blur);
        let targets = self.views[settings.view as usize].as_ref().expect("made by targets_for");
        let rec = Recording::new(ctx, cmd, pool, push, targets, self.env.as_ref());
        let steps = steps::StepRecorder {
            rec,
            passes: self.passes.as_ref().expect("passes live until drop"),
            material: buffers.get("material").expect("written by begin_frame"),
            compensation: ["tables", "kernels"].map(|n| buffers.get(n).expect("written by begin_frame")),
            light_samples: light_counts
                .map(|(n, c)| steps::light_set(buffers.get("keylights.frame").expect("written above"), 0, n, c)),
            tiles: buffers.get("keylights.tiles").filter(|_| !tiles.is_empty()),
            keys: keys.filter(|_| settings.estimator == Estimator::Key),
            mesh: self.mesh.as_ref(),
            halton: self.halton.as_ref().map(|h| &h.1),
            sequence: self.sequence.as_ref().map(|s| &s.1),
            view_proj: settings.camera.view_proj(w, h),
            spp: settings.spp,
            seed: self.seed,
        };
        let recorded = steps.record(ts, plan);
        // What the view's last dispatches wrote, for whatever the frame records next.
        steps.rec.hazards.flush(ctx, cmd);
        recorded
    }
}
