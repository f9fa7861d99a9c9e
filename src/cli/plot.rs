//! `brdf-shop plot`: the editor's BRDF pictures as PNG files, for scripts — `lobe3d`, the 3-D view
//! of `f·cos θ_i` for one light (`brdf_shop::plot::lobe3d`), and `albedo`, the directional albedo
//! against the view angle from the energy report's own measurement (`brdf_shop::plot::albedo`).
//! The lines come from `brdf_shop::plot`, as the editor's do; `plotters` draws them on a bitmap
//! (the embedded DejaVu Sans for text) and the PNG is written atomically. Every flag is checked,
//! and the output's folder tried, first: a refusal reads no material.

use std::path::{Path, PathBuf};

use brdf_shop::brdf::energy::{albedo_curve_watched, Watch, MAX_SAMPLES};
use brdf_shop::brdf::Material;
use brdf_shop::plot::albedo::{AlbedoPlot, X_MAX_DEG};
use brdf_shop::plot::lobe3d::{Surface, View};
use brdf_shop::plot::{Line, Scale, BACKGROUND};
use brdf_shop::Error;
use glam::DVec3;
use plotters::prelude::*;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Text and grid colours on the dark background.
const TEXT: RGBColor = RGBColor(200, 200, 205);
const GRID: RGBColor = RGBColor(50, 50, 58);

/// The largest side of a plot, in pixels.
const MAX_SIDE: u32 = 4096;
/// The smallest side of a plot, in pixels (room for the caption).
const MIN_SIDE: u32 = 64;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// `f·cos θ_i` over the hemisphere for one light, as a wireframe: one colour per lobe, white
    /// for the sum, with the horizon, the normal and the incident direction.
    Lobe3d,
    /// The directional albedo against the view angle θ_o (largest over azimuths and channels), per
    /// lobe and in total, with a line at ρ_d + Σρ_k: the measurement `check` reports.
    Albedo,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ScaleArg {
    Linear,
    /// Six decades below the peak.
    Log,
}

#[derive(clap::Args, Clone, Debug)]
pub struct PlotArgs {
    /// The material (*.brdf.json).
    #[arg(long)]
    pub material: PathBuf,
    /// What to draw.
    #[arg(long, value_enum)]
    pub kind: Kind,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
    /// lobe3d: the canvas light `x,y,z` (canvas space; its elevation is what counts, at most 89°
    /// from the normal, as in the editor's graphs); default: the default strokes' light.
    #[arg(long, allow_hyphen_values = true)]
    pub light: Option<String>,
    /// Image size `WxH`, each side 64 to 4096.
    #[arg(long, default_value = "640x480", allow_hyphen_values = true)]
    pub size: String,
    /// lobe3d: the turn of the view about the normal, in degrees (default: the editor's first view).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub yaw: Option<f64>,
    /// lobe3d: the eye's height above the horizon, in degrees, −90 to 90 (default: the editor's
    /// first view).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub pitch: Option<f64>,
    /// lobe3d: distance from the origin linear in f·cos θ_i, or logarithmic.
    #[arg(long, value_enum, default_value_t = ScaleArg::Linear)]
    pub scale: ScaleArg,
    /// albedo: Monte Carlo samples per view direction for the paper's model, as `check --samples`
    /// (2 to 1000000); the reciprocal model's quadrature takes none.
    #[arg(long, default_value_t = 20_000, allow_hyphen_values = true)]
    pub samples: usize,
}

fn parse_size(s: &str) -> Result<(u32, u32), Error> {
    let bad =
        || Error::input("--size", format!("expected WxH with whole numbers, got \"{}\"", brdf_shop::fsio::quote(s)));
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if !((MIN_SIDE..=MAX_SIDE).contains(&w) && (MIN_SIDE..=MAX_SIDE).contains(&h)) {
        return Err(Error::input("--size", format!("{w}x{h}: each side must be {MIN_SIDE} to {MAX_SIDE} pixels")));
    }
    Ok((w, h))
}

