//! `report error-vs-time`: for scenes (environment × material) and sample counts, each estimator's
//! GPU time (the whole frame, first command to last, every clear and copy included, its passes not
//! timed apart: `key` moves work
//! between passes that `fis` does elsewhere, so only whole frames compare; median of repeated frames
//! taken in rounds that interleave a scene's estimators and sample counts) and its error against the
//! converged CPU reference
//! (relative L1, RMSE and maximum absolute error over the object). References are cached on disk,
//! keyed by a hash of everything they depend on (`reference_cache`). Writes `error-vs-time.csv`, `error-vs-time.png`
//! (log–log: the error–time frontier of each estimator) and `error-vs-time.md` (the default `key`
//! estimator's error at `fis`-8's GPU time, its equal-error speed-ups and time to 2 %, the maps'
//! key-light decisions, and what a timed pass costs before any work on the device, measured after
//! the sweep: `render::peak::fixed_costs`; the older estimators against `fis` 8 spp and the `fis`
//! bias floor).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::reference::{self, Image};
use crate::render::peak::FixedCosts;
use crate::render::{Estimator, Renderer, Settings, View};
use crate::scene::{Camera, Mesh};

use super::plot::{loglog_png, Series};
use super::reference_cache::cached_reference;

/// What a run covers.
#[derive(Clone, Debug)]
pub struct Plan {
    pub envs: Vec<&'static str>,
    pub materials: Vec<&'static str>,
    pub spps: Vec<u32>,
    pub size: u32,
    pub reference_spp: u32,
    pub repeats: usize,
    /// The folder holding the maps `envs` names (`--hdri`; see `measure::hdri_dir`).
    pub hdri: PathBuf,
}

impl Plan {
    /// The full sweep: four maps, every report material, 1 … 256 samples, 64², reference at 4096.
    pub fn full() -> Plan {
        Plan {
            envs: vec!["sky.exr", "studio.exr", "venice.exr", "city.exr"],
            materials: super::report_materials().iter().map(|m| m.0).collect(),
            spps: vec![1, 2, 4, 8, 16, 32, 64, 128, 256],
            size: 64,
            reference_spp: 4096,
            // Nine timed frames a configuration: on lavapipe one configuration's frames spread by
            // tens of percent about their median, and `key`'s cheapest frame is near `fis`-8's on
            // most scenes, so the frontier goal is often decided by a few percent.
            repeats: 9,
            hdri: PathBuf::from(super::DEFAULT_HDRI_DIR),
        }
    }

    /// What CI runs: two maps, sharp, medium and rough paper lobes and two painted reciprocal
    /// materials (an anisotropic streak beside a rough lobe; lobes far off the mirror point), five
    /// sample counts, 32².
    pub fn quick() -> Plan {
        Plan {
            envs: vec!["studio.exr", "venice.exr"],
            materials: vec!["sharp-ward", "medium-gm", "rough-gm", "painted-aniso", "painted-tilted"],
            spps: vec![1, 4, 8, 32, 128],
            size: 32,
            reference_spp: 2048,
            repeats: 3,
            hdri: PathBuf::from(super::DEFAULT_HDRI_DIR),
        }
    }
}

impl Plan {
    /// Keeps only the named maps and materials (all of a kind when its list is empty); a name the
    /// plan does not hold is an error naming the option and what the plan holds.
    pub fn restrict(&mut self, maps: &[String], materials: &[String]) -> Result<()> {
        fn keep(option: &str, names: &[String], all: &mut Vec<&'static str>) -> Result<()> {
            if names.is_empty() {
                return Ok(());
            }
            if let Some(bad) = names.iter().find(|n| !all.contains(&n.as_str())) {
                return Err(Error::input(
                    option,
                    format!("{} is not in this sweep (it has {})", crate::fsio::quote(bad), all.join(", ")),
                ));
            }
            all.retain(|a| names.iter().any(|n| n == a));
            Ok(())
        }
        keep("--maps", maps, &mut self.envs)?;
        keep("--materials", materials, &mut self.materials)
    }

