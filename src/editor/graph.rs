//! The BRDF graphs under the canvas, drawn as egui shapes over the composed window (GPU triangles,
//! no CPU pixels), side by side in the graph area: left, a polar plot of `f·cos θ_i` for the canvas
//! light's incident direction over outgoing directions in its plane of incidence (paper Fig. 1, lower
//! right); right, the same over the whole hemisphere as a 3-D wireframe ([`crate::plot::lobe3d`]),
//! turned by dragging inside it. Both draw one colour per lobe plus the sum, linear or log scale.
//! The values are computed once per material and light ([`Curves`]); the 3-D view's turn lives in
//! egui's memory, so it outlives a change of material. Also the tool panel's small plot of the
//! directional albedo against the view angle ([`paint_albedo`]).

use glam::DVec3;

use crate::brdf::Material;
use crate::plot::albedo::AlbedoPlot;
use crate::plot::lobe3d::{Surface, View};
use crate::plot::{self, lobe_colour, mean, Line, Scale, SUM_COLOUR};

/// The plot's data: the light's incident direction, the outgoing directions and one curve per lobe
/// plus the sum (values of `f·cos θ_i`, channel mean), and the 3-D view's surfaces.
pub struct Curves {
    wi: DVec3,
    dirs: Vec<DVec3>,
    curves: Vec<(Vec<f64>, [u8; 3])>,
    peak: f64,
    surface: Surface,
}

fn rgb(c: [u8; 3]) -> egui::Color32 {
    egui::Color32::from_rgb(c[0], c[1], c[2])
}

fn scale_of(log: bool) -> Scale {
    if log {
        Scale::Log
    } else {
        Scale::Linear
    }
}

impl Curves {
    pub fn new(m: &Material, light: DVec3) -> Curves {
        // The UI thread never waits for a compensation table: until every lobe's is baked (on a
        // thread of its own, `render::compensation::Tables`) the graphs show the lobes alone, and
        // are made again when the tables arrive (`CanvasKey::tables`).
        let ready = !m.compensated() || m.lobes.iter().all(crate::brdf::compensation::baked);
        let without = Material { preserve_energy: false, ..m.clone() };
        let m = if ready { m } else { &without };
        // The incident direction in the local frame of the canvas centre (n = +z): the light's
        // elevation, in the plane φ = 0.
        let wi = plot::incident(light);
        let n = 181;
        let dirs: Vec<DVec3> = (0..n)
            .map(|k| {
                let t = (-90.0 + 180.0 * k as f64 / (n - 1) as f64).to_radians();
                DVec3::new(t.sin(), 0.0, t.cos().max(1e-4)).normalize()
            })
            .collect();
        let mut curves: Vec<(Vec<f64>, [u8; 3])> = Vec::new();
        for (k, lobe) in m.lobes.iter().enumerate() {
            let single = crate::brdf::Material { diffuse: [0.0; 3], lobes: vec![lobe.clone()], ..m.clone() };
            curves.push((dirs.iter().map(|&wo| mean(single.eval(wi, wo)) * wi.z).collect(), lobe_colour(k)));
        }
        curves.push((dirs.iter().map(|&wo| mean(m.eval(wi, wo)) * wi.z).collect(), SUM_COLOUR));
        let peak = curves.iter().flat_map(|c| c.0.iter()).fold(0.0f64, |a, &b| a.max(b)).max(1e-12);
        let peak = if peak.is_finite() { peak } else { 1.0 };
        Curves { wi, dirs, curves, peak, surface: Surface::new(m, light) }
    }