fn parse_light(s: &str) -> Result<DVec3, Error> {
    let v: Option<Vec<f64>> = s.split(',').map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect();
    let quoted = brdf_shop::fsio::quote(s);
    match v.as_deref() {
        Some(&[x, y, z]) => brdf_shop::brdf::material::unit(DVec3::new(x, y, z))
            .ok_or_else(|| Error::input("--light", format!("\"{quoted}\" is not a usable direction (zero length)"))),
        _ => Err(Error::input("--light", format!("expected x,y,z with three finite numbers, got \"{quoted}\""))),
    }
}

/// The view of `--yaw` and `--pitch` (degrees), each defaulting to [`View::DEFAULT`]'s.
fn parse_view(yaw: Option<f64>, pitch: Option<f64>) -> Result<View, Error> {
    if let Some(y) = yaw.filter(|y| !y.is_finite()) {
        return Err(Error::input("--yaw", format!("must be a finite number of degrees, got {y}")));
    }
    if let Some(p) = pitch.filter(|p| !(-90.0..=90.0).contains(p)) {
        return Err(Error::input("--pitch", format!("must be −90 to 90 degrees, got {p}")));
    }
    Ok(View {
        yaw: yaw.map_or(View::DEFAULT.yaw, f64::to_radians),
        pitch: pitch.map_or(View::DEFAULT.pitch, f64::to_radians),
    })
}

/// `--out`: a `.png` in a folder that takes a new file.
fn check_out(out: &Path) -> Result<(), Error> {
    let png = out.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        return Err(Error::input(
            "--out",
            format!("{}: the plot is a PNG; the name must end in .png", brdf_shop::fsio::show(out)),
        ));
    }
    brdf_shop::fsio::check_output("--out", out)
}

pub fn run(args: &PlotArgs) -> anyhow::Result<()> {
    let size = parse_size(&args.size)?;
    let light = match &args.light {
        Some(l) => parse_light(l)?,
        None => brdf_shop::brush::strokes::default_strokes()?.settings("embedded default strokes")?.canvas.light,
    };
    let view = parse_view(args.yaw, args.pitch)?;
    if !(2..=MAX_SAMPLES).contains(&args.samples) {
        return Err(Error::input("--samples", format!("{} is not within 2 and {MAX_SAMPLES}", args.samples)).into());
    }
    check_out(&args.out)?;
    let m = Material::load(&args.material)?;
    let shown = brdf_shop::fsio::show(&args.out);
    match args.kind {
        Kind::Lobe3d => {
            let scale = if args.scale == ScaleArg::Log { Scale::Log } else { Scale::Linear };
            let png = lobe3d_png(&Surface::new(&m, light), view, scale, size)?;
            brdf_shop::fsio::write_atomic(&args.out, &png)?;
            eprintln!("brdf-shop: wrote {shown} (lobe3d, {} lobes)", m.lobes.len());
        }
        Kind::Albedo => {
            brdf_shop::interrupt::install();
            let watch = Watch { advance: &|_| {}, stop: &brdf_shop::interrupt::requested };
            // The measurement of `check`'s report.
            let (_, curve) = albedo_curve_watched(&m, args.samples, watch).ok_or(brdf_shop::interrupt::Interrupted)?;
            let plot = AlbedoPlot::new(&curve, m.energy_sums());
            let png = albedo_png(&plot, size)?;
            brdf_shop::fsio::write_atomic(&args.out, &png)?;
            let a = plot.maximum;
            println!(
                "maximum directional albedo: {} at θ_o = {}°, φ_o = {}° in the {} channel",
                a.value,
                a.theta_deg,
                a.phi_deg,
                ["red", "green", "blue"][a.channel]
            );
            eprintln!("brdf-shop: wrote {shown} (albedo, {} lobes)", m.lobes.len());
        }
    }
    Ok(())
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

fn drawing_error(e: &dyn std::fmt::Display) -> Error {
    Error::input("--out", format!("plotting failed: {e}"))
}

/// RGB pixels as PNG bytes.
fn encode(buf: &[u8], (w, h): (u32, u32)) -> Result<Vec<u8>, Error> {
    use image::ImageEncoder;
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(buf, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::input("--out", format!("cannot encode the plot: {e}")))?;
    Ok(png)
}

/// The 3-D view: [`Surface::project`] fitted under a line of caption.
fn lobe3d_png(s: &Surface, view: View, scale: Scale, (w, h): (u32, u32)) -> Result<Vec<u8>, Error> {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let lines: Vec<Line> = s.project(view, scale);
    let caption = format!(
        "f·cos θi, θi = {:.1}°, peak {:.4}, {}; yaw {:.0}°, pitch {:.0}°",
        s.incident().z.clamp(-1.0, 1.0).acos().to_degrees(),
        s.peak(),
        if scale == Scale::Log { "log (6 decades)" } else { "linear" },
        view.yaw.to_degrees(),
        view.pitch.to_degrees()
    );
    let text_h = 22.0;
    let (ox, oy, r) = brdf_shop::plot::fit(view.frame(), [0.0, text_h, w as f64, h as f64 - text_h], 6.0);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&rgb(BACKGROUND)).map_err(|e| drawing_error(&e))?;
        for l in &lines {
            let pts: Vec<(i32, i32)> =
                l.points.iter().map(|p| ((ox + p[0] * r).round() as i32, (oy - p[1] * r).round() as i32)).collect();
            root.draw(&PathElement::new(pts, rgb(l.colour).stroke_width(1))).map_err(|e| drawing_error(&e))?;
        }
        let font = ("sans-serif", 15).into_font().color(&TEXT);
        root.draw(&Text::new(caption, (6, 4), font)).map_err(|e| drawing_error(&e))?;
        root.present().map_err(|e| drawing_error(&e))?;
    }
    encode(&buf, (w, h))
}

