//! Records a frame's plan: each step's pass, timed under the step's name, with what it reads from
//! the frame (the material, the light samples, the lobes' tiles, the sample tables). Every choice
//! was made by the plan (`render::plan`); this only follows it.

use super::Recording;
use crate::error::{Error, Result};
use crate::render::environment::GpuKeyLights;
use crate::render::lobe::{self, LightSet};
use crate::render::mesh::GpuMesh;
use crate::render::plan::{LobeImages, LobeLights, LobeStep, Pass, Plan, Step};
use crate::render::{gpu, Passes};
use crate::vk::query::Timestamps;
use crate::vk::{barrier, Buffer};

/// A light set of `count` entries at `offset` of `buffer`, without per-light ends.
pub fn light_set(buffer: &Buffer, offset: u64, count: u32, counts: [f32; 2]) -> LightSet<'_> {
    LightSet { buffer, offset, count, counts, ends: None }
}

/// What the steps of one view record with.
pub struct StepRecorder<'a> {
    pub rec: Recording<'a>,
    pub passes: &'a Passes,
    pub material: &'a Buffer,
    /// The compensation tables' words and the kernels (`render::compensation::Tables`).
    pub compensation: [&'a Buffer; 2],
    /// The frame's light samples, where a lobe takes them by MIS.
    pub light_samples: Option<LightSet<'a>>,
    /// The lobes' tile sets, one uniform block each in the order of the plan's lobes.
    pub tiles: Option<&'a Buffer>,
    /// The map's key lights, in a `key` frame.
    pub keys: Option<&'a GpuKeyLights>,
    pub mesh: Option<&'a GpuMesh>,
    pub halton: Option<&'a Buffer>,
    pub sequence: Option<&'a Buffer>,
    pub view_proj: glam::Mat4,
    pub spp: u32,
    pub seed: u32,
}

fn missing(what: &str) -> Error {
    Error::Bug(format!("the frame's plan needs {what}, which the renderer did not make"))
}

impl StepRecorder<'_> {
    /// Records every step of `plan` in order, each timed under its name (a transfer clear untimed).
    pub fn record(&self, ts: &mut Timestamps, plan: &Plan) -> Result<()> {
        let (ctx, cmd) = (self.rec.ctx, self.rec.cmd);
        let mut tiles_seen = 0;
        for step in &plan.steps {
            if !step.timed() {
                self.step(step, &mut tiles_seen)?;
                continue;
            }
            ts.time(ctx, cmd, &step.name(), || self.step(step, &mut tiles_seen))?;
        }
        Ok(())
    }

    fn step(&self, step: &Step, tiles_seen: &mut usize) -> Result<()> {
        let (rec, p) = (&self.rec, self.passes);
        let (ctx, cmd, pool, targets) = (rec.ctx, rec.cmd, rec.pool, rec.targets);
        match &step.pass {
            Pass::Canvas => p.canvas.record(rec, self.material, self.compensation[0]),
            Pass::GBuffer { cull, start, background_blocks } => {
                let mesh = self.mesh.ok_or_else(|| missing("a mesh"))?;
                p.gbuffer.record(ctx, cmd, targets, mesh, &self.view_proj, *cull);
                p.compact.record(rec, *start)?;
                if *background_blocks {
                    p.background.record_blocks(rec)?;
                }
                Ok(())
            }
            Pass::RestoreBase => {
                targets.restore_base(ctx, cmd);
                Ok(())
            }
            Pass::Compact { diffuse } => p.compact.record(rec, crate::render::compact::Start::Here(*diffuse)),
            Pass::Background => p.background.record(rec),
            Pass::Diffuse { albedo, key } => p.diffuse.record(rec, *albedo, *key),
            Pass::SaveBase => {
                targets.save_base(ctx, cmd);
                Ok(())
            }
            Pass::Zero { images, by_compute } => {
                let images = match images {
                    LobeImages::Cells => vec![&targets.cells, &targets.cells_light],
                    LobeImages::Rough => vec![&targets.rough],
                };
                if *by_compute {
                    p.zero.record(ctx, cmd, pool, &images)
                } else {
                    for image in images {
                        image.clear_to_general(ctx, cmd, barrier::COMPUTE_READ_WRITE);
                    }
                    Ok(())
                }
            }
            Pass::Lobe(l) => self.lobe(l, tiles_seen),
            Pass::Denoise { min_alpha, sparse, diffuse } => {
                p.denoise.record(rec, *min_alpha, self.spp, *sparse, *diffuse)
            }
            Pass::Compensation { lights } => {
                let [tables, kernels] = self.compensation;
                p.compensation.record(rec, [self.material, tables, kernels], *lights)
            }
            Pass::Mis { offset, samples } => {
                let seq = self.sequence.ok_or_else(|| missing("the mis sequence"))?;
                p.mis.record(rec, *offset, *samples, [self.material, self.compensation[0]], seq)
            }
            Pass::Accumulate { first, samples } => {
                // The accumulate pass reads the frame's image outside the view's derived barriers.
                rec.hazards.flush(ctx, cmd);
                p.accumulate.record(ctx, cmd, pool, targets, *first, *samples)
            }
        }
    }

    /// One lobe pass, reading the light set its plan names.
    fn lobe(&self, l: &LobeStep, tiles_seen: &mut usize) -> Result<()> {
        let halton = self.halton.ok_or_else(|| missing("the sample table"))?;
        let light_samples = match &l.lights {
            LobeLights::None | LobeLights::Samples => self.light_samples,
            LobeLights::Points => self.keys.map(|k| light_set(&k.points, 0, 4 * k.set.lights.len() as u32, [0.0; 2])),
            LobeLights::WidePoints => {
                self.keys.and_then(|k| k.wide.as_ref()).map(|w| light_set(&w.points, 0, w.count, [0.0; 2]))
            }
            LobeLights::Tiles(t) => {
                let buffer = self.tiles.ok_or_else(|| missing("the lobes' tiles"))?;
                let at = *tiles_seen;
                *tiles_seen += 1;
                let offset = (at * gpu::LIGHT_SET_UNIFORM_BYTES) as u64;
                Some(LightSet {
                    ends: LightSet::light_ends(&t.ends),
                    ..light_set(buffer, offset, t.rows.len() as u32, [0.0; 2])
                })
            }
        };
        let job = lobe::Job {
            index: l.index,
            samples: self.spp,
            seed: self.seed,
            material: self.material,
            halton,
            light_samples,
            into: l.into,
        };
        self.passes.lobe.record(&self.rec, l.variant, &job)
    }
}
