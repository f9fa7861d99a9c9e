//! Pass 3 (paper §4), one dispatch per lobe: Halton QMC importance sampling of the rotated Ward
//! lobe, four samples at a time, reading the prefiltered environment (or level 0 for `plain`).
//! One pipeline per combination of specialisation constants a scene needs, built on first use:
//! at once for a headless render, or on a thread of its own for the editor (LLVM compiles a new
//! lobe variant slowly on lavapipe, which would stall the window; the mesh view keeps its last
//! image until the pipeline is there).

use std::collections::HashMap;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;

use super::environment::GpuEnvironment;
use super::Recording;
use crate::scene::keylight::MAX_LIGHTS;
use crate::vk::descriptor::Binding;
use crate::vk::pipeline::Pipeline;
use crate::vk::{Buffer, Context};
use crate::Result;

mod policy;
pub use super::plan::variant::{Into, KeyLights, Lookup, Output, Reach, Variant};
pub use policy::*;

/// What one lobe pass adds: lobe `index` sampled with the `halton` groups of `samples` samples (a
/// `key` variant computes the sequence of frame `seed` instead and, with lights, adds the frame's
/// light samples and their count).
#[derive(Clone, Copy)]
pub struct Job<'a> {
    pub index: u32,
    pub samples: u32,
    pub seed: u32,
    pub material: &'a Buffer,
    pub halton: &'a Buffer,
    pub light_samples: Option<LightSet<'a>>,
    pub into: Into,
}

/// The light set a lobe pass reads: the frame's light samples, or for a `points` variant the
/// lights' points (or their tiles', `keylight::tiles`).
#[derive(Clone, Copy)]
pub struct LightSet<'a> {
    /// The uniform block is `gpu::LIGHT_SET_UNIFORM_BYTES` of this buffer from `offset`.
    pub buffer: &'a Buffer,
    pub offset: u64,
    /// How many samples or points it holds.
    pub count: u32,
    /// The sample counts of the bright and dark sets (zeros for points).
    pub counts: [f32; 2],
    /// For tiles (`keylight::tiles::TileSet`), where each light's rows end, the slots past the
    /// lights' ending where the last does: a `points` variant with the reach test runs each light's
    /// points only at the pixels within its reach (`glsl/include/lobe_lights.glsl` `near_points`,
    /// `block_points`). `None` for the other sets.
    pub ends: Option<[u32; MAX_LIGHTS]>,
}

impl LightSet<'_> {
    /// `ends` of a tile set: `None` for more lights than the reach test's slots.
    pub fn light_ends(ends: &[usize]) -> Option<[u32; MAX_LIGHTS]> {
        let last = *ends.last()?;
        (ends.len() <= MAX_LIGHTS).then(|| std::array::from_fn(|k| ends.get(k).copied().unwrap_or(last) as u32))
    }
}

/// Called on the building thread when a pipeline built in the background is ready.
pub type Notify = Arc<dyn Fn() + Send + Sync>;

pub struct LobePass {
    pipelines: HashMap<Variant, Pipeline>,
    /// Pipelines being built on threads of their own ([`LobePass::ready`]); each thread sends its
    /// pipeline on `built` before it calls its `Notify`, so whoever is notified finds it there.
    building: HashMap<Variant, JoinHandle<()>>,
    built: (Sender<Built>, Receiver<Built>),
}

/// What a building thread sends: its variant and pipeline.
type Built = (Variant, Result<Pipeline>);

/// The end of a building thread, also by a panic: an error is sent in place of the pipeline, then
/// the owner is notified (so a waiting view learns of the failure instead of waiting forever).
struct Done {
    variant: Variant,
    sender: Sender<Built>,
    notify: Notify,
}

impl Drop for Done {
    fn drop(&mut self) {
        if std::thread::panicking() {
            let _ = self.sender.send((self.variant, Err(panicked())));
        }
        (self.notify)();
    }
}

