//! The lobe passes of a frame: which lobes get one (non-zero albedo), each one's pipeline variant,
//! how it sees the map's key lights (MIS samples, their points, tiles or strips, the wide lights,
//! the reach test) and where it writes (the accumulation image or the filter's images).

use super::lights::{Cut, KeyLightSet, TileLights, WideLightSet};
use super::variant::{Into, KeyLights, Lookup, Output, Reach, Variant};
use super::{Plan, Request};
use crate::brdf::Lobe;
use crate::render::lobe;
use crate::render::{denoise, Estimator};
use crate::scene::keylight::tiles::{max_points, tile_alpha, TileSet};
use crate::scene::keylight::{quadrature_fits, KeyLight, MAX_LIGHTS};

/// How a `key` lobe pass sees the map's key lights.
#[derive(Clone, Debug, PartialEq)]
pub enum LobeLights {
    /// No light term: not a `key` frame, or a map without key lights.
    None,
    /// The frame's light samples, by MIS.
    Samples,
    /// The key lights' own quadrature points.
    Points,
    /// The key and wide lights' quadrature points.
    WidePoints,
    /// Tiles or strips of the lights (`keylight::tiles`, `keylight::strips`).
    Tiles(TileSet),
}

/// One lobe pass: lobe `index` drawn with `variant` into `into`, seeing the lights as `lights` say.
#[derive(Clone, Debug, PartialEq)]
pub struct LobeStep {
    pub index: u32,
    pub variant: Variant,
    pub into: Into,
    pub lights: LobeLights,
}

impl LobeStep {
    /// The pass's name in timings and plans: `lobe3[aniso,rot]`, with a tile set's size.
    pub fn name(&self) -> String {
        let (i, tag) = (self.index, self.variant.tag());
        match &self.lights {
            LobeLights::Tiles(t) if t.oriented > 0 => format!("lobe{i}[{tag} {}]", t.points_seen()),
            LobeLights::Tiles(t) => format!("lobe{i}[{tag},tiles {}]", t.rows.len()),
            _ => format!("lobe{i}[{tag}]"),
        }
    }
}

/// The lobe passes of the frame `r` asks for, in lobe order; what it leaves out goes to `p`.
pub fn choose(r: &Request, sparse: bool, p: &mut Plan) -> Vec<LobeStep> {
    let key = r.estimator == Estimator::Key;
    let lookup = match r.estimator {
        Estimator::Key => Lookup::Residual,
        Estimator::Plain => Lookup::Level0,
        _ => Lookup::Prefiltered,
    };
    let lights = r.lights.filter(|_| key);
    if key && lights.is_none() {
        p.leave_out("light term", "the map has no key lights");
    }
    let floor = denoise::min_alpha(sparse, r.width, r.height);
    let mut steps = Vec::new();
    for (i, l) in r.material.lobes.iter().enumerate() {
        if l.albedo.iter().all(|&a| a == 0.0) {
            p.leave_out(format!("lobe{i}"), "its albedo is 0");
            continue;
        }
        let base = Variant { vec4: !r.options.scalar_lobes, ..Variant::of(r.material, l, lookup) };
        let (mut variant, tiles) = match lights {
            Some(k) => key_lights(r, l, base, k),
            None => (base, None),
        };
        // Where the pass writes: the rough lobes the filter takes, sampled once a 2 × 2 block in
        // sparse frames.
        let mis_lights = matches!(variant.lights, KeyLights::Samples { .. });
        let filtered = variant.key() && denoise::fits(l, mis_lights, floor);
        let into = match (filtered, sparse) {
            (false, _) => Into::Accum,
            (true, true) => Into::Cells { pixel_lights: denoise::pixel_lights(l, r.width, r.height) },
            (true, false) => Into::Rough,
        };
        // The editor's stand-in (`LobePass::ready`) covers every lobe that may leave `Accum`.
        debug_assert!(into == Into::Accum || variant.outputs_vary(), "{variant:?} writes {into:?}");
        variant.output = if r.options.any_output_lobes { Output::Any } else { into.output() };
        let lights = match (variant.lights, tiles) {
            (KeyLights::None, _) => LobeLights::None,
            (KeyLights::Samples { .. }, _) => LobeLights::Samples,
            (KeyLights::Points { .. }, Some(t)) => LobeLights::Tiles(t),
            (KeyLights::Points { wide: true, .. }, None) => LobeLights::WidePoints,
            (KeyLights::Points { wide: false, .. }, None) => LobeLights::Points,
        };
        steps.push(LobeStep { index: i as u32, variant, into, lights });
    }
    steps
}