    /// Paints the polar plot into `rect` (window points) with `painter`: background, horizon, the
    /// light's direction and the curves.
    pub fn paint(&self, painter: &egui::Painter, rect: egui::Rect, log: bool) {
        if rect.width() < 8.0 || rect.height() < 8.0 {
            return;
        }
        painter.rect_filled(rect, 0.0, rgb(plot::BACKGROUND));
        let scale = scale_of(log);
        let (cx, cy) = (rect.center().x as f64, rect.bottom() as f64 - 4.0);
        let radius = (rect.width() as f64 / 2.0 - 4.0).min(rect.height() as f64 - 8.0);
        let at = |x: f64, y: f64| egui::pos2(x as f32, y as f32);
        let thin = |c: [u8; 3]| egui::Stroke::new(1.0, rgb(c));
        painter.line_segment([at(cx - radius, cy), at(cx + radius, cy)], thin([70, 70, 80]));
        painter.line_segment([at(cx, cy), at(cx + self.wi.x * radius, cy - self.wi.z * radius)], thin([120, 110, 60]));
        for (values, colour) in &self.curves {
            let pts: Vec<egui::Pos2> = values
                .iter()
                .zip(&self.dirs)
                .map(|(&v, d)| {
                    let r = scale.radius(v, self.peak);
                    at(cx + d.x * radius * r, cy - d.z * radius * r)
                })
                .collect();
            painter.add(egui::Shape::line(pts, thin(*colour)));
        }
    }

    /// Paints the 3-D view into `rect` (window points) seen from `view`: background, then the
    /// wireframe of [`Surface::project`], its [`View::frame`] fitted into the rectangle.
    pub fn paint_3d(&self, painter: &egui::Painter, rect: egui::Rect, log: bool, view: View) {
        if rect.width() < 8.0 || rect.height() < 8.0 {
            return;
        }
        painter.rect_filled(rect, 0.0, rgb(plot::BACKGROUND));
        let r = [rect.left() as f64, rect.top() as f64, rect.width() as f64, rect.height() as f64];
        let (ox, oy, s) = plot::fit(view.frame(), r, 4.0);
        paint_lines(painter, &self.surface.project(view, scale_of(log)), |p| {
            egui::pos2((ox + p[0] * s) as f32, (oy - p[1] * s) as f32)
        });
    }
}

fn paint_lines(painter: &egui::Painter, lines: &[Line], at: impl Fn([f64; 2]) -> egui::Pos2) {
    for l in lines {
        let pts: Vec<egui::Pos2> = l.points.iter().map(|&p| at(p)).collect();
        painter.add(egui::Shape::line(pts, egui::Stroke::new(1.0, rgb(l.colour))));
    }
}

/// Paints the graph area `rect` (window points): the polar plot in its left half, the 3-D view in
/// its right half, turned by a drag inside it (egui's `interact` on that half; the turn is kept in
/// egui's memory).
pub fn paint(ctx: &egui::Context, curves: &Curves, rect: egui::Rect, log: bool) {
    let mid = rect.center().x;
    let left = egui::Rect::from_min_max(rect.min, egui::pos2(mid, rect.max.y));
    let right = egui::Rect::from_min_max(egui::pos2(mid, rect.min.y), rect.max);
    curves.paint(&ctx.layer_painter(egui::LayerId::background()), left, log);
    if right.width() < 8.0 || right.height() < 8.0 {
        return;
    }
    egui::Area::new(view_id()).fixed_pos(right.min).order(egui::Order::Background).constrain(false).show(ctx, |ui| {
        let response = ui.allocate_rect(right, egui::Sense::drag());
        let mut view = view_3d(ctx);
        if response.dragged() {
            let d = response.drag_delta();
            view = view.turned(d.x as f64, d.y as f64);
            ctx.data_mut(|m| m.insert_temp(view_id(), (view.yaw, view.pitch)));
        }
        curves.paint_3d(ui.painter(), right, log, view);
    });
}

/// The 3-D view's area, and the key of its turn in egui's memory.
fn view_id() -> egui::Id {
    egui::Id::new("brdf-shop 3-D view")
}