    /// Renders the sweep's images `side` pixels square (`--size`): from [`MIN_SIDE`] to
    /// [`MAX_SIDE`], else an error naming the option and the range.
    pub fn resize(&mut self, side: u32) -> Result<()> {
        if !(MIN_SIDE..=MAX_SIDE).contains(&side) {
            return Err(Error::input("--size", format!("{side} is outside {MIN_SIDE} to {MAX_SIDE} pixels")));
        }
        self.size = side;
        Ok(())
    }
}

/// The smallest image side of a sweep (`--size`): the sphere still covers a few dozen pixels.
pub const MIN_SIDE: u32 = 8;
/// The largest: the full sweep's CPU references at 1024² take 4096 samples at each of a million
/// pixels, 44 times over.
pub const MAX_SIDE: u32 = 1024;

/// One row of the CSV.
#[derive(Clone, Debug)]
pub struct Row {
    pub env: String,
    pub material: String,
    pub estimator: Estimator,
    pub spp: u32,
    pub ms_median: f64,
    pub ms_min: f64,
    pub ms_max: f64,
    pub rel_l1: f64,
    pub rmse: f64,
    pub max_abs: f64,
}

impl Row {
    pub fn scene(&self) -> String {
        format!("{}/{}", self.env, self.material)
    }
}

/// Relative L1, RMSE and maximum absolute error over the pixels both images cover.
pub fn errors(a: &Image, b: &Image) -> (f64, f64, f64) {
    let rel = reference::relative_l1(a, b).unwrap_or(f64::NAN);
    let (mut sq, mut max, mut n) = (0.0, 0.0f64, 0usize);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        if p[3] >= 0.5 && q[3] >= 0.5 {
            for c in 0..3 {
                let d = (p[c] as f64 - q[c] as f64).abs();
                sq += d * d;
                max = max.max(d);
                n += 1;
            }
        }
    }
    (rel, if n > 0 { (sq / n as f64).sqrt() } else { f64::NAN }, max)
}

/// Frames over which the summary's fixed costs of a timed pass are measured (after the sweep).
pub const FIXED_COST_FRAMES: usize = 15;

/// Per map name, the `key` estimator's key-light decision (`KeyLightSummary::describe`).
pub type Decisions = Vec<(String, String)>;

/// Runs the plan; `progress` shows a bar over the scenes. Returns the rows and, per map, the `key`
/// estimator's key-light decision.
pub fn run(renderer: &mut Renderer, plan: &Plan, out: &Path, progress: bool) -> Result<(Vec<Row>, Decisions)> {
    // The sweep reads whole frames only: its frames time no pass (`Renderer::time_passes`), so
    // that no estimator pays for timestamps by its count of passes.
    let time_passes = std::mem::replace(&mut renderer.time_passes, false);
    let result = sweep(renderer, plan, out, progress);
    renderer.time_passes = time_passes;
    result
}