/// A `key` lobe's variant on a map with key lights `k`, and the tiles it sees them as.
fn key_lights(r: &Request, l: &Lobe, base: Variant, k: &KeyLightSet) -> (Variant, Option<TileSet>) {
    let fits = |lights: &[KeyLight]| quadrature_fits(lights, l.alpha_x, l.alpha_y);
    let whole = fits(&k.lights);
    let pays = lobe::reach_test_pays(r.material, l);
    let reach = pays.then(|| lobe::reach_half_angles(r.material.normalization, l));
    let wide_lights = k.wide.as_ref();
    // A lobe that sees the wide lights as points too takes them off its residual.
    let mut wide = whole && wide_lights.is_some_and(|w| fits(&w.lights));
    let mut tile_set = None;
    if !wide {
        let cut = Cutter::new(l, base, k);
        // The key and wide lights together first (also for a lobe that sees the key lights as
        // points: those are then their own one tile), where the reach test (if it pays) sees them
        // all; their tiles take the wide lights off the residual.
        let wide_tiles = r.spp >= lobe::WIDE_TILES_MIN_SPP;
        let tested = |w: &&WideLightSet| !pays || w.reach_testable();
        if let Some(w) = wide_lights.filter(|w| wide_tiles && tested(w)) {
            tile_set = cut.cut(max_points(&w.all, reach), TileLights::KeyAndWide);
        }
        // Otherwise a lobe wide enough sees the wide lights as their own points: its key lights'
        // tiles within their own allowance, and four points for each wide light (the allowance of
        // the key and wide lights together, which counts the wide lights' share of the pixels in
        // reach, would be smaller).
        let wide_points = |w: &&WideLightSet| tested(w) && lobe::sees_wide_lights_as_points(l, &w.lights, r.spp);
        let key_points = max_points(&k.lights, reach);
        if let Some(w) = wide_lights.filter(|w| tile_set.is_none() && wide_points(w)) {
            tile_set = cut.cut(key_points + 4 * w.lights.len(), TileLights::KeyAndWidePoints);
        }
        wide = tile_set.is_some();
        if tile_set.is_none() && !whole {
            tile_set = cut.cut(key_points, TileLights::Key);
        }
    }
    let tiled = tile_set.is_some();
    let points = whole || tiled;
    let tests_reach = r.options.light_reach_test && pays && (!points || tiled);
    // The lights of the cone table the test reads (`LobePass::record`).
    let reach = match (tests_reach, wide) {
        (false, _) => Reach::Untested,
        (true, true) => Reach::Tested { slots: slots(k.wide.as_ref().map_or(MAX_LIGHTS, |w| w.all.len())) },
        (true, false) => Reach::Tested { slots: slots(k.lights.len()) },
    };
    let lights = if points {
        KeyLights::Points { wide, reach, strips: tile_set.as_ref().map_or(0, |t| t.oriented as u8) }
    } else {
        KeyLights::Samples { reach }
    };
    (Variant { lights, ..base }, tile_set)
}

/// The cone table's slots for `n` lights (at least one, at most the table's).
fn slots(n: usize) -> u8 {
    n.clamp(1, MAX_LIGHTS) as u8
}

/// Cuts a lobe's lights into round tiles or, for an anisotropic lobe of one component, strips
/// across its narrow axis (`keylight::strips`), whichever runs fewer points a pixel.
struct Cutter<'a> {
    lights: &'a KeyLightSet,
    round: Cut,
    streak: Option<Cut>,
}

impl<'a> Cutter<'a> {
    fn new(l: &Lobe, base: Variant, lights: &'a KeyLightSet) -> Cutter<'a> {
        let round = Cut::Tiles(tile_alpha(l.alpha_x, l.alpha_y));
        let (narrow, broad) = (l.alpha_x.min(l.alpha_y), l.alpha_x.max(l.alpha_y));
        let streak = (!(base.shape.split || base.sym) && narrow < broad).then_some(Cut::Strips(narrow, broad));
        Cutter { lights, round, streak }
    }

    fn cut(&self, budget: usize, which: TileLights) -> Option<TileSet> {
        let round = self.lights.tiles(self.round, budget, which);
        let strips = self.streak.and_then(|c| self.lights.tiles(c, budget, which));
        match (round, strips) {
            (Some(t), Some(s)) if s.points_seen() >= t.points_seen() => Some(t),
            (t, s) => s.or(t),
        }
    }
}
