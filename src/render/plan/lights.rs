//! The key lights as a frame's plan sees them: the lights a map's `key` estimator splits off, the
//! wide lights beside them, and the tiles or strips a lobe narrower than they are cuts them into
//! (`keylight::tiles`, `keylight::strips`), made once per map and kept. Pure CPU data: the GPU
//! buffers that hold the same lights are `render::environment::GpuKeyLights`.

use std::cell::RefCell;
use std::collections::HashMap;

use crate::scene::keylight::tiles::{self, TileSet};
use crate::scene::keylight::{self, strips, KeyLight};

/// Which lights a lobe's tiles are made of ([`KeyLightSet::tiles`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TileLights {
    /// The key lights.
    Key,
    /// The key and wide lights together ([`WideLightSet::all`]).
    KeyAndWide,
    /// The key lights' tiles, then each wide light as its own four points
    /// (`lobe::sees_wide_lights_as_points`).
    KeyAndWidePoints,
}

/// How a lobe's tiles cut the lights ([`KeyLightSet::tiles`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cut {
    /// Round tiles for a lobe of this roughness (`keylight::tiles::tile_alpha`).
    Tiles(f64),
    /// Strips across the narrow axis of a lobe of these narrow and wide roughnesses
    /// (`keylight::strips`).
    Strips(f64, f64),
}

impl Cut {
    fn key(self) -> (u64, u64) {
        match self {
            Cut::Tiles(a) => (a.to_bits(), 0),
            Cut::Strips(n, w) => (n.to_bits(), w.to_bits()),
        }
    }

    fn points(self, lights: &[KeyLight], max_points: usize) -> Option<TileSet> {
        match self {
            Cut::Tiles(a) => tiles::tile_points(lights, a, max_points),
            Cut::Strips(n, w) => strips::strip_points(lights, n, w, max_points),
        }
    }
}

/// The tiles of a lobe, keyed by its cut, its point allowance and the lights they cut.
type TilesKey = ((u64, u64), usize, TileLights);

/// How many lobes' tiles a map keeps ([`KeyLightSet::tiles`]; all are dropped when it is full).
const TILES_KEPT: usize = 1024;

/// A map's key lights, its wide lights, and the tiles made of them so far.
#[derive(Debug, Default)]
pub struct KeyLightSet {
    /// The key lights, as detected.
    pub lights: Vec<KeyLight>,
    /// The wide lights beside them (`keylight::WideLights`), if the map has any.
    pub wide: Option<WideLightSet>,
    /// The tiles made so far, by lobe roughness, point allowance and whether they cut the wide
    /// lights too: a frame asks for them per lobe, and an edit changes one lobe at a time.
    tiles: RefCell<HashMap<TilesKey, Option<TileSet>>>,
}

/// The wide lights of a map, for the lobes that see them as points or tiles.
#[derive(Clone, Debug)]
pub struct WideLightSet {
    /// The wide lights, as detected.
    pub lights: Vec<KeyLight>,
    /// The key lights and the wide lights, in that order (what the wide points and the wide tiles
    /// are made of).
    pub all: Vec<KeyLight>,
}

impl WideLightSet {
    /// Whether the reach test's cone table holds all of them (`keylight::MAX_LIGHTS`, `lobe.comp`'s
    /// `MAX_LIGHTS`): a lobe that sees them all as tiles takes no reach test otherwise.
    pub fn reach_testable(&self) -> bool {
        self.all.len() <= keylight::MAX_LIGHTS
    }
}

impl KeyLightSet {
    /// The set of `lights` and, where the map has them, `wide` lights.
    pub fn new(lights: Vec<KeyLight>, wide: Option<Vec<KeyLight>>) -> KeyLightSet {
        let wide = wide.map(|w| WideLightSet { all: lights.iter().chain(&w).cloned().collect(), lights: w });
        KeyLightSet { lights, wide, tiles: RefCell::default() }
    }

    /// The tiles or strips (`cut`) for a lobe, at most `max_points` points a pixel, of the lights
    /// `which` says (`None` for the wide lights on a map without any), made once per map (at most
    /// `TILES_KEPT` kept).
    pub fn tiles(&self, cut: Cut, max_points: usize, which: TileLights) -> Option<TileSet> {
        let key = (cut.key(), max_points, which);
        if let Some(made) = self.tiles.borrow().get(&key) {
            return made.clone();
        }
        let made = match (which, &self.wide) {
            (TileLights::Key, _) => cut.points(&self.lights, max_points),
            (TileLights::KeyAndWide, Some(w)) => cut.points(&w.all, max_points),
            (TileLights::KeyAndWidePoints, Some(w)) => {
                let left = max_points.checked_sub(4 * w.lights.len())?;
                let made = cut.points(&self.lights, left).map(|t| t.and_points(&w.lights));
                // The wide lights' points fit the block too.
                made.filter(|t| t.rows.len() <= tiles::MAX_BLOCK_POINTS)
            }
            (_, None) => return None,
        };
        let mut kept = self.tiles.borrow_mut();
        if kept.len() >= TILES_KEPT {
            kept.clear();
        }
        kept.insert(key, made.clone());
        made
    }
}
