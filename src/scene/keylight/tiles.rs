//! Lights cut into tiles for a lobe narrower than they are (the `key` estimator).
//!
//! A lobe wider than a light sees it as the light's four quadrature points
//! ([`super::quadrature_fits`]). A narrower lobe resolves the light's shape, and its light samples
//! (MIS) are what leaves studio's lamp noisy at 8 spp. Here the light is cut into tiles
//! instead, each seen as its own four points (the same quadrature, exact to second order within the
//! tile), fine where the light's weight is and coarse where it is faint.
//!
//! The error bound. The four points of a region of net weight `W` and spread `s` (the radius of the
//! uniform disc with its fourth moment about its mean, texels of either sign counted by `|w|`) err by
//! a fourth-order term, and the whole light is taken as points when `s ≤ r α` ([`QUADRATURE_RATIO`]
//! `= r`): `|W| s⁴ ≤ |W| (r α)⁴`. `|W| s⁴ = 3 Σ|w| ρ⁴` is the region's absolute fourth moment, so the
//! tiles of a light keep that bound, times [`TILE_BUDGET`], when their moments add up to no more:
//! `Σ_t |W_t| s_t⁴ ≤ TILE_BUDGET |W| (r α)⁴`. The tile with the largest moment is split (at the
//! middle of its longer side, in the plane tangent at the light) until the sum fits. A tile whose
//! signs cancel (net weight under half its `Σ|w|`) has points far off its texels and is always
//! split; a tile of a single texel is cut into its quarters (the map is read texel by texel: the
//! radiance is constant over a texel). A lobe whose tiles would take more points than it may
//! ([`max_points`]) gets none (`None`: it keeps MIS).
//! `tests/keylight.rs` checks the bias against the exact integral over the texels. A streak (a
//! lobe much narrower along one axis than the light and wider than it along the other) may see
//! the light as strips across its narrow axis instead ([`super::strips`]), in fewer points.
//!
//! Pure CPU, a few microseconds per lobe. The renderer makes a lobe's tiles once per map and keeps
//! them with it (`render::environment::GpuKeyLights::tiles`, keyed by roughness, point budget and
//! lights; up to 1024 lobes' tiles a map).

use glam::DVec3;

use super::{quadrature, Environment, KeyLight, QUADRATURE_RATIO};

/// The roughness an anisotropic lobe's tiles are made for ([`tile_points`]' `alpha`): its `α` where
/// it is round; otherwise the `α` of the round lobe whose tiles' error matches its own averaged over
/// its orientation to the light. The four points of a region of spread `s` err by a fourth-order
/// term in the lobe's exponent `x²/αx² + y²/αy²` over the region (its fourth directional
/// derivatives), which a round region at angle `φ` to the lobe's axes weighs by
/// `(cos²φ/αx² + sin²φ/αy²)²`; over `φ` its mean is `(3/αx⁴ + 2/(αx² αy²) + 3/αy⁴) / 8` (`E cos⁴ =
/// E sin⁴ = 3/8`, `E cos² sin² = 1/8`), `1/α⁴` for a round lobe. Along the narrow axis the weight is
/// `1/αx⁴`, at most 8/3 of the mean, so the tiles' bound ([`TILE_BUDGET`]) holds on average over the
/// orientations and within 8/3 of it at the worst (`tests/keylight.rs` checks eight orientations of
/// three lobes on four maps; tiles at the geometric mean `√(αx αy)`, which ignores the narrow axis,
/// err several times more: docs/renderer.md, Alternatives measured and rejected). The lobe's
/// smaller `α` instead, the bound at every orientation, takes 44 points for studio's lamp where
/// this takes 28 (the sweep's Ward 0.05 × 0.3 lobe).
pub fn tile_alpha(alpha_x: f64, alpha_y: f64) -> f64 {
    let (a2, b2) = (alpha_x * alpha_x, alpha_y * alpha_y);
    (8.0 / (3.0 / (a2 * a2) + 2.0 / (a2 * b2) + 3.0 / (b2 * b2))).powf(0.25)
}

/// The most points a lobe's tiles may take where every shaded pixel evaluates them all (no reach
/// test, see [`max_points`]): every shaded pixel pays for every point, and past this many they cost
/// a lobe pass more on lavapipe than the MIS light samples they replace (docs/renderer.md,
/// Alternatives measured and rejected), so a lobe that needs more keeps MIS.
pub const MAX_TILE_POINTS: usize = 64;

/// The most points the lobe pass's uniform block holds (`render::gpu::LIGHT_SET_MAX`). Room for a
/// sharp lobe's tiles: studio's lamp as tiles for a lobe of α 0.02 takes 768 points at a
/// [`TILE_BUDGET`] of ½ (212 at 8), and as tiles that lobe's 8-spp error on studio is far below its
/// error with MIS light samples.
pub const MAX_BLOCK_POINTS: usize = 1024;