fn sweep(renderer: &mut Renderer, plan: &Plan, out: &Path, progress: bool) -> Result<(Vec<Row>, Decisions)> {
    let cache = out.join("cache");
    let mesh = Mesh::sphere();
    renderer.set_mesh(&mesh)?;
    let camera = Camera::default();
    let all = super::report_materials();
    let bar = progress.then(|| {
        let b = indicatif::ProgressBar::new((plan.envs.len() * plan.materials.len()) as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("error-vs-time {bar:40} {pos}/{len} scenes, {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    let mut rows = Vec::new();
    let mut decisions = Vec::new();
    for env_name in &plan.envs {
        let env = super::environment(&plan.hdri, env_name)?;
        renderer.set_environment(&env)?;
        if let Some(k) = renderer.key_lights() {
            decisions.push((env_name.to_string(), k.describe()));
        }
        for mat_name in &plan.materials {
            let Some((_, m)) = all.iter().find(|(n, _)| n == mat_name) else {
                return Err(Error::Bug(format!(
                    "error-vs-time: the plan names {mat_name}, which is not a report material"
                )));
            };
            if let Some(b) = &bar {
                b.set_message(format!("{env_name}/{mat_name}"));
            }
            let reference = cached_reference(&cache, m, &env, &mesh, &camera, plan.size, plan.reference_spp)?;
            // Every (estimator, spp) of the scene: one frame first, not counted (drivers compile
            // pipelines on first use; the frames of one configuration are the same image), then the
            // timed rounds, interleaved, so that a slow spell of the machine falls on every
            // configuration alike instead of on whichever ran then.
            let configs: Vec<(Estimator, u32)> =
                Estimator::ALL.iter().flat_map(|&e| plan.spps.iter().map(move |&spp| (e, spp))).collect();
            let settings = |(estimator, spp): (Estimator, u32)| Settings {
                width: plan.size,
                height: plan.size,
                spp,
                estimator,
                view: View::Mesh,
                camera: camera.clone(),
                light: glam::DVec3::Z,
                intensity: 1.0,
                backdrop_blur: 0.0,
            };
            let mut images = Vec::with_capacity(configs.len());
            for &c in &configs {
                // Ctrl-C (the CLI installs the handler): stop before the next measurement.
                if crate::interrupt::requested() {
                    return Err(Error::input("error-vs-time", "interrupted"));
                }
                images.push(renderer.render(m, &settings(c))?.image);
            }
            // The rounds run the list backwards and forwards in turn (the first one backwards,
            // after the untimed frames' forward run), so that each frame follows a neighbour of its
            // own configuration in the list, and never the longest frame (`mis` at the most
            // samples, tens of milliseconds) of a run in the other order: a frame after that one
            // runs slower on lavapipe.
            let rounds = plan.repeats.max(1);
            let mut times = vec![Vec::new(); configs.len()];
            for round in 0..rounds {
                let order: Vec<usize> =
                    if round % 2 == 0 { (0..configs.len()).rev().collect() } else { (0..configs.len()).collect() };
                for k in order {
                    let c = configs[k];
                    if crate::interrupt::requested() {
                        return Err(Error::input("error-vs-time", "interrupted"));
                    }
                    times[k].push(renderer.render(m, &settings(c))?.frame_ms);
                }
            }
            for (((estimator, spp), image), times) in configs.into_iter().zip(images).zip(times) {
                let (rel_l1, rmse, max_abs) = errors(&image, &reference);
                let (ms_median, ms_min, ms_max) = super::stats(&times);
                rows.push(Row {
                    env: env_name.to_string(),
                    material: mat_name.to_string(),
                    estimator,
                    spp,
                    ms_median,
                    ms_min,
                    ms_max,
                    rel_l1,
                    rmse,
                    max_abs,
                });
            }
            if let Some(b) = &bar {
                b.inc(1);
            }
        }
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Ok((rows, decisions))
}

pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from("env,material,estimator,spp,gpu_ms_median,gpu_ms_min,gpu_ms_max,rel_l1,rmse,max_abs\n");
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{:.4},{:.4},{:.4},{:.6},{:.6},{:.6}\n",
            r.env,
            r.material,
            r.estimator.name(),
            r.spp,
            r.ms_median,
            r.ms_min,
            r.ms_max,
            r.rel_l1,
            r.rmse,
            r.max_abs
        ));
    }
    s
}

/// Where along a measured curve `(spp, ms, error)` the error first reaches `target`, interpolated
/// log–log between measured points: `(spp, ms)`, or `None` when it never does.
pub fn reach(curve: &[(u32, f64, f64)], target: f64) -> Option<(f64, f64)> {
    for (k, &(spp, ms, e)) in curve.iter().enumerate() {
        if e <= target {
            if k == 0 {
                return Some((spp as f64, ms));
            }
            let (s0, m0, e0) = curve[k - 1];
            let t = if e0 > e { (e0.ln() - target.ln()) / (e0.ln() - e.ln()) } else { 1.0 };
            let lerp = |a: f64, b: f64| (a.ln() + t * (b.ln() - a.ln())).exp();
            return Some((lerp(s0 as f64, spp as f64), lerp(m0.max(1e-9), ms.max(1e-9))));
        }
    }
    None
}

fn curve(rows: &[Row], scene: &str, estimator: Estimator) -> Vec<(u32, f64, f64)> {
    curve_timed(rows, scene, estimator, |r| r.ms_median)
}

/// A scene's curve `(spp, ms, error)` for one estimator, its times read by `time`.
fn curve_timed(rows: &[Row], scene: &str, estimator: Estimator, time: fn(&Row) -> f64) -> Vec<(u32, f64, f64)> {
    let mut c: Vec<_> = rows
        .iter()
        .filter(|r| r.scene() == scene && r.estimator == estimator)
        .map(|r| (r.spp, time(r), r.rel_l1))
        .collect();
    c.sort_by_key(|p| p.0);
    c
}

/// The scenes of `rows`, in their order (a scene's rows are consecutive).
fn scenes(rows: &[Row]) -> Vec<String> {
    let mut scenes: Vec<String> = rows.iter().map(Row::scene).collect();
    scenes.dedup();
    scenes
}

/// The error target for the default estimator at `fis`-8's GPU time.
pub const GOAL_ERROR: f64 = 0.08;

/// The frontier goal over the scenes of `rows`: how many have `key`'s error at `fis`-8's GPU time
/// ([`error_at`], as the summary's table) within [`GOAL_ERROR`], each configuration's time read by
/// `time` (its median frame, or its fastest: the frames' noise decides scenes within a tenth of a
/// millisecond); and how many scenes there are.
pub fn goal_count(rows: &[Row], time: fn(&Row) -> f64) -> (usize, usize) {
    let scenes = scenes(rows);
    let within = scenes
        .iter()
        .filter(|scene| {
            let fis = curve_timed(rows, scene, Estimator::Fis, time);
            let key = curve_timed(rows, scene, Estimator::Key, time);
            fis.iter().find(|p| p.0 == 8).and_then(|&(_, ms, _)| error_at(&key, ms)).is_some_and(|e| e <= GOAL_ERROR)
        })
        .count();
    (within, scenes.len())
}

/// The best error a measured curve `(spp, ms, error)` reaches within GPU time `ms`: along its
/// frontier, interpolated log–log between the measured points around `ms`; past its dearest frame,
/// the frontier's last error (every frame of the curve then costs less than `ms`); `None` where
/// `ms` lies below its cheapest frame.
pub fn error_at(curve: &[(u32, f64, f64)], ms: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = curve.iter().map(|&(_, t, e)| (t.max(1e-9), e.max(1e-12))).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Time is noisy: keep each point's best error up to its time (the frontier, falling with time).
    let mut frontier: Vec<(f64, f64)> = Vec::new();
    for (t, e) in pts {
        let best = frontier.last().map_or(e, |l| l.1.min(e));
        frontier.push((t, best));
    }
    let first = frontier.first()?;
    if ms < first.0 {
        return None;
    }
    for w in frontier.windows(2) {
        let ((t0, e0), (t1, e1)) = (w[0], w[1]);
        if ms <= t1 {
            let s = if t1 > t0 { (ms.ln() - t0.ln()) / (t1.ln() - t0.ln()) } else { 1.0 };
            return Some((e0.ln() + s * (e1.ln() - e0.ln())).exp());
        }
    }
    frontier.last().map(|l| l.1)
}

/// The Markdown summary: per scene, `fis` at 8 spp against the default `key` estimator at the same
/// GPU time, `key`'s equal-error speed-up over each older estimator, the time `key` needs for 2 %,
/// the goal's count, what a timed pass costs before any work (`fixed`: measured, or why not), and
/// the map's key-light decision; then the older estimators against `fis` 8 spp.
pub fn summary(
    rows: &[Row],
    plan: &Plan,
    device: &str,
    decisions: &[(String, String)],
    fixed: &std::result::Result<FixedCosts, String>,
) -> String {
    let scenes = scenes(rows);
    let mut s = format!(
        "# Error against GPU time\n\nDevice: {device}. Sphere, {0}x{0}, default camera; reference: CPU MIS at {1} spp. \
         Error: relative L1 over the object. GPU ms: the whole frame, first command to last, its passes not timed apart (median of {2} frames, in rounds interleaving each scene's estimators and sample counts, backwards and forwards in turn).\n\n",
        plan.size, plan.reference_spp, plan.repeats
    );
    s.push_str("## The default estimator (`key`)\n\n");
    s.push_str("| scene | fis 8 spp: error, ms | key at that ms: error | key 8 spp: error, ms | speed-up at key-8's error over fis / plain / mis | key to 2 %: spp, ms |\n");
    s.push_str("| --- | --- | --- | --- | --- | --- |\n");
    for scene in &scenes {
        let fis = curve(rows, scene, Estimator::Fis);
        let key = curve(rows, scene, Estimator::Key);
        let Some(&(_, fms, fe)) = fis.iter().find(|p| p.0 == 8).or(fis.last()) else { continue };
        let Some(&(_, kms, ke)) = key.iter().find(|p| p.0 == 8).or(key.last()) else { continue };
        let dearest = key.iter().max_by(|a, b| a.1.total_cmp(&b.1));
        let at = match (error_at(&key, fms), dearest) {
            // Past key's dearest frame: the best error of its frames, each cheaper than fis-8's.
            (Some(e), Some(&(spp, ms, _))) if fms > ms => {
                format!("{e:.4} (every key frame cheaper; dearest {spp} spp, {ms:.2} ms)")
            }
            (Some(e), _) => format!("{e:.4}"),
            (None, _) => match key.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
                Some(&(spp, ms, _)) => format!("— (key's cheapest frame: {spp} spp, {ms:.2} ms)"),
                None => "—".to_string(),
            },
        };
        let speedups: Vec<String> = [Estimator::Fis, Estimator::Plain, Estimator::Mis]
            .iter()
            .map(|&e| match reach(&curve(rows, scene, e), ke) {
                Some((_, ms)) => format!("{:.1}×", ms / kms.max(1e-9)),
                None => format!("> {:.0}×", curve(rows, scene, e).last().map_or(0.0, |p| p.1) / kms.max(1e-9)),
            })
            .collect();
        let two = match reach(&key, 0.02) {
            Some((spp, ms)) => format!("{spp:.0}, {ms:.2}"),
            None => format!("not within {} spp", plan.spps.last().copied().unwrap_or(0)),
        };
        s.push_str(&format!(
            "| {scene} | {fe:.4}, {fms:.2} | {at} | {ke:.4}, {kms:.2} | {} | {two} |\n",
            speedups.join(" / ")
        ));
    }
    let (by_median, n) = goal_count(rows, |r| r.ms_median);
    let (by_fastest, _) = goal_count(rows, |r| r.ms_min);
    s.push_str(&format!(
        "\n**The frontier goal, `key` within {:.0} % at `fis`-8's GPU time: {by_median} of {n} scenes** by the medians above; {by_fastest} of {n} with each configuration's fastest frame instead.\n",
        GOAL_ERROR * 100.0
    ));
    s.push_str(&match fixed {
        Ok(f) => format!(
            "\nWhat a timed pass costs before any work on this device, in the same run (`render::peak::fixed_costs`, median of {} frames): a timed region with nothing in it {:.3} ms, with one dispatch that does next to nothing (one workgroup; and the barrier after it) {:.3} ms, with two {:.3} ms. At this size that is much of every frame's time: `fis` records one lobe dispatch, `key` one per lobe, and a lobe it filters two more (`render::denoise`).\n",
            f.frames, f.empty, f.one_dispatch, f.two_dispatches
        ),
        Err(e) => format!("\nWhat a timed pass costs before any work on this device could not be measured: {e}\n"),
    });
    s.push_str("\n`key at that ms` interpolates key's error–time frontier (log–log) at fis-8's GPU time, or, where fis-8 takes longer than every key frame, gives the best error of key's frames; `—` where key's cheapest frame costs more. A speed-up is the time an older estimator needs to reach key-8's error (interpolated along its curve) over key-8's time; `> N×` where it never does within the sweep (N: its longest run over key-8's time).\n\n");
    if !decisions.is_empty() {
        s.push_str("Key lights per map (`key` splits these off; a map without one gets no light term):\n\n");
        for (map, d) in decisions {
            s.push_str(&format!("- {map}: {d}\n"));
        }
        s.push('\n');
    }
    s.push_str("## The paper's estimator and the others\n\n");
    s.push_str("| scene | fis 8 spp: error, ms | plain to match: spp, ms, speed-up | mis to match: spp, ms, speed-up | fis floor: error (from spp) |\n");
    s.push_str("| --- | --- | --- | --- | --- |\n");
    for scene in &scenes {
        let fis = curve(rows, scene, Estimator::Fis);
        let Some(&(_, fms, fe)) = fis.iter().find(|p| p.0 == 8).or(fis.last()) else { continue };
        let matched = |e: Estimator| match reach(&curve(rows, scene, e), fe) {
            Some((spp, ms)) => format!("{spp:.0}, {ms:.2}, {:.1}×", ms / fms.max(1e-9)),
            None => format!("not within {} spp", plan.spps.last().copied().unwrap_or(0)),
        };
        let floor = fis.iter().map(|p| p.2).fold(f64::MAX, f64::min);
        let from = fis.iter().find(|p| p.2 <= floor * 1.05).map_or(0, |p| p.0);
        s.push_str(&format!(
            "| {scene} | {fe:.4}, {fms:.2} | {} | {} | {floor:.4} ({from}) |\n",
            matched(Estimator::Plain),
            matched(Estimator::Mis)
        ));
    }
    s.push_str("\n`speed-up` is the matching estimator's GPU ms over fis's at 8 spp (how many times longer it runs for the same error). The fis floor is its smallest error over the sweep and the first sample count within 5 % of it; where that is the largest count, fis had not stopped improving within the sweep (its lod shrinks as the sample count grows, so its prefiltering bias shrinks too).\n");
    s
}

