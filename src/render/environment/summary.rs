//! The `key` estimator's decision about a map's key and wide lights, as the line `render` prints
//! and as the JSON of `render --timings`.

use crate::scene::keylight;

/// What the renderer decided about a map's key lights (reported by `render --timings` and `report`).
#[derive(Clone, Debug, PartialEq)]
pub struct KeyLightSummary {
    pub lights: Vec<crate::scene::keylight::KeyLight>,
    pub share: f64,
    pub threshold: f64,
    /// The wide lights beside the key lights and their share (empty and 0 without).
    pub wide: Vec<crate::scene::keylight::KeyLight>,
    pub wide_share: f64,
}

impl KeyLightSummary {
    /// The decision as JSON (`render --timings`): threshold, share and each light.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "decision": self.describe(),
            "threshold": self.threshold,
            "threshold_over_mean": crate::scene::keylight::THRESHOLD_OVER_MEAN,
            "quadrature_ratio": crate::scene::keylight::QUADRATURE_RATIO,
            "tiles_min_alpha": self.tiles_min_alpha(),
            "tiles_max_points": crate::scene::keylight::tiles::MAX_TILE_POINTS,
            "tiles_max_points_with_reach": crate::scene::keylight::tiles::MAX_BLOCK_POINTS,
            "share": self.share,
            "lights": self.lights.iter().map(light_json).collect::<Vec<_>>(),
            "wide": {
                "threshold_over_mean": crate::scene::keylight::WIDE_THRESHOLD_OVER_MEAN,
                "share": self.wide_share,
                "quadrature_min_alpha": self.wide_min_alpha(),
                "points_min_alpha_max": self.wide_points_min_alpha(),
                "lights": self.wide.iter().map(light_json).collect::<Vec<_>>(),
            },
        })
    }

    /// The smallest `max(αx, αy)` of a lobe that sees each wide light as its four points where it
    /// does not see them as tiles, in frames of fewer than `lobe::WIDE_POINTS_BY_SMALLER_ALPHA_SPP`
    /// samples (from there on, the smallest `min(αx, αy)`: `lobe::sees_wide_lights_as_points`);
    /// `None` without wide lights.
    pub fn wide_points_min_alpha(&self) -> Option<f64> {
        let spread = self.wide.iter().map(|l| l.spread).fold(0.0, f64::max);
        (!self.wide.is_empty()).then(|| spread / crate::render::lobe::WIDE_POINTS_RATIO)
    }

    /// The smallest `min(αx, αy)` of a lobe that sees the key and wide lights as points (`None`
    /// without wide lights).
    pub fn wide_min_alpha(&self) -> Option<f64> {
        let spread = self.lights.iter().chain(&self.wide).map(|l| l.spread).fold(0.0, f64::max);
        (!self.wide.is_empty()).then(|| spread / crate::scene::keylight::QUADRATURE_RATIO)
    }

    /// The smallest `α` of an isotropic lobe of one component that sees the key lights as tiles
    /// (`keylight::tiles`, within `tiles::max_points`, with the reach test where it pays; Ward's
    /// reach, the wider), to 1 %; `None` without lights.
    pub fn tiles_min_alpha(&self) -> Option<f64> {
        use crate::render::lobe::{reach_angle, reach_half_angles, REACH_TEST_MAX_DEG};
        use crate::scene::keylight::tiles::{max_points, narrowest_alpha};
        let ward = crate::brdf::Normalization::Ward;
        narrowest_alpha(&self.lights, |a| {
            let lobe = crate::brdf::Lobe::isotropic([1.0; 3], a);
            let pays = reach_angle(ward, &lobe).to_degrees() <= REACH_TEST_MAX_DEG;
            max_points(&self.lights, pays.then(|| reach_half_angles(ward, &lobe)))
        })
    }

    /// One line: how many lights, their share of the energy, the threshold, and each light's radius and
    /// direction (or why there is none).
    pub fn describe(&self) -> String {
        use crate::scene::keylight::{MIN_SHARE, QUADRATURE_RATIO, THRESHOLD_OVER_MEAN, WIDE_THRESHOLD_OVER_MEAN};
        if self.lights.is_empty() {
            return format!(
                "no key light (no compact region above {THRESHOLD_OVER_MEAN} × the mean radiance = {:.4} carries ≥ {:.0} % of the energy): no light term",
                self.threshold,
                MIN_SHARE * 100.0
            );
        }
        let each: Vec<String> = self.lights.iter().map(describe_light).collect();
        let spread = self.lights.iter().map(|l| l.spread).fold(0.0, f64::max);
        let mut line = format!(
            "{} key light(s) carrying {:.1} % of the energy (threshold {THRESHOLD_OVER_MEAN} × the mean radiance = {:.4}): {}; lobes with min(αx, αy) ≥ {:.4} (the largest spread ≤ {QUADRATURE_RATIO} α) see them as 4 quadrature points each, {}",
            self.lights.len(),
            self.share * 100.0,
            self.threshold,
            each.join("; "),
            spread / QUADRATURE_RATIO,
            match self.tiles_min_alpha() {
                Some(a) => format!(
                    "those with min(αx, αy) ≥ {a:.4} (isotropic) as tiles of 4 points each (at most {} points, up to {} where a narrow lobe tests its reach), an anisotropic lobe of one component with max(αx, αy) ≥ {:.4} as strips across its narrow axis where those run fewer points, the others by MIS",
                    crate::scene::keylight::tiles::MAX_TILE_POINTS,
                    crate::scene::keylight::tiles::MAX_BLOCK_POINTS,
                    spread / QUADRATURE_RATIO
                ),
                None => "the others by MIS".to_string(),
            }
        );
        if let Some(alpha) = self.wide_min_alpha() {
            let each: Vec<String> = self.wide.iter().map(describe_light).collect();
            line += &format!(
                "; {} wide light(s) carrying {:.1} % (above {WIDE_THRESHOLD_OVER_MEAN} × the mean once the key lights are removed): {}; lobes with min(αx, αy) ≥ {alpha:.4} see key and wide lights as points over the map without both, and, in frames of {} samples or more, a narrower lobe sees the key and wide lights as tiles together where those fit (and its reach test, if it takes one, can hold them all), over the map without both; otherwise a lobe with max(αx, αy) ≥ {points:.4} (min(αx, αy) in frames of {} samples or more) sees each wide light as its 4 quadrature points (and the key lights as points or tiles), over the map without both",
                self.wide.len(),
                self.wide_share * 100.0,
                each.join("; "),
                crate::render::lobe::WIDE_TILES_MIN_SPP,
                crate::render::lobe::WIDE_POINTS_BY_SMALLER_ALPHA_SPP,
                points = self.wide_points_min_alpha().unwrap_or(0.0)
            );
        }
        line
    }
}

/// One light in `render --timings`' JSON.
fn light_json(l: &keylight::KeyLight) -> serde_json::Value {
    serde_json::json!({
        "direction": [l.direction.x, l.direction.y, l.direction.z],
        "angular_radius_deg": l.angular_radius.to_degrees(),
        "extent_deg": l.extent.to_degrees(),
        "spread_deg": l.spread.to_degrees(),
        "solid_angle": l.solid_angle,
        "power": l.power,
        "texels": l.texels,
    })
}

/// One light in the decision's line: radius, spread and direction.
fn describe_light(l: &keylight::KeyLight) -> String {
    let d = l.direction;
    format!(
        "radius {:.2}°, spread {:.2}° toward ({:.3}, {:.3}, {:.3})",
        l.angular_radius.to_degrees(),
        l.spread.to_degrees(),
        d.x,
        d.y,
        d.z
    )
}