/// The debug name of a variant's pipeline.
/// What a lobe pass reads besides its targets: the lights' cones for the reach test, the lights'
/// texels, the residual map and the light set (stand-ins where the variant reads none: the layout is
/// the same for every variant).
struct Reads<'a> {
    cones: &'a Buffer,
    texels: &'a crate::vk::Image,
    residual: &'a crate::vk::Image,
    lights: LightSet<'a>,
}

impl<'a> Reads<'a> {
    fn of(env: &'a GpuEnvironment, variant: Variant, job: &Job<'a>) -> Result<Reads<'a>> {
        let keys = env.keys.as_ref().filter(|_| variant.has_lights());
        if variant.has_lights() && (keys.is_none() || job.light_samples.is_none()) {
            return Err(crate::Error::Bug("a lobe pass with key lights on a map without any".into()));
        }
        let (mut cones, texels) = keys.map_or((&env.sh, &env.texture), |k| (&k.cones, &k.texels));
        // A lobe that sees the key and wide lights as tiles tests its reach to all of them.
        let reach = match variant.reach() {
            Reach::Tested { slots } => Some(usize::from(slots)),
            Reach::Untested => None,
        };
        if variant.wide() && reach.is_some() {
            cones = keys.and_then(|k| k.wide.as_ref()).and_then(|w| w.cones.as_ref()).ok_or_else(|| {
                crate::Error::Bug("a wide-light lobe pass tests its reach without the wide lights' cones".into())
            })?;
        }
        if let (Some(k), Some(slots)) = (keys, reach) {
            let tested = match &k.set.wide {
                Some(w) if variant.wide() => w.all.len(),
                _ => k.set.lights.len(),
            };
            if tested != slots {
                return Err(crate::Error::Bug(format!(
                    "a lobe pass tests the reach of {slots} lights of a table of {tested}"
                )));
            }
        }
        let residual = match (variant.key(), keys.and_then(|k| k.wide.as_ref()).filter(|_| variant.wide())) {
            (true, Some(w)) => &w.residual,
            (true, None) if variant.wide() => {
                return Err(crate::Error::Bug("a wide-light lobe pass on a map without wide lights".into()))
            }
            (true, None) => env.residual().0,
            (false, _) => &env.texture,
        };
        // The material's uniform buffer stands in (it is longer than the light set's block).
        let lights = job.light_samples.filter(|_| variant.has_lights()).unwrap_or(LightSet {
            buffer: job.material,
            offset: 0,
            count: 0,
            counts: [0.0; 2],
            ends: None,
        });
        Ok(Reads { cones, texels, residual, lights })
    }

    /// The light set's ends fit the variant: rising light by light to the set's count at the last of
    /// the reach test's lights (`LightSet::light_ends`' padding), and whole sets of strips for each
    /// oriented light.
    fn check(&self, variant: Variant) -> Result<()> {
        let LightSet { count: m, ends, .. } = self.lights;
        if let (Reach::Tested { slots }, true) = (variant.reach(), variant.points()) {
            let slots = usize::from(slots);
            let fits = ends.is_some_and(|e| {
                e.windows(2).all(|w| w[0] <= w[1])
                    && e[slots - 1] == m
                    && e[MAX_LIGHTS - 1] == m
                    && (slots == 1 || e[slots - 2] < m)
            });
            if !fits {
                return Err(crate::Error::Bug(format!(
                    "a lobe pass tests its lights' reach with ends {ends:?} for {slots} lights of {m} points"
                )));
            }
        }
        if variant.strips() > 0 {
            // Each oriented light's rows are `ORIENTATIONS` sets of as many points.
            let n = usize::from(variant.strips());
            let sets = crate::scene::keylight::strips::ORIENTATIONS as u32;
            let fits = variant.points()
                && n <= MAX_LIGHTS
                && ends.is_some_and(|e| (0..n).all(|k| (e[k] - if k == 0 { 0 } else { e[k - 1] }) % sets == 0));
            if !fits {
                return Err(crate::Error::Bug(format!(
                    "a lobe pass runs {n} lights' strips with ends {ends:?} of {m} points"
                )));
            }
        }
        Ok(())
    }
}