/// The log–log plot: one line per scene and estimator, coloured by estimator.
pub fn plot(rows: &[Row], device: &str) -> Result<Vec<u8>> {
    let scenes = scenes(rows);
    let mut series = Vec::new();
    for scene in &scenes {
        for e in Estimator::ALL {
            let points = curve(rows, scene, e).into_iter().map(|(_, ms, err)| (ms, err)).collect();
            let colour = match e {
                Estimator::Fis => 0,
                Estimator::Plain => 1,
                Estimator::Mis => 2,
                Estimator::Key => 3,
            };
            series.push(Series { label: e.name().to_string(), colour, points });
        }
    }
    loglog_png(
        &format!("error against GPU time ({device})"),
        "GPU ms (whole frame)",
        "relative L1 error",
        &series,
        (1100, 760),
    )
}

/// Runs the plan and writes the CSV, plot and summary into `out`; a missing map is refused before
/// anything is written.
pub fn report(renderer: &mut Renderer, plan: &Plan, out: &Path, progress: bool) -> Result<(Vec<Row>, Vec<PathBuf>)> {
    super::require_maps(&plan.hdri, &plan.envs)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let (rows, decisions) = run(renderer, plan, out, progress)?;
    // Measured after the sweep; a failure here is stated in the summary rather than losing the sweep.
    let fixed = crate::render::peak::fixed_costs(renderer, FIXED_COST_FRAMES).map_err(|e| e.to_string());
    let device = renderer.device_name().to_string();
    let files = vec![out.join("error-vs-time.csv"), out.join("error-vs-time.png"), out.join("error-vs-time.md")];
    // All three as one step: every temporary file is written before the first rename.
    let (csv, png, md) = (csv(&rows), plot(&rows, &device)?, summary(&rows, plan, &device, &decisions, &fixed));
    crate::fsio::write_all_atomic(&[(&files[0], csv.as_bytes()), (&files[1], &png), (&files[2], md.as_bytes())])?;
    Ok((rows, files))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(material: &str, estimator: Estimator, spp: u32, median: f64, min: f64, rel_l1: f64) -> Row {
        Row {
            env: "m.exr".into(),
            material: material.into(),
            estimator,
            spp,
            ms_median: median,
            ms_min: min,
            ms_max: median,
            rel_l1,
            rmse: 0.0,
            max_abs: 0.0,
        }
    }

    /// A scene whose `key` frames are cheaper than `fis`-8 by the medians but dearer by the fastest
    /// frames counts in the first reading only; one over the error target in neither; one whose
    /// every `key` frame is cheaper than `fis`-8 counts by `key`'s best error.
    #[test]
    fn the_goal_is_counted_by_medians_and_by_fastest_frames() {
        let rows = vec![
            row("a", Estimator::Fis, 8, 1.0, 0.5, 0.4),
            row("a", Estimator::Key, 1, 0.9, 0.6, 0.05),
            row("a", Estimator::Key, 2, 1.2, 0.7, 0.04),
            row("b", Estimator::Fis, 8, 1.0, 1.0, 0.4),
            row("b", Estimator::Key, 1, 0.5, 0.5, 0.2),
            row("b", Estimator::Key, 2, 2.0, 2.0, 0.05),
        ];
        // b: at 1.0 ms its frontier lies between 0.2 and 0.05, log–log: 0.1.
        assert_eq!(goal_count(&rows, |r| r.ms_median), (1, 2));
        assert_eq!(goal_count(&rows, |r| r.ms_min), (0, 2));
        let e = error_at(&curve(&rows, "m.exr/b", Estimator::Key), 1.0).unwrap();
        assert!((e - 0.1).abs() < 1e-12, "{e}");
        // c: every key frame costs less than fis-8's, so key's best error counts (0.03, its
        // 2-spp frame, not its dearest); d: the same times, but no key frame within the target.
        let mut more = rows.clone();
        more.extend([
            row("c", Estimator::Fis, 8, 3.0, 3.0, 0.4),
            row("c", Estimator::Key, 1, 1.0, 1.0, 0.09),
            row("c", Estimator::Key, 2, 2.0, 2.0, 0.03),
            row("c", Estimator::Key, 4, 2.5, 2.5, 0.05),
            row("d", Estimator::Fis, 8, 3.0, 3.0, 0.4),
            row("d", Estimator::Key, 1, 1.0, 1.0, 0.2),
            row("d", Estimator::Key, 2, 2.0, 2.0, 0.09),
        ]);
        assert_eq!(goal_count(&more, |r| r.ms_median), (2, 4));
        let c = error_at(&curve(&more, "m.exr/c", Estimator::Key), 3.0);
        assert_eq!(c, Some(0.03));
        assert_eq!(error_at(&curve(&more, "m.exr/c", Estimator::Key), 0.5), None);
        let md = summary(&more, &Plan::quick(), "test", &[], &Err("not measured".into()));
        assert!(md.contains("| 0.0300 (every key frame cheaper; dearest 4 spp, 2.50 ms) |"), "{md}");
    }
}