/// The most points a lobe's tiles may take. Without the per-pixel reach test every shaded pixel
/// evaluates them all: [`MAX_TILE_POINTS`]. A lobe whose pass skips the pixels out of the lights'
/// reach (`reach`: the angles from the normal, along each tangent axis, past which its half vector is
/// out of reach, `render::lobe::reach_half_angles`, radians) evaluates them only at the pixels whose
/// normal has a light's half vector within that ellipse widened by half the light's extent (the half
/// vector turns by half as much as the light's direction). On a sphere that is at most the share
/// `2 (1 − cos θ)` of the pixels, `θ` the half-angle of the circle of the widened ellipse's area
/// `π a b + P ε/2 + π ε²/4` (`P` its perimeter, Ramanujan's approximation; `θ = a + ε/2` for a circle),
/// weighted by `n·v` over the visible hemisphere. Twice that share (vectors of 8 pixels straddle its
/// edge) times the points stays within `MAX_TILE_POINTS`, up to the block's [`MAX_BLOCK_POINTS`].
pub fn max_points(lights: &[KeyLight], reach: Option<(f64, f64)>) -> usize {
    use std::f64::consts::{FRAC_PI_2, PI};
    let Some((a, b)) = reach else { return MAX_TILE_POINTS };
    let perimeter = PI * (3.0 * (a + b) - ((3.0 * a + b) * (a + 3.0 * b)).sqrt());
    let half = |l: &KeyLight| {
        let e = 0.5 * l.extent;
        (a * b + e * e + perimeter * e / PI).sqrt().min(FRAC_PI_2)
    };
    let share: f64 = lights.iter().map(|l| 4.0 * (1.0 - half(l).cos())).sum::<f64>().min(1.0);
    if !(share > 0.0) {
        return MAX_BLOCK_POINTS;
    }
    ((MAX_TILE_POINTS as f64 / share) as usize).clamp(MAX_TILE_POINTS, MAX_BLOCK_POINTS)
}

/// The tiles' moments sum to at most this multiple of the whole light's bound `|W| (r α)⁴`: the bias
/// a lobe's tiles may leave, against the cost of their points. 8: the
/// bound of a whole light seen as one tile's four points at spread `s ≤ 8^¼ r α = 0.76 α`, just
/// inside `s = 0.8 α`, where the four points still keep within 5 % of the largest value (the
/// whole light's points at that [`QUADRATURE_RATIO`], docs/renderer.md, Alternatives measured and
/// rejected), so the tiles' bias stays within 5 % of the largest value (`tests/keylight.rs` checks
/// it). Against a budget of ½, studio's lamp for a Ward lobe of α 0.02
/// is 212 points instead of 768, its frames cost much less for the same error, and a Ward
/// 0.05 × 0.3 lobe on studio sees the lamp as 44 points instead of MIS light samples, more
/// accurately (docs/renderer.md, Alternatives measured and rejected). The light term of a frame is
/// this biased whatever its samples; the refinement frames (MIS) are not.
pub const TILE_BUDGET: f64 = 8.0;

/// One texel of a light (or a part of one, see [`quarters`]), as the tiles need it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightTexel {
    /// Its centre in the map's `(u, v)`.
    pub uv: [f64; 2],
    /// Its size in `(u, v)`: `(1/W, 1/H)` for a whole texel.
    pub size: [f64; 2],
    /// Its centre's direction.
    pub direction: DVec3,
    /// `(luminance − background's) dω`, of either sign.
    pub weight: f64,
    /// `dω`.
    pub solid_angle: f64,
    /// `(L − background) dω` per channel.
    pub power: [f64; 3],
}

/// A tile: its texels (indices into the light's region), four points, power and moment.
pub(super) struct Tile {
    pub(super) texels: Vec<usize>,
    pub(super) points: [DVec3; 4],
    pub(super) power: [f64; 3],
    /// `|W| s⁴`, infinite where the signs cancel.
    pub(super) moment: f64,
}

pub(super) fn tile(region: &[LightTexel], texels: Vec<usize>) -> Tile {
    let net: f64 = texels.iter().map(|&k| region[k].weight).sum();
    let abs: f64 = texels.iter().map(|&k| region[k].weight.abs()).sum();
    let sign = if net < 0.0 { -1.0 } else { 1.0 };
    let weighted: Vec<(DVec3, f64, f64)> =
        texels.iter().map(|&k| (region[k].direction, sign * region[k].weight, region[k].solid_angle)).collect();
    let centre = region[texels[0]].direction;
    let (points, spread) = quadrature(&weighted, centre);
    let power = texels.iter().fold([0.0; 3], |p, &k| [0, 1, 2].map(|c| p[c] + region[k].power[c]));
    let moment = if texels.len() == 1 && net == 0.0 {
        // A texel of no luminance: its colour at its centre, nothing to refine.
        0.0
    } else if (texels.len() > 1 && net.abs() < 0.5 * abs) || !spread.is_finite() {
        f64::INFINITY
    } else {
        net.abs() * spread.powi(4)
    };
    Tile { texels, points, power, moment }
}

