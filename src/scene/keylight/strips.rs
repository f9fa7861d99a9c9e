//! Lights cut into strips across an anisotropic lobe's narrow axis (the `key` estimator).
//!
//! A lobe much narrower along one axis than along the other (a streak) resolves a light's shape
//! along its narrow axis only: along its wide axis, where it is wider than the light, a light's
//! four quadrature points follow it to second order ([`super::quadrature_fits`]). Round tiles
//! ([`super::tiles`]) cut the light along both axes for the lobe's orientation-mean roughness;
//! strips cut it across the narrow axis alone, into far fewer points. Which way the narrow axis
//! crosses the light depends on the pixel (the lobe's frame turns over the surface), so each light
//! is cut at [`ORIENTATIONS`] orientations in the plane tangent at its direction ([`frame`]), and
//! a pixel runs the strips of the orientation nearest its lobe's narrow axis there ([`orientation`],
//! `glsl/include/lobe_lights.glsl` `strip_orientation`).
//!
//! Each strip is its four quadrature points, exact to second order within it. The bound is the
//! round tiles' for a round lobe of the narrow roughness `α`: a strip's error is a fourth-order
//! term across it, `8 Σ|w| (x − x̄)⁴` (`x` along the cut's axis; for a round region the tiles'
//! `|W| s⁴`), and the widest strip is split at the middle of its extent across the axis until
//! those add up to no more than `TILE_BUDGET |W| (r α)⁴`. The orientations are `π / 16` apart, so a
//! pixel's strips are turned by at most `π / 32` from its lobe's axes: a strip of length `ℓ` then
//! spreads its points across the narrow axis by at most `ℓ sin(π/32) ≈ 0.1 ℓ`.
//! `tests/keylight.rs` checks the bias against the exact integral over the texels.
//!
//! Pure CPU; made once per map and lobe shape, as the tiles are.

use std::f64::consts::PI;

use glam::DVec3;

use super::tiles::{quarters, refine, tile, LightTexel, Tile, TileSet, MAX_BLOCK_POINTS};
use super::{KeyLight, QUADRATURE_RATIO};

/// How many orientations each light is cut at, `π / ORIENTATIONS` apart (`lobe_lights.glsl`'s
/// `ORIENTATIONS` is the same number).
pub const ORIENTATIONS: usize = 16;

/// The axes of the plane tangent at a light's direction `l` in which the strips' orientations are
/// measured: `e1 = ŷ × l` normalised (`x̂ × l` within 26° of the poles), `e2 = l × e1`.
/// `lobe_lights.glsl` `strip_frame` makes the same.
pub fn frame(l: DVec3) -> (DVec3, DVec3) {
    let e1 = if l.y.abs() < 0.9 { DVec3::Y.cross(l) } else { DVec3::X.cross(l) }.normalize();
    (e1, l.cross(e1))
}

/// The orientation whose strips a pixel runs for the light toward `l`: that of its lobe's narrow
/// axis at the light. The lobe's exponent grows with `t² / α²`, `t = (H · y) / (H · z)` the slope
/// of the half vector `H = l + b` along the narrow axis `y` (`z` the lobe's normal, `b` the view
/// it is sampled about); its gradient in `l` is along `y − t z`, projected onto the plane tangent
/// at `l`. Its angle in [`frame`], rounded to the nearest of the [`ORIENTATIONS`] (modulo `π`).
/// `lobe_lights.glsl` `strip_orientation` computes the same.
pub fn orientation(l: DVec3, narrow: DVec3, normal: DVec3, view: DVec3) -> usize {
    let h = l + view;
    let t = h.dot(narrow) / h.dot(normal);
    let mut d = narrow - t * normal;
    d -= d.dot(l) * l;
    let (e1, e2) = frame(l);
    let phi = d.dot(e2).atan2(d.dot(e1));
    let o = (phi * ORIENTATIONS as f64 / PI).round();
    if o.is_finite() {
        (o as i64).rem_euclid(ORIENTATIONS as i64) as usize
    } else {
        0
    }
}

