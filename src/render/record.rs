//! Recording a frame: which passes a view needs (the lobes with non-zero albedo, their variants, the
//! key lights' samples or points), in order into the current frame of the ring, each timed; and the
//! compose pass that places both views in the window image.

use ash::vk;

use super::environment::{Cut, GpuEnvironment, GpuWideLights, TileLights};
use super::gpu::{self, Push};
use super::targets::Targets;
use super::{
    compact, compose, denoise, key_light_samples, lobe, Estimator, Progress, Recorded, Renderer, Settings, View,
    MAX_SPP,
};
use crate::brdf::Material;
use crate::error::{Error, Result};
use crate::scene::keylight::tiles::{max_points, tile_alpha, TileSet};
use crate::scene::keylight::MAX_LIGHTS;
use crate::scene::Camera;
use crate::vk::descriptor::{self, Binding};
use crate::vk::pipeline::Pipeline;
use crate::vk::{barrier, Buffer, Context};

/// How many sizes of targets a view keeps: the full size and two preview steps (the editor's
/// preview may change its step without dropping the full size's G-buffer).
const SIZES_KEPT: usize = 3;

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
        let (w, h) = (self.targets.width, self.targets.height);
        self.dispatch_groups(pipeline, set, push, (w.div_ceil(8), h.div_ceil(8)));
    }

    /// Dispatches `groups` workgroups, then orders the accumulation image as [`Self::dispatch`].
    pub fn dispatch_groups(&self, pipeline: &Pipeline, set: vk::DescriptorSet, push: &Push, groups: (u32, u32)) {
        pipeline.bind(self.ctx, self.cmd, set, bytemuck::bytes_of(push));
        // SAFETY: `cmd` is recording with a compute pipeline bound.
        unsafe { self.ctx.raw().cmd_dispatch(self.cmd, groups.0, groups.1, 1) };
        crate::vk::barrier::memory(self.ctx, self.cmd, barrier::COMPUTE_WRITE, barrier::COMPUTE_READ_WRITE);
    }

    /// Dispatches groups of [`compact::GROUP`] over the targets' list of shaded pixels (as many as
    /// `compact.comp` wrote into its header), then orders the accumulation image as [`Self::dispatch`].
    pub fn dispatch_listed(&self, pipeline: &Pipeline, set: vk::DescriptorSet, push: &Push) {
        self.dispatch_over(&self.targets.pixels, pipeline, set, push);
    }

    /// The same over `list`, the targets' list of pixels or of blocks (`compact.comp` writes both).
    pub fn dispatch_over(&self, list: &Buffer, pipeline: &Pipeline, set: vk::DescriptorSet, push: &Push) {
        pipeline.bind(self.ctx, self.cmd, set, bytemuck::bytes_of(push));
        // SAFETY: `cmd` is recording with a compute pipeline bound; the list buffer has INDIRECT_BUFFER
        // usage and its header, written by the compact pass of this G-buffer, holds the groups.
        unsafe { self.ctx.raw().cmd_dispatch_indirect(self.cmd, list.raw, compact::GROUPS_OFFSET) };
        crate::vk::barrier::memory(self.ctx, self.cmd, barrier::COMPUTE_WRITE, barrier::COMPUTE_READ_WRITE);
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
    push.eye = gpu::vec4(camera.eye, 1.0);
    push.right = gpu::vec4(right * t * aspect, 0.0);
    push.up = gpu::vec4(up * t, 0.0);
    push.forward = gpu::vec4(forward, 0.0);
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
            return Err(Error::Validation("compose before both views were rendered".into()));
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
            return Err(Error::Validation("refinement frames are mis frames".into()));
        }
        let (w, h) = (settings.width, settings.height);
        let mesh_view = settings.view == View::Mesh;
        if mesh_view && (self.env.is_none() || self.mesh.is_none()) {
            return Err(Error::input("render", "a mesh view needs an environment and a mesh"));
        }
        let slot = settings.view as usize;
        let refined_before = self.refined;
        let switched = self.targets_for(slot, w, h)?;
        let offset = if refine { self.refined } else { 0 };
        if refine && offset.saturating_add(settings.spp) > MAX_SPP {
            return Err(Error::input(
                "--spp",
                format!("{} samples after {offset} is more than the limit of {MAX_SPP}", settings.spp),
            ));
        }
        // Which lobes get a pass: non-zero albedo only.
        let prefilter = matches!(settings.estimator, Estimator::Fis | Estimator::Key);
        let key = settings.estimator == Estimator::Key;
        let key_lights = self.env.as_ref().and_then(|e| e.keys.as_ref()).filter(|_| key);
        let lights = key_lights.is_some();
        // Where each lobe pass writes: the rough lobes the filter takes (`denoise::fits`), sampled
        // once a 2 × 2 block in sparse frames.
        let sparse = self.sparse_filter && denoise::sparse(settings.spp, w, h);
        let floor = denoise::min_alpha(sparse, w, h);
        // A lobe too narrow for the lights' own points sees them as tiles where those fit.
        let chosen: Vec<(u32, lobe::Variant, Option<TileSet>)> = material
            .lobes
            .iter()
            .enumerate()
            .filter(|(_, l)| l.albedo.iter().any(|&a| a != 0.0))
            .map(|(i, l)| {
                let mut tile_set = None;
                let fits = |lights: &[crate::scene::keylight::KeyLight]| {
                    crate::scene::keylight::quadrature_fits(lights, l.alpha_x, l.alpha_y)
                };
                let whole = key_lights.is_some_and(|k| fits(&k.lights));
                // The tiles a lobe may take count on its reach test (`tiles::max_points`); the same
                // tiles with the test off give the same image (a test compares).
                let base = lobe::Variant::of(material, l, prefilter);
                let pays = lights && lobe::reach_test_pays(material, l);
                let reach = pays.then(|| lobe::reach_half_angles(material.normalization, l));
                let reach_test = self.light_reach_test && pays;
                let wide_lights = key_lights.and_then(|k| k.wide.as_ref()).filter(|_| self.wide_lights);
                // A lobe that sees the wide lights as points too takes them off its residual.
                let mut wide = whole && wide_lights.is_some_and(|w| fits(&w.lights));
                let mut tiled = false;
                if let Some(k) = key_lights.filter(|_| !wide && self.light_tiles) {
                    // Round tiles, or for an anisotropic lobe of one component strips across its
                    // narrow axis (`keylight::strips`), whichever runs fewer points a pixel.
                    let round = Cut::Tiles(tile_alpha(l.alpha_x, l.alpha_y));
                    let (narrow, broad) = (l.alpha_x.min(l.alpha_y), l.alpha_x.max(l.alpha_y));
                    let streak = (self.light_strips && !(base.split || base.sym) && narrow < broad)
                        .then_some(Cut::Strips(narrow, broad));
                    let cut = |budget: usize, which: TileLights| match (
                        k.tiles(round, budget, which),
                        streak.and_then(|c| k.tiles(c, budget, which)),
                    ) {
                        (Some(t), Some(s)) if s.points_seen() >= t.points_seen() => Some(t),
                        (t, s) => s.or(t),
                    };
                    // The key and wide lights together first (also for a lobe that sees the key
                    // lights as points: those are then their own one tile), where the reach test
                    // (if it pays) sees them all; their tiles take the wide lights off the residual.
                    let wide_tiles = self.wide_tiles && settings.spp >= lobe::WIDE_TILES_MIN_SPP;
                    let tested = |w: &&GpuWideLights| !pays || w.cones.is_some();
                    if let Some(w) = wide_lights.filter(|w| wide_tiles && tested(w)) {
                        if let Some(rows) = cut(max_points(&w.all, reach), TileLights::KeyAndWide) {
                            tile_set = Some(rows);
                            (tiled, wide) = (true, true);
                        }
                    }
                    // Otherwise a lobe wide enough sees the wide lights as their own points: its key
                    // lights' tiles within their own allowance, and four points for each wide light
                    // (the allowance of the key and wide lights together, which counts the wide
                    // lights' share of the pixels in reach, is smaller: it would hold the quick
                    // sweep's painted streak, α 0.33 × 0.02 on studio, to 64 points, where the lamp
                    // alone takes 124 as round tiles; its strips take 36).
                    let wide_points = |w: &&GpuWideLights| {
                        self.wide_tiles && tested(w) && lobe::sees_wide_lights_as_points(l, &w.lights, settings.spp)
                    };
                    let key_points = max_points(&k.lights, reach);
                    if let Some(w) = wide_lights.filter(|w| !tiled && wide_points(w)) {
                        let budget = key_points + 4 * w.lights.len();
                        if let Some(rows) = cut(budget, TileLights::KeyAndWidePoints) {
                            tile_set = Some(rows);
                            (tiled, wide) = (true, true);
                        }
                    }
                    if !tiled && !whole {
                        if let Some(rows) = cut(key_points, TileLights::Key) {
                            tile_set = Some(rows);
                            tiled = true;
                        }
                    }
                }
                let points = whole || tiled;
                let tests_reach = reach_test && (!points || tiled);
                // The lights of the cone table the test reads (`LobePass::record`).
                let light_slots = match key_lights.filter(|_| tests_reach) {
                    Some(k) if wide => k.wide.as_ref().map_or(MAX_LIGHTS, |w| w.all.len()),
                    Some(k) => k.lights.len(),
                    None => MAX_LIGHTS,
                };
                let variant = lobe::Variant {
                    vec4: !self.scalar_lobes,
                    key,
                    lights,
                    points,
                    wide,
                    reach: tests_reach,
                    light_slots: light_slots.clamp(1, MAX_LIGHTS) as u8,
                    oriented: tile_set.as_ref().map_or(0, |t| t.oriented as u8),
                    ..base
                };
                (i as u32, variant, tile_set)
            })
            .collect();
        let mut tiles: Vec<(u32, TileSet)> = Vec::new();
        let mut lobes: Vec<(u32, lobe::Variant)> = Vec::new();
        for (i, v, t) in chosen {
            tiles.extend(t.map(|t| (i, t)));
            lobes.push((i, v));
        }
        // Where each lobe pass writes, which its pipeline is built for (`lobe::Output`).
        let intos: Vec<lobe::Into> = lobes
            .iter()
            .map(|(i, v)| {
                let l = &material.lobes[*i as usize];
                let filtered = self.denoise && v.key && denoise::fits(l, v.lights && !v.points, floor);
                match (filtered, sparse) {
                    (false, _) => lobe::Into::Accum,
                    (true, true) => lobe::Into::Cells { pixel_lights: denoise::pixel_lights(l, w, h) },
                    (true, false) => lobe::Into::Rough { strata: self.stratified_shifts },
                }
            })
            .collect();
        for ((_, v), into) in lobes.iter_mut().zip(&intos) {
            // The editor's stand-in (`LobePass::ready`) covers every lobe that may leave `Accum`.
            debug_assert!(*into == lobe::Into::Accum || v.outputs_vary(), "{v:?} writes {into:?}");
            v.output = if self.any_output_lobes { lobe::Output::Any } else { into.output() };
        }
        if mesh_view {
            self.buffers_for(offset.saturating_add(settings.spp), settings.spp, settings.estimator)?;
            if settings.estimator != Estimator::Mis {
                let variants: Vec<_> = lobes.iter().map(|l| l.1).collect();
                let lobe = &mut self.passes.as_mut().expect("passes live until drop").lobe;
                match &self.build_in_background {
                    Some(notify) => {
                        if !lobe.ready(&self.ctx, &variants, notify)? {
                            // The view keeps showing what it showed: back to the targets it had.
                            if switched {
                                let shown = self.spare[slot].remove(0);
                                let new = self.views[slot].replace(shown).expect("made above");
                                self.spare[slot].insert(0, new);
                                self.refined = refined_before;
                            }
                            // New targets show black until the view is drawn (compose reads them).
                            let targets = self.views[slot].as_mut().expect("made above");
                            if !targets.drawn {
                                let cmd = self.ring.as_mut().expect("ring lives until drop").current().cmd;
                                targets.accum.clear_to_general(&self.ctx, cmd, barrier::COMPUTE_READ_WRITE);
                                targets.drawn = true;
                            }
                            return Ok(Recorded::Waiting);
                        }
                    }
                    None => lobe.prepare(&self.ctx, &variants)?,
                }
            }
        }
        let ctx = &self.ctx;
        let ring = self.ring.as_mut().expect("ring lives until drop");
        let mut light_counts = None;
        let sampled = lobes.iter().any(|l| l.1.lights && !l.1.points);
        if let (true, true, Some(keys)) = (mesh_view, sampled, self.env.as_ref().and_then(|e| e.keys.as_ref())) {
            let m = key_light_samples(settings.spp);
            let samples = keys.frame_samples(m, self.seed);
            ring.current().upload(ctx, "keylights.frame", &gpu::light_set_bytes(&samples))?;
            light_counts = Some((samples.len() as u32, [m as f32, keys.sampling.dark_samples(m) as f32]));
        }
        if mesh_view && !tiles.is_empty() {
            let bytes: Vec<u8> = tiles.iter().flat_map(|(_, t)| gpu::light_set_bytes(&t.rows)).collect();
            ring.current().upload(ctx, "keylights.tiles", &bytes)?;
        }
        let frame = ring.current();
        let (cmd, pool) = (frame.cmd, frame.pool);
        let (ts, buffers) = frame.parts();
        let material_buf = buffers.get("material").expect("written by begin_frame");
        let set = |buffer, offset, count, counts| lobe::LightSet { buffer, offset, count, counts, ends: None };
        let light_samples =
            light_counts.map(|(n, c)| set(buffers.get("keylights.frame").expect("written above"), 0, n, c));
        let key_lights = self.env.as_ref().and_then(|e| e.keys.as_ref()).filter(|_| key);
        let light_points = key_lights.map(|k| set(&k.points, 0, 4 * k.lights.len() as u32, [0.0; 2]));
        let wide_points = key_lights.and_then(|k| k.wide.as_ref()).map(|w| set(&w.points, 0, w.count, [0.0; 2]));
        let tile_set = |lobe: u32| {
            let at = tiles.iter().position(|t| t.0 == lobe)?;
            let buffer = buffers.get("keylights.tiles").expect("written above");
            let t = &tiles[at].1;
            let ends = lobe::LightSet::light_ends(&t.ends);
            Some(lobe::LightSet {
                ends,
                ..set(buffer, (at * gpu::LIGHT_SET_UNIFORM_BYTES) as u64, t.rows.len() as u32, [0.0; 2])
            })
        };
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
            targets.pixels_listed = false;
        }
        // Set again at the end, the same way (a frame that saves it may stop half-recorded).
        let base_of = targets.base_of.take();
        let targets = self.views[slot].as_ref().expect("made above");
        let mut push = Push::default();
        camera_push(&settings.camera, w, h, &mut push);
        let (ew, eh) = self.env.as_ref().map_or((1, 1), |e| (e.width, e.height));
        push.size = [w, h, ew, eh];
        push.light = gpu::vec4(settings.light, settings.intensity as f32);
        // The backdrop's mip level (`backdrop_lod` in pass.glsl) travels in the forward vector's
        // unused fourth component.
        push.forward[3] = backdrop_lod(settings.backdrop_blur);
        let rec = Recording { ctx, cmd, pool, push, targets, env: self.env.as_ref() };
        if !mesh_view {
            ts.time(ctx, cmd, "canvas", || passes.canvas.record(&rec, material_buf))?;
            self.views[slot].as_mut().expect("made above").drawn = true;
            return Ok(Recorded::Done);
        }
        let mesh = self.mesh.as_ref().expect("checked above");
        let vp = settings.camera.view_proj(w, h);
        // The diffuse pass's term, where the frame has one.
        let diffuse = (settings.estimator != Estimator::Mis && material.diffuse.iter().any(|&d| d != 0.0))
            .then_some((material.diffuse, key));
        // A frame that rasterises and filters sparsely leaves the diffuse term to the filter, which
        // reads and writes every listed pixel anyway (`compact::Start::Later`).
        let later = raster
            && self.frame_plan.clear_then_later
            && sparse
            && settings.estimator != Estimator::Mis
            && intos.iter().any(|into| matches!(into, lobe::Into::Cells { .. }));
        // Whether a pass of this frame runs over the list of pixels (the others run over the blocks).
        let over_pixels =
            settings.estimator == Estimator::Mis || intos.iter().any(|into| !matches!(into, lobe::Into::Cells { .. }));
        // The lists of shaded pixels and blocks belong to the G-buffer: built with it, timed with it,
        // and the same pass starts the image (`CompactPass::record`): no background and diffuse
        // passes. Where no pass runs over the pixels, their list waits for a frame that keeps the
        // G-buffer and needs it (`Targets::pixels_listed`).
        let start = if later { compact::Start::Later { pixels: over_pixels } } else { compact::Start::Here(diffuse) };
        if raster {
            ts.time(ctx, cmd, "gbuffer", || {
                passes.gbuffer.record(ctx, cmd, targets, mesh, &vp, cull);
                passes.compact.record(&rec, start)?;
                if later {
                    passes.background.record_blocks(&rec)?;
                }
                Ok(())
            })?;
        }
        // A frame that keeps a G-buffer whose pixels are not listed lists them, in the pass that
        // starts the image as the background and diffuse passes would (bit for bit). So does every
        // frame that keeps its G-buffer where the frame plan draws that image again rather than
        // copying it.
        let copy_base = self.frame_plan.copy_base;
        let relist = !raster && (!targets.pixels_listed || (!copy_base && settings.estimator != Estimator::Mis));
        // A frame that keeps the G-buffer starts from the image the background and diffuse passes
        // left the frame before (`Targets::base`): while painting only the lobes change.
        let base_key = (settings.estimator != Estimator::Mis && !raster && copy_base).then(|| {
            let env = self.env.as_ref().map(|e| e.key.clone()).unwrap_or_default();
            (env, key, material.diffuse.map(f64::to_bits), push.forward[3].to_bits())
        });
        let restored = base_key.is_some() && base_of == base_key && !relist;
        if restored {
            ts.time(ctx, cmd, "base", || {
                targets.restore_base(ctx, cmd);
                Ok(())
            })?;
        } else if relist {
            ts.time(ctx, cmd, "compact", || passes.compact.record(&rec, compact::Start::Here(diffuse)))?;
        } else if !raster {
            ts.time(ctx, cmd, "background", || passes.background.record(&rec))?;
        }
        match settings.estimator {
            Estimator::Mis => {
                let seq = &self.sequence.as_ref().expect("made above").1;
                ts.time(ctx, cmd, "mis", || passes.mis.record(&rec, offset, settings.spp, material_buf, seq))?;
            }
            Estimator::Fis | Estimator::Plain | Estimator::Key => {
                if let Some((albedo, residual)) = diffuse.filter(|_| !restored && !raster && !relist) {
                    ts.time(ctx, cmd, "diffuse", || passes.diffuse.record(&rec, albedo, residual))?;
                }
                if !restored && base_key.is_some() {
                    ts.time(ctx, cmd, "base.save", || {
                        targets.save_base(ctx, cmd);
                        Ok(())
                    })?;
                }
                let halton = &self.halton.as_ref().expect("made above").1;
                // (Refinement frames are `mis` frames: a `key` frame is whole.)
                // The smallest α among the lobes the filter takes.
                let min_alpha = lobes
                    .iter()
                    .zip(&intos)
                    .filter(|(_, into)| **into != lobe::Into::Accum)
                    .map(|((i, _), _)| {
                        let l = &material.lobes[*i as usize];
                        l.alpha_x.min(l.alpha_y)
                    })
                    .fold(f64::INFINITY, f64::min);
                if min_alpha.is_finite() {
                    // Zero (unmarked) where no lobe pass writes (`denoise.comp`); the passes add.
                    let images = if sparse { vec![&targets.cells, &targets.cells_light] } else { vec![&targets.rough] };
                    if self.frame_plan.zero_by_compute {
                        ts.time(ctx, cmd, "zero", || passes.zero.record(ctx, cmd, pool, &images))?;
                    } else {
                        for image in images {
                            image.clear_to_general(ctx, cmd, barrier::COMPUTE_READ_WRITE);
                        }
                    }
                }
                for (&(i, v), &into) in lobes.iter().zip(&intos) {
                    let name = match tiles.iter().find(|t| t.0 == i) {
                        Some((_, t)) if t.oriented > 0 => format!("lobe{i}[{} {}]", v.tag(), t.points_seen()),
                        Some((_, t)) => format!("lobe{i}[{},tiles {}]", v.tag(), t.rows.len()),
                        None => format!("lobe{i}[{}]", v.tag()),
                    };
                    ts.time(ctx, cmd, &name, || {
                        let job = lobe::Job {
                            index: i,
                            samples: settings.spp,
                            seed: self.seed,
                            material: material_buf,
                            halton,
                            light_samples: match (v.points, v.wide) {
                                (true, true) => tile_set(i).or(wide_points),
                                (true, false) => tile_set(i).or(light_points),
                                (false, _) => light_samples,
                            },
                            into,
                        };
                        passes.lobe.record(&rec, v, &job)
                    })?;
                }
                if min_alpha.is_finite() {
                    let deferred = diffuse.filter(|_| later);
                    let name = match (sparse, deferred.is_some()) {
                        (true, true) => "denoise[sparse,diffuse]",
                        (true, false) => "denoise[sparse]",
                        (false, _) => "denoise",
                    };
                    ts.time(ctx, cmd, name, || passes.denoise.record(&rec, min_alpha, settings.spp, sparse, deferred))?;
                }
            }
        }
        if refine {
            ts.time(ctx, cmd, "accumulate", || {
                passes.accumulate.record(ctx, cmd, pool, targets, offset == 0, settings.spp)
            })?;
            self.refined = offset + settings.spp;
        } else {
            self.refined = 0;
        }
        let targets = self.views[slot].as_mut().expect("made above");
        targets.gbuffer_of = gbuffer_key;
        if raster {
            targets.pixels_listed = start.lists_pixels();
        } else if relist {
            targets.pixels_listed = true;
        }
        // A `mis` frame leaves `base` as it was.
        targets.base_of = if raster { None } else { base_key.or(base_of) };
        targets.drawn = true;
        Ok(Recorded::Done)
    }
}