/// How the 3-D view is turned in `ctx`'s window: [`View::DEFAULT`] while it has not been dragged.
pub fn view_3d(ctx: &egui::Context) -> View {
    let turn = ctx.data(|d| d.get_temp::<(f64, f64)>(view_id()));
    turn.map_or(View::DEFAULT, |(yaw, pitch)| View { yaw, pitch })
}

/// Paints the albedo plot into `rect` (window points): background, axes, the energy sum's line,
/// each lobe's curve and the total's, and a line of text naming the maximum.
pub fn paint_albedo(painter: &egui::Painter, rect: egui::Rect, albedo: &AlbedoPlot) {
    if rect.width() < 16.0 || rect.height() < 24.0 {
        return;
    }
    painter.rect_filled(rect, 0.0, rgb(plot::BACKGROUND));
    let text = 12.0f32;
    let top = (rect.top() + text + 6.0) as f64;
    let inner = [rect.left() as f64 + 4.0, top, rect.width() as f64 - 8.0, rect.bottom() as f64 - 4.0 - top];
    paint_lines(painter, &albedo.place(inner), |p| egui::pos2(p[0] as f32, p[1] as f32));
    let m = albedo.maximum;
    painter.text(
        rect.left_top() + egui::vec2(4.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("max {:.3} at θo {}°; line: ρd+Σρk {:.3}", m.value, m.theta_deg, albedo.bound),
        egui::FontId::proportional(text),
        rgb(crate::plot::lobe3d::NORMAL_COLOUR),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs one egui frame of the graph area `rect` in an 800×600 window with `events`.
    fn frame(ctx: &egui::Context, curves: &Curves, rect: egui::Rect, events: Vec<egui::Event>) {
        let screen = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(800.0, 600.0));
        let input = egui::RawInput { screen_rect: Some(screen), events, ..Default::default() };
        let _ = ctx.run(input, |ctx| paint(ctx, curves, rect, false));
    }

    /// A left-button drag from `from` by `by` in small steps, one frame each.
    fn drag(ctx: &egui::Context, curves: &Curves, rect: egui::Rect, from: egui::Pos2, by: egui::Vec2) {
        let button = |pos, pressed| egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        };
        frame(ctx, curves, rect, vec![egui::Event::PointerMoved(from)]);
        frame(ctx, curves, rect, vec![button(from, true)]);
        for k in 1..=10 {
            frame(ctx, curves, rect, vec![egui::Event::PointerMoved(from + by * (k as f32 / 10.0))]);
        }
        frame(ctx, curves, rect, vec![button(from + by, false)]);
    }

    /// A drag inside the 3-D view turns it (right: yaw up, down: pitch up) and the turn stays; a
    /// drag on the polar graph beside it does not.
    #[test]
    fn dragging_inside_the_3d_view_turns_it() {
        let m = Material { lobes: vec![crate::brdf::Lobe::isotropic([0.3; 3], 0.2)], ..Material::scratch() };
        let curves = Curves::new(&m, DVec3::new(0.3, 0.4, 0.866));
        let ctx = egui::Context::default();
        let rect = egui::Rect::from_min_max(egui::pos2(200.0, 300.0), egui::pos2(800.0, 600.0));
        frame(&ctx, &curves, rect, Vec::new());
        assert_eq!(view_3d(&ctx), View::DEFAULT);
        drag(&ctx, &curves, rect, egui::pos2(350.0, 450.0), egui::vec2(60.0, 30.0));
        assert_eq!(view_3d(&ctx), View::DEFAULT, "a drag on the polar graph turned the 3-D view");
        drag(&ctx, &curves, rect, egui::pos2(650.0, 450.0), egui::vec2(60.0, 30.0));
        let v = view_3d(&ctx);
        assert!(v.yaw > View::DEFAULT.yaw + 0.3 && v.pitch > View::DEFAULT.pitch + 0.1, "{v:?}");
        frame(&ctx, &curves, rect, Vec::new());
        assert_eq!(view_3d(&ctx), v, "the turn is kept");
    }
}