/// A lobe pass's push constants: the frame's, with the lobe, its samples, the seed, the light set's
/// size and sample counts, the lod bias, where the pass writes and each light's end in the set.
fn push(frame: &super::gpu::Push, job: &Job<'_>, lights: &LightSet<'_>) -> super::gpu::LobePush {
    let cells = matches!(job.into, Into::Cells { .. });
    // A block's pixel takes at least one vector of 4 samples (fewer cost as much on llvmpipe):
    // a block of 4 pixels, so 1 sample a pixel on average.
    let samples = if cells { job.samples.max(super::denoise::SPARSE_MIN_SAMPLES) } else { job.samples };
    super::gpu::LobePush {
        params: [job.index, samples, job.seed, lights.count],
        mode: job.into.output().code(),
        lod_bias: if job.into == Into::Accum { KEY_LOD_BIAS } else { super::denoise::LOD_BIAS },
        light_counts: lights.counts,
        ends: lights.ends.unwrap_or([lights.count; MAX_LIGHTS]),
        frame: frame.frame,
    }
}

fn pipeline_name(v: &Variant) -> String {
    format!("lobe[{}]", v.tag())
}

fn build(raw: &ash::Device, cache: ash::vk::PipelineCache, v: &Variant) -> Result<Pipeline> {
    Pipeline::compute_on(raw, cache, crate::spirv!("lobe.comp"), &pipeline_name(v), 128, &v.constants().values())
}

fn panicked() -> crate::Error {
    crate::Error::Bug("the thread building a lobe pipeline panicked".into())
}

impl LobePass {
    pub fn new() -> LobePass {
        LobePass { pipelines: HashMap::new(), building: HashMap::new(), built: channel() }
    }

    fn insert(&mut self, ctx: &Context, v: Variant, p: Pipeline) {
        p.name(ctx, &pipeline_name(&v));
        self.pipelines.insert(v, p);
    }

    /// Takes in the pipelines the building threads have sent (the first error, after taking all).
    pub fn collect(&mut self, ctx: &Context) -> Result<()> {
        let mut failed = None;
        // Threads that have ended: each sent its pipeline (or, panicking, an error) before it ended.
        let ended: Vec<Variant> = self.building.iter().filter(|(_, t)| t.is_finished()).map(|(v, _)| *v).collect();
        for v in ended {
            if self.building.remove(&v).expect("listed above").join().is_err() && failed.is_none() {
                failed = Some(panicked());
            }
        }
        while let Ok((v, p)) = self.built.1.try_recv() {
            if let Some(thread) = self.building.remove(&v) {
                // It has sent its one message; what is left of it is returning.
                let _ = thread.join();
            }
            match p {
                Ok(p) => self.insert(ctx, v, p),
                Err(e) => failed = failed.or(Some(e)),
            }
        }
        failed.map_or(Ok(()), Err)
    }

    /// Builds the pipelines of `variants` not built yet, waiting for those being built.
    pub fn prepare(&mut self, ctx: &Context, variants: &[Variant]) -> Result<()> {
        for v in variants {
            if let Some(thread) = self.building.remove(v) {
                // It sends its pipeline before it returns.
                let _ = thread.join();
            }
        }
        self.collect(ctx)?;
        for v in variants {
            if !self.pipelines.contains_key(v) {
                let p = build(ctx.raw(), ctx.pipeline_cache.raw, v)?;
                self.insert(ctx, *v, p);
            }
        }
        Ok(())
    }

    /// Builds `v` on a thread of its own unless one already is.
    fn spawn(&mut self, ctx: &Context, v: Variant, notify: &Notify) -> Result<()> {
        if self.building.contains_key(&v) {
            return Ok(());
        }
        let (raw, variant, notify, sender) = (ctx.raw().clone(), v, notify.clone(), self.built.0.clone());
        let cache = ctx.pipeline_cache.raw;
        // The device outlives the thread: `destroy` joins it before the renderer lets the device go.
        let thread = std::thread::Builder::new()
            .name("lobe pipeline".into())
            .spawn(move || {
                let done = Done { variant, sender, notify };
                let _ = done.sender.send((variant, build(&raw, cache, &variant)));
            })
            .map_err(|source| crate::Error::System { what: "cannot start a thread to build a pipeline", source })?;
        self.building.insert(v, thread);
        Ok(())
    }