/// A texel's four quarters in `(u, v)`, each with the part of its solid angle, weight and power
/// that its `sin θ` gives it (the map is read texel by texel, nearest: the radiance is the same over
/// the texel). A texel is split only for a lobe narrower than it, where its own extent is what the
/// four points of one texel cannot follow.
pub(super) fn quarters(t: &LightTexel) -> [LightTexel; 4] {
    let offsets = [[-0.25, -0.25], [0.25, -0.25], [-0.25, 0.25], [0.25, 0.25]];
    let uv = offsets.map(|o| [t.uv[0] + o[0] * t.size[0], t.uv[1] + o[1] * t.size[1]]);
    let sin = uv.map(|p| (std::f64::consts::PI * p[1]).sin().max(0.0));
    let total: f64 = sin.iter().sum();
    let mut out = [*t; 4];
    for (k, q) in out.iter_mut().enumerate() {
        let share = if total > 0.0 { sin[k] / total } else { 0.25 };
        *q = LightTexel {
            uv: uv[k],
            size: [0.5 * t.size[0], 0.5 * t.size[1]],
            direction: Environment::direction(uv[k][0], uv[k][1]),
            weight: t.weight * share,
            solid_angle: t.solid_angle * share,
            power: t.power.map(|c| c * share),
        };
    }
    out
}