/// The albedo plot: θ_o from 0 to 90° against albedo from 0, each series with its points marked,
/// the energy sum's line and a legend.
fn albedo_png(plot: &AlbedoPlot, (w, h): (u32, u32)) -> Result<Vec<u8>, Error> {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let err = |e: &dyn std::fmt::Display| drawing_error(e);
        root.fill(&rgb(BACKGROUND)).map_err(|e| err(&e))?;
        let a = plot.maximum;
        let caption =
            format!("directional albedo; maximum {:.4} at θo = {}°, φo = {}°", a.value, a.theta_deg, a.phi_deg);
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, ("sans-serif", 16).into_font().color(&TEXT))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..X_MAX_DEG, 0.0..plot.y_max)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc("θo (degrees)")
            .y_desc("albedo (largest over φo and channels)")
            .label_style(("sans-serif", 13).into_font().color(&TEXT))
            .axis_style(TEXT)
            .bold_line_style(GRID)
            .light_line_style(BACKGROUND_GRID)
            .draw()
            .map_err(|e| err(&e))?;
        let bound = rgb(brdf_shop::plot::albedo::BOUND_COLOUR);
        chart
            .draw_series(LineSeries::new([(0.0, plot.bound), (X_MAX_DEG, plot.bound)], bound.stroke_width(1)))
            .map_err(|e| err(&e))?
            .label(format!("ρd + Σρk = {:.4}", plot.bound))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], bound.stroke_width(2)));
        for s in &plot.series {
            let colour = rgb(s.colour);
            let pts: Vec<(f64, f64)> = s.points.iter().map(|p| (p[0], p[1])).filter(|p| p.1.is_finite()).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(1)))
                .map_err(|e| err(&e))?
                .label(s.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 2, colour.filled()))).map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(rgb(BACKGROUND).mix(0.85))
            .border_style(GRID)
            .label_font(("sans-serif", 13).into_font().color(&TEXT))
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    encode(&buf, (w, h))
}

/// The finer grid lines: a shade off the background.
const BACKGROUND_GRID: RGBColor = RGBColor(34, 34, 40);