/// Whether a lobe whose wider roughness is `alpha_wide` sees every light as a point along that
/// axis (the quadrature's threshold, [`QUADRATURE_RATIO`]), so that strips across its narrow axis
/// hold the tiles' bound.
pub fn strips_fit(lights: &[KeyLight], alpha_wide: f64) -> bool {
    lights.iter().all(|l| l.spread <= QUADRATURE_RATIO * alpha_wide)
}

/// The strip of `texels`: [`tile`]'s points and power, its moment across `axis`.
fn strip(region: &[LightTexel], texels: Vec<usize>, axis: DVec3) -> Tile {
    let mut t = tile(region, texels);
    if t.moment.is_finite() && t.moment > 0.0 {
        let abs: f64 = t.texels.iter().map(|&k| region[k].weight.abs()).sum();
        let mean = t.texels.iter().map(|&k| region[k].weight.abs() * region[k].direction.dot(axis)).sum::<f64>() / abs;
        // A texel's own extent: its variance Ω/12 along any axis.
        t.moment = 8.0
            * t.texels
                .iter()
                .map(|&k| {
                    let x = region[k].direction.dot(axis) - mean;
                    region[k].weight.abs() * (x * x + region[k].solid_angle / 12.0).powi(2)
                })
                .sum::<f64>();
    }
    t
}

/// Splits `t` in two at the middle of its extent along `axis`; texels all at one place along it
/// (a strip of one texel, or of a column of texels) are first cut into their quarters, appended to
/// `region`.
fn split_across(region: &mut Vec<LightTexel>, t: &Tile, axis: DVec3) -> Option<(Tile, Tile)> {
    let range = |region: &[LightTexel], texels: &[usize]| {
        texels.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &k| {
            let x = region[k].direction.dot(axis);
            (lo.min(x), hi.max(x))
        })
    };
    let mut texels = t.texels.clone();
    let (mut lo, mut hi) = range(region, &texels);
    if !(hi - lo > 1e-12) {
        let mut parts = Vec::with_capacity(4 * texels.len());
        for &k in &texels {
            let first = region.len();
            let quartered = quarters(&region[k]);
            region.extend(quartered);
            parts.extend(first..first + 4);
        }
        texels = parts;
        (lo, hi) = range(region, &texels);
    }
    let middle = 0.5 * (lo + hi);
    let (a, b): (Vec<usize>, Vec<usize>) = texels.iter().partition(|&&k| region[k].direction.dot(axis) < middle);
    if a.is_empty() || b.is_empty() {
        return None;
    }
    Some((strip(region, a, axis), strip(region, b, axis)))
}

/// The strips of `light` across `axis` for a lobe of narrow roughness `alpha`, at most
/// `max_strips` of them, or `None` when they do not fit.
fn light_strips(light: &KeyLight, axis: DVec3, alpha: f64, max_strips: usize) -> Option<Vec<Tile>> {
    if max_strips == 0 {
        return None;
    }
    refine(
        light,
        alpha,
        max_strips,
        |region, texels| strip(region, texels, axis),
        |region, t| split_across(region, t, axis),
    )
}

