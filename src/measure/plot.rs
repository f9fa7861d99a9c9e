//! Log–log line plots for the reports (`plotters` on a bitmap, the embedded DejaVu Sans for text),
//! encoded as PNG in memory so the caller writes them atomically.

use plotters::prelude::*;

use crate::error::{Error, Result};

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// One line: its points `(x, y)` (both positive), its colour index and, for the legend, its label
/// (lines sharing a label share one legend entry).
pub struct Series {
    pub label: String,
    pub colour: usize,
    pub points: Vec<(f64, f64)>,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// A log–log plot of `series` as PNG bytes.
pub fn loglog_png(title: &str, x_label: &str, y_label: &str, series: &[Series], size: (u32, u32)) -> Result<Vec<u8>> {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.0.is_finite() && p.1.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(Error::input(title, "nothing to plot: no positive, finite points"));
    }
    let (x0, x1) = pts.iter().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.0), a.1.max(p.0)));
    let (y0, y1) = pts.iter().fold((f64::MAX, f64::MIN), |a, p| (a.0.min(p.1), a.1.max(p.1)));
    let pad = |lo: f64, hi: f64| (lo / 1.5, if hi > lo { hi * 1.5 } else { lo * 2.0 });
    let ((x0, x1), (y0, y1)) = (pad(x0, x1), pad(y0, y1));
    let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        let err = |e: &dyn std::fmt::Display| Error::input(title, format!("plotting failed: {e}"));
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| err(&e))?;
        let mut labelled = std::collections::HashSet::new();
        for s in series {
            let colour = PALETTE[s.colour % PALETTE.len()];
            let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| p.0 > 0.0 && p.1 > 0.0).collect();
            let line = chart.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(1))).map_err(|e| err(&e))?;
            if labelled.insert(s.label.clone()) {
                line.label(s.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(3)));
            }
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 2, colour.filled()))).map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    let mut png = Vec::new();
    use image::ImageEncoder;
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&buf, size.0, size.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::input(title, format!("cannot encode the plot: {e}")))?;
    Ok(png)
}