/// Splits `t` in two at the middle of its longer side in the plane `(e1, e2)`; a tile of one texel
/// (or part of one) is first cut into its [`quarters`], appended to `region`.
fn split(region: &mut Vec<LightTexel>, t: &Tile, e1: DVec3, e2: DVec3) -> Option<(Tile, Tile)> {
    if t.texels.len() == 1 {
        let parts = quarters(&region[t.texels[0]]);
        let first = region.len();
        region.extend(parts);
        // The two halves across the longer side (in angle: u spans 2π sin θ, v spans π).
        let p = &region[t.texels[0]];
        let wide = 2.0 * p.size[0] * (std::f64::consts::PI * p.uv[1]).sin() >= p.size[1];
        let (a, b) = if wide { ([0, 2], [1, 3]) } else { ([0, 1], [2, 3]) };
        let region = &*region;
        return Some((tile(region, a.map(|k| first + k).to_vec()), tile(region, b.map(|k| first + k).to_vec())));
    }
    let at = |k: usize| (region[k].direction.dot(e1), region[k].direction.dot(e2));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &k in &t.texels {
        let (x, y) = at(k);
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    let axis = if hi[0] - lo[0] >= hi[1] - lo[1] { 0 } else { 1 };
    let middle = 0.5 * (lo[axis] + hi[axis]);
    let (a, b): (Vec<usize>, Vec<usize>) = t.texels.iter().partition(|&&k| {
        let (x, y) = at(k);
        [x, y][axis] < middle
    });
    if a.is_empty() || b.is_empty() {
        return None;
    }
    Some((tile(region, a), tile(region, b)))
}

/// The tiles of `light` for a lobe of roughness `alpha` ([`tile_alpha`]), at most `max_tiles` of them, or
/// `None` when they do not fit.
fn light_tiles(light: &KeyLight, alpha: f64, max_tiles: usize) -> Option<Vec<Tile>> {
    let e1 = light.direction.any_orthonormal_vector();
    let e2 = light.direction.cross(e1);
    refine(light, alpha, max_tiles, tile, |region, t| split(region, t, e1, e2))
}

/// `light` cut into parts (`part` makes one of texels, `split` halves one) until the parts'
/// moments sum to at most the bound for a lobe of roughness `alpha`, `TILE_BUDGET |W| (r α)⁴`, the
/// part of the largest moment split first; at most `max_parts` of them, or `None` when they do not
/// fit.
pub(super) fn refine(
    light: &KeyLight,
    alpha: f64,
    max_parts: usize,
    part: impl Fn(&[LightTexel], Vec<usize>) -> Tile,
    split: impl Fn(&mut Vec<LightTexel>, &Tile) -> Option<(Tile, Tile)>,
) -> Option<Vec<Tile>> {
    let mut region = light.region.clone();
    if region.is_empty() {
        return None;
    }
    let net: f64 = region.iter().map(|t| t.weight).sum();
    let budget = TILE_BUDGET * net.abs() * (QUADRATURE_RATIO * alpha).powi(4);
    let mut parts = vec![part(&region, (0..region.len()).collect())];
    loop {
        let total: f64 = parts.iter().map(|t| t.moment).sum();
        if total <= budget {
            return Some(parts);
        }
        if parts.len() >= max_parts {
            return None;
        }
        let worst = (0..parts.len()).max_by(|&a, &b| parts[a].moment.total_cmp(&parts[b].moment))?;
        let (a, b) = split(&mut region, &parts[worst])?;
        parts[worst] = a;
        parts.push(b);
    }
}

/// A lobe's light set of tiles ([`tile_points`]): the rows, light after light, and where each
/// light's rows end, for the lobe pass that runs a light's points only at the pixels within its
/// reach (`lobe.comp` `REACH_TEST`).
#[derive(Clone, Debug, PartialEq)]
pub struct TileSet {
    /// `[direction, 0, power / 4, 0]`, four a tile.
    pub rows: Vec<[f32; 8]>,
    /// The end of light `k`'s rows in `rows`, one per light, the last `rows.len()`.
    pub ends: Vec<usize>,
    /// How many of the first lights are cut into strips ([`super::strips`]): each of their rows
    /// holds [`super::strips::ORIENTATIONS`] sets of as many points, of which a pixel takes one.
    pub oriented: usize,
}

impl TileSet {
    /// These tiles followed by each of `lights` as its own four points ([`super::point_table`]).
    pub fn and_points(mut self, lights: &[KeyLight]) -> TileSet {
        for light in lights {
            self.rows.extend(super::point_table(std::slice::from_ref(light)));
            self.ends.push(self.rows.len());
        }
        self
    }

    /// The rows a pixel runs: every light's, but one orientation's strips of each oriented light,
    /// `orientation(k)` for light `k`.
    pub fn rows_seen(&self, orientation: impl Fn(usize) -> usize) -> Vec<[f32; 8]> {
        let mut start = 0;
        let mut seen = Vec::new();
        for (k, &end) in self.ends.iter().enumerate() {
            let rows = &self.rows[start..end];
            if k < self.oriented {
                let per = rows.len() / super::strips::ORIENTATIONS;
                let o = orientation(k) % super::strips::ORIENTATIONS;
                seen.extend_from_slice(&rows[o * per..(o + 1) * per]);
            } else {
                seen.extend_from_slice(rows);
            }
            start = end;
        }
        seen
    }

    /// How many points a pixel runs ([`TileSet::rows_seen`]).
    pub fn points_seen(&self) -> usize {
        let mut start = 0;
        let mut seen = 0;
        for (k, &end) in self.ends.iter().enumerate() {
            let rows = end - start;
            seen += if k < self.oriented { rows / super::strips::ORIENTATIONS } else { rows };
            start = end;
        }
        seen
    }
}

/// The `[direction, 0, power / 4, 0]` rows of every light's tiles' points for a lobe of
/// roughness `alpha`, at most `max_points` in all; `None` when the lobe is too narrow for that many.
/// Where every light fits whole ([`super::quadrature_fits`]) these are
/// [`super::point_table`]'s rows.
pub fn tile_points(lights: &[KeyLight], alpha: f64, max_points: usize) -> Option<TileSet> {
    if !(alpha > 0.0) {
        return None;
    }
    if super::quadrature_fits(lights, alpha, alpha) {
        let ends = (1..=lights.len()).map(|k| 4 * k).collect();
        return Some(TileSet { rows: super::point_table(lights), ends, oriented: 0 });
    }
    let mut rows = Vec::new();
    let mut ends = Vec::with_capacity(lights.len());
    for light in lights {
        let left = (max_points / 4).checked_sub(rows.len() / 4)?;
        for t in light_tiles(light, alpha, left)? {
            let p = t.power.map(|c| (c / 4.0) as f32);
            rows.extend(t.points.map(|d| [d.x as f32, d.y as f32, d.z as f32, 0.0, p[0], p[1], p[2], 0.0]));
        }
        ends.push(rows.len());
    }
    Some(TileSet { rows, ends, oriented: 0 })
}

/// The smallest `alpha` (to 1 %) whose tiles fit in `max_points(alpha)` points, or `None` when no
/// lobe's do.
pub fn narrowest_alpha(lights: &[KeyLight], max_points: impl Fn(f64) -> usize) -> Option<f64> {
    let fits = |a: f64| tile_points(lights, a, max_points(a)).is_some();
    let widest = lights.iter().map(|l| l.spread / QUADRATURE_RATIO).fold(0.0, f64::max);
    if !(widest.is_finite() && widest > 0.0 && fits(widest * 1.0001)) {
        return None;
    }
    let (mut lo, mut hi) = (widest * 1e-3, widest * 1.0001);
    if fits(lo) {
        return Some(lo);
    }
    while hi / lo > 1.01 {
        let mid = (lo * hi).sqrt();
        if fits(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(hi)
}