    /// Whether every variant of `variants` can be drawn: its own pipeline is built or, for a variant
    /// whose output depends on the view's size ([`Variant::outputs_vary`]), the one of every output
    /// ([`Output::Any`]), which stands in until it is. Missing pipelines are started on threads of
    /// their own (one per variant), each calling `notify` once its pipeline can be collected: the
    /// stand-in first (what a frame waits for, once for all sizes), then, once it is built, the
    /// variant's own (what later frames take).
    pub fn ready(&mut self, ctx: &Context, variants: &[Variant], notify: &Notify) -> Result<bool> {
        self.collect(ctx)?;
        let mut ready = true;
        let mut wanted = Vec::new();
        for v in variants {
            if self.pipelines.contains_key(v) {
                continue;
            }
            let any = v.any_output();
            if v.outputs_vary() && self.pipelines.contains_key(&any) {
                wanted.push(*v);
            } else {
                ready = false;
                wanted.push(if v.outputs_vary() { any } else { *v });
            }
        }
        for v in wanted {
            self.spawn(ctx, v, notify)?;
        }
        Ok(ready)
    }

    /// Adds one lobe as `job` says into the image.
    pub fn record(&self, rec: &Recording<'_>, variant: Variant, job: &Job<'_>) -> Result<()> {
        if variant.output != Output::Any && variant.output != job.into.output() {
            return Err(crate::Error::Bug(format!("lobe pipeline {variant:?} does not write {:?}", job.into)));
        }
        // The variant's own pipeline, or (the editor's, while that one is built) the one of every output.
        let Some(pipeline) = self.pipelines.get(&variant).or_else(|| self.pipelines.get(&variant.any_output())) else {
            return Err(crate::Error::Bug(format!("lobe pipeline {variant:?} was not prepared")));
        };
        let env = rec.env()?;
        let reads = Reads::of(env, variant, job)?;
        reads.check(variant)?;
        let t = rec.targets;
        // A sparse pass runs over the blocks' list, the others over the pixels'.
        let cells = matches!(job.into, Into::Cells { .. });
        let list = if cells { &t.blocks } else { &t.pixels };
        let set = rec.set(
            pipeline,
            &[
                Binding::StorageImageRead(&t.normal),
                Binding::StorageImage(match job.into {
                    Into::Accum => &t.accum,
                    Into::Rough => &t.rough,
                    Into::Cells { .. } => &t.cells,
                }),
                // `key` reads its residual within the nearest mip level (`environment::KEY_MIPMAP`).
                Binding::Sampled(reads.residual, if variant.key() { env.key_sampler } else { env.sampler }),
                Binding::StorageRead(job.material),
                Binding::StorageRead(job.halton),
                Binding::Sampled(reads.texels, env.sampler),
                Binding::StorageRead(reads.cones),
                Binding::Uniform(reads.lights.buffer, reads.lights.offset, super::gpu::LIGHT_SET_UNIFORM_BYTES as u64),
                Binding::StorageRead(list),
                // A filtered pass's light term (read only by those; a sparse one's a block into
                // `cells_light`).
                Binding::StorageImage(match job.into {
                    Into::Cells { pixel_lights: false } => &t.cells_light,
                    _ => &t.accum,
                }),
            ],
        )?;
        rec.dispatch_over(list, pipeline, set, &push(&rec.push, job, &reads.lights));
        Ok(())
    }

    pub fn destroy(mut self, ctx: &Context) {
        for (_, thread) in self.building.drain() {
            let _ = thread.join();
        }
        while let Ok((_, p)) = self.built.1.try_recv() {
            if let Ok(p) = p {
                p.destroy(ctx);
            }
        }
        for (_, p) in self.pipelines {
            p.destroy(ctx);
        }
    }
}

impl Default for LobePass {
    fn default() -> Self {
        Self::new()
    }
}