/// The strips of every light for a lobe of roughness `alpha_narrow` × `alpha_wide`: for each
/// light, [`ORIENTATIONS`] sets of `[direction, 0, power / 4, 0]` rows, four a strip, each set
/// padded to the longest with rows of no power; a pixel runs one set a light, at most
/// `max_points` points in all, and the rows fit the lobe pass's block ([`MAX_BLOCK_POINTS`]).
/// `None` where a light is wider than the lobe's wide axis ([`strips_fit`]) or the strips do not
/// fit.
pub fn strip_points(lights: &[KeyLight], alpha_narrow: f64, alpha_wide: f64, max_points: usize) -> Option<TileSet> {
    if !(alpha_narrow > 0.0 && alpha_wide >= alpha_narrow && strips_fit(lights, alpha_wide)) {
        return None;
    }
    let mut rows: Vec<[f32; 8]> = Vec::new();
    let mut ends = Vec::with_capacity(lights.len());
    let mut seen = 0;
    for light in lights {
        let left = (max_points / 4).checked_sub(seen)?;
        let (e1, e2) = frame(light.direction);
        let sets = (0..ORIENTATIONS)
            .map(|o| {
                let phi = o as f64 * PI / ORIENTATIONS as f64;
                light_strips(light, phi.cos() * e1 + phi.sin() * e2, alpha_narrow, left)
            })
            .collect::<Option<Vec<_>>>()?;
        let per = sets.iter().map(Vec::len).max()?;
        seen += per;
        if rows.len() + ORIENTATIONS * 4 * per > MAX_BLOCK_POINTS {
            return None;
        }
        let d = light.direction;
        for set in sets {
            for t in &set {
                let p = t.power.map(|c| (c / 4.0) as f32);
                rows.extend(t.points.map(|d| [d.x as f32, d.y as f32, d.z as f32, 0.0, p[0], p[1], p[2], 0.0]));
            }
            let none = [d.x as f32, d.y as f32, d.z as f32, 0.0, 0.0, 0.0, 0.0, 0.0];
            rows.extend(std::iter::repeat_n(none, 4 * (per - set.len())));
        }
        ends.push(rows.len());
    }
    Some(TileSet { rows, ends, oriented: lights.len() })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frame is orthonormal, and its second axis completes it about the light.
    #[test]
    fn the_frame_is_orthonormal_everywhere() {
        for l in [DVec3::X, DVec3::Y, -DVec3::Y, DVec3::new(0.3, 0.95, 0.1).normalize(), DVec3::new(0.74, 0.66, -0.12)]
        {
            let l = l.normalize();
            let (e1, e2) = frame(l);
            for (a, b) in [(e1, e2), (e1, l), (e2, l)] {
                assert!(a.dot(b).abs() < 1e-12, "{l}: {a} · {b}");
            }
            assert!((e1.length() - 1.0).abs() < 1e-12 && (e2.length() - 1.0).abs() < 1e-12, "{l}");
            assert!((e1.cross(e2) - l).length() < 1e-12, "{l}");
        }
    }

    /// A lobe whose narrow axis crosses the light along `e1` takes orientation 0, along `e2` the
    /// middle one, and its opposite the same; turned by `π/16` the next; a degenerate view gives
    /// an orientation in range rather than a NaN's.
    #[test]
    fn the_orientation_follows_the_narrow_axis_modulo_pi() {
        let l = DVec3::new(0.74, 0.66, -0.12).normalize();
        let (e1, e2) = frame(l);
        // Seen at the lobe's peak head-on (the view, the normal and the light alike), the narrow
        // axis crosses the light as it lies.
        let at = |narrow: DVec3| orientation(l, narrow, l, l);
        assert_eq!(at(e1), 0);
        assert_eq!(at(-e1), 0);
        assert_eq!(at(e2), ORIENTATIONS / 2);
        let step = PI / ORIENTATIONS as f64;
        assert_eq!(at(step.cos() * e1 + step.sin() * e2), 1);
        assert_eq!(at((-step).cos() * e1 + (-step).sin() * e2), ORIENTATIONS - 1);
        // Off the peak the slope's term turns it: a view tilted along the narrow axis leaves it.
        let view = (l + 0.3 * e2).normalize();
        let normal = (l + view).normalize();
        assert_eq!(orientation(l, e1, normal, view), 0);
        assert!(orientation(l, DVec3::ZERO, l, -l) < ORIENTATIONS);
        assert!(orientation(l, DVec3::new(f64::NAN, 0.0, 0.0), l, l) < ORIENTATIONS);
    }
}
