//! PNG charts of a trade-off study, drawn with `plotters` into an RGB buffer and saved with
//! `image`: (a) effective Mrays/s against rays per frame (log x), one line per configuration plus
//! the best-of envelope and the crossovers, after Karras & Aila 2013, Figure 1; (b) SAH cost
//! against build time (log x) with the Pareto front highlighted. Each has its legend in a panel
//! at the right, clear of the data. Text is drawn by `TextBackend` in egui's bundled Ubuntu font
//! (no system fonts needed).

use std::path::Path;

use ab_glyph::FontRef;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::text_backend::TextBackend;
use super::{best_ranges, effective_mrays, Measurement};
use crate::{Error, Result};

/// Width and height of every chart, in pixels.
pub const CHART_SIZE: (u32, u32) = (1200, 600);
/// Width of the legend panel at the right of each chart, in pixels.
const LEGEND_WIDTH: u32 = 270;

/// plotters needs a family name; `TextBackend` draws every family in its one font.
const FONT: &str = "sans-serif";

/// Colour families (light to dark): one per builder and treelet size, in order of appearance.
const FAMILIES: [[RGBColor; 3]; 7] = [
    [
        RGBColor(107, 174, 214),
        RGBColor(33, 113, 181),
        RGBColor(8, 48, 107),
    ],
    [
        RGBColor(253, 141, 60),
        RGBColor(217, 72, 1),
        RGBColor(127, 39, 4),
    ],
    [
        RGBColor(116, 196, 118),
        RGBColor(35, 139, 69),
        RGBColor(0, 68, 27),
    ],
    [
        RGBColor(251, 106, 74),
        RGBColor(203, 24, 29),
        RGBColor(103, 0, 13),
    ],
    [
        RGBColor(158, 154, 200),
        RGBColor(106, 81, 163),
        RGBColor(63, 0, 125),
    ],
    [
        RGBColor(150, 150, 150),
        RGBColor(82, 82, 82),
        RGBColor(0, 0, 0),
    ],
    [
        RGBColor(102, 194, 164),
        RGBColor(35, 139, 120),
        RGBColor(0, 90, 70),
    ],
];

/// A colour per measurement: configurations of one builder and treelet size share a hue, darker
/// for the later ones (more rounds, larger split budget).
fn series_colors(measurements: &[Measurement]) -> Vec<RGBColor> {
    let key = |m: &Measurement| (m.builder.clone(), m.treelet_size);
    let mut groups: Vec<(String, Option<u32>)> = Vec::new();
    for m in measurements {
        if !groups.contains(&key(m)) {
            groups.push(key(m));
        }
    }
    measurements
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let group = groups.iter().position(|g| *g == key(m)).unwrap_or(0);
            let members: Vec<usize> = (0..measurements.len())
                .filter(|&j| key(&measurements[j]) == key(m))
                .collect();
            let rank = members.iter().position(|&j| j == i).unwrap_or(0);
            // One member: the middle shade; two: middle and dark; three or more: all three.
            let shade = match members.len() {
                1 => 1,
                2 => rank + 1,
                _ => rank.min(2),
            };
            FAMILIES[group % FAMILIES.len()][shade]
        })
        .collect()
}

/// Draws effective Mrays/s against rays per frame at the sample points `rays` to `path`.
pub fn throughput_chart(
    path: &Path,
    title: &str,
    measurements: &[Measurement],
    rays: &[f64],
) -> Result<()> {
    let colors = series_colors(measurements);
    let usable: Vec<(&Measurement, RGBColor)> = measurements
        .iter()
        .zip(colors)
        .filter(|(m, _)| m.is_usable())
        .collect();
    let (Some(&first), Some(&last)) = (rays.first(), rays.last()) else {
        return Err(Error::InvalidArgument("no rays-per-frame samples".into()));
    };
    let y_max = usable
        .iter()
        .map(|(m, _)| m.mrays_per_s)
        .fold(0.0f64, f64::max)
        .max(1e-6)
        * 1.08;
    let envelope_style = ShapeStyle::from(BLACK.mix(0.2)).stroke_width(9);
    let series_style = |color: RGBColor| ShapeStyle::from(color).stroke_width(2);
    let mut legend = vec![LegendEntry {
        label: "best (envelope)".into(),
        swatch: Swatch::Line(envelope_style),
    }];
    legend.extend(usable.iter().map(|&(m, color)| LegendEntry {
        label: legend_label(m),
        swatch: if m.gpu {
            Swatch::Line(series_style(color))
        } else {
            Swatch::Dashed(series_style(color))
        },
    }));
    save_chart(path, title, &legend, |area| {
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d((first..last).log_scale(), 0.0..y_max)
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .x_desc("rays per frame (build once, then trace)")
            .y_desc("effective Mrays/s = rays / (build + rays / throughput)")
            .x_label_formatter(&|r| rays_label(*r))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .light_line_style(WHITE)
            .draw()
            .map_err(draw_error)?;
        let envelope = rays.iter().map(|&r| {
            let best = usable
                .iter()
                .map(|(m, _)| effective_mrays(m, r))
                .fold(0.0f64, f64::max);
            (r, best)
        });
        chart
            .draw_series(LineSeries::new(envelope, envelope_style))
            .map_err(draw_error)?;
        // The crossovers: where the best configuration changes.
        let best = best_ranges(measurements, first, last);
        for at in best.iter().skip(1).map(|r| r.from_rays) {
            let style = ShapeStyle::from(BLACK.mix(0.5)).stroke_width(1);
            chart
                .draw_series(DashedLineSeries::new([(at, 0.0), (at, y_max)], 4, 4, style))
                .map_err(draw_error)?;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((at, 0.0))
                        + Text::new(rays_label(at), (4, -18), (FONT, 13).into_font()),
                ))
                .map_err(draw_error)?;
        }
        for &(m, color) in &usable {
            // CPU references are dashed: their build time is CPU time, not part of a GPU frame.
            let points: Vec<(f64, f64)> =
                rays.iter().map(|&r| (r, effective_mrays(m, r))).collect();
            if m.gpu {
                chart.draw_series(LineSeries::new(points, series_style(color)))
            } else {
                chart.draw_series(DashedLineSeries::new(points, 10, 6, series_style(color)))
            }
            .map_err(draw_error)?;
        }
        Ok(())
    })
}

/// Draws SAH cost against build time to `path`, the measurements at indices `front` (the Pareto
/// front, ordered by build time) joined, ringed and labelled.
pub fn pareto_chart(
    path: &Path,
    title: &str,
    measurements: &[Measurement],
    front: &[usize],
) -> Result<()> {
    let colors = series_colors(measurements);
    let points: Vec<ParetoPoint> = measurements
        .iter()
        .zip(colors)
        .enumerate()
        .filter(|(_, (m, _))| m.build_ms.is_finite() && m.sah.is_finite())
        .map(|(i, (m, color))| ParetoPoint {
            at: (m.build_ms.max(1e-3), m.sah),
            m,
            color,
            on_front: front.contains(&i),
        })
        .collect();
    if points.is_empty() {
        return Err(Error::InvalidArgument("no measurements to chart".into()));
    }
    let xs = points.iter().map(|p| p.at.0);
    let ys = points.iter().map(|p| p.at.1);
    let (x_min, x_max) = (
        xs.clone().fold(f64::INFINITY, f64::min),
        xs.fold(0.0, f64::max),
    );
    let (y_min, y_max) = (
        ys.clone().fold(f64::INFINITY, f64::min),
        ys.fold(f64::NEG_INFINITY, f64::max),
    );
    let y_pad = ((y_max - y_min) * 0.1).max(y_max.abs() * 0.02).max(1e-3);
    let front_style = ShapeStyle::from(RGBColor(214, 39, 40)).stroke_width(2);
    let mut legend = vec![LegendEntry {
        label: "Pareto front".into(),
        swatch: Swatch::Line(front_style),
    }];
    legend.extend(points.iter().map(|p| LegendEntry {
        label: legend_label(p.m),
        swatch: Swatch::Dot(p.color),
    }));
    save_chart(path, title, &legend, |area| {
        let mut chart = ChartBuilder::on(area)
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(
                (x_min / 2.0..x_max * 4.0).log_scale(),
                (y_min - y_pad)..(y_max + y_pad),
            )
            .map_err(draw_error)?;
        chart
            .configure_mesh()
            .x_desc("build time (ms, log scale; GPU time for GPU builders, CPU time for CPU ones)")
            .y_desc("SAH cost (lower is better)")
            .x_label_formatter(&|ms| ms_label(*ms))
            .label_style((FONT, 13))
            .axis_desc_style((FONT, 14))
            .light_line_style(WHITE)
            .draw()
            .map_err(draw_error)?;
        let front_points = front
            .iter()
            .filter_map(|&i| measurements.get(i))
            .map(|m| (m.build_ms.max(1e-3), m.sah));
        chart
            .draw_series(LineSeries::new(front_points, front_style))
            .map_err(draw_error)?;
        let on_front = || points.iter().filter(|p| p.on_front);
        chart
            .draw_series(on_front().map(|p| Circle::new(p.at, 9, front_style)))
            .map_err(draw_error)?;
        chart
            .draw_series(
                points
                    .iter()
                    .map(|p| Circle::new(p.at, 6, p.color.filled())),
            )
            .map_err(draw_error)?;
        // Labels alternate below and above the front so neighbours overlap less.
        let labels = on_front().enumerate().map(|(k, p)| {
            let dy = if k % 2 == 0 { 6 } else { -20 };
            EmptyElement::at(p.at) + Text::new(legend_label(p.m), (11, dy), (FONT, 13).into_font())
        });
        chart.draw_series(labels).map_err(draw_error)?;
        Ok(())
    })
}

/// One measurement placed on the Pareto chart.
struct ParetoPoint<'a> {
    /// (build ms, clamped for the log axis; SAH)
    at: (f64, f64),
    m: &'a Measurement,
    color: RGBColor,
    on_front: bool,
}

/// One row of a chart's legend panel.
struct LegendEntry {
    label: String,
    swatch: Swatch,
}

enum Swatch {
    Line(ShapeStyle),
    Dashed(ShapeStyle),
    Dot(RGBColor),
}

/// Draws `entries` top-down in `area`.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Drawn {
    const ROW: i32 = 21;
    for (i, entry) in entries.iter().enumerate() {
        let y = 40 + ROW * i as i32;
        let (x0, x1) = (8, 36);
        match entry.swatch {
            Swatch::Line(style) => area.draw(&PathElement::new([(x0, y), (x1, y)], style)),
            Swatch::Dashed(style) => area
                .draw(&PathElement::new([(x0, y), (x0 + 10, y)], style))
                .and_then(|()| area.draw(&PathElement::new([(x1 - 10, y), (x1, y)], style))),
            Swatch::Dot(color) => area.draw(&Circle::new(((x0 + x1) / 2, y), 5, color.filled())),
        }
        .map_err(draw_error)?;
        area.draw(&Text::new(
            entry.label.as_str(),
            (x1 + 8, y - 8),
            (FONT, 14).into_font(),
        ))
        .map_err(draw_error)?;
    }
    Ok(())
}

/// "trbvh n=7 r=3", with " (CPU)" for CPU builders.
fn legend_label(m: &Measurement) -> String {
    if m.gpu {
        m.label.clone()
    } else {
        format!("{} (CPU)", m.label)
    }
}

/// Rays per frame for axes and tables: 1e6 → "1M", 3e10 → "30G".
pub fn rays_label(rays: f64) -> String {
    const UNITS: [(f64, &str); 4] = [(1e12, "T"), (1e9, "G"), (1e6, "M"), (1e3, "k")];
    UNITS
        .iter()
        .find(|(scale, _)| rays >= *scale)
        .map_or(format!("{rays:.0}"), |(scale, unit)| {
            format!("{}{unit}", trim(rays / scale))
        })
}

/// Milliseconds with as few digits as read well: 0.05, 3, 120, 2500.
fn ms_label(ms: f64) -> String {
    trim(ms)
}

fn trim(v: f64) -> String {
    let s = if v >= 10.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    };
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Renders a white chart of `CHART_SIZE` titled `title`, with `legend` in a panel at the right
/// and `draw` drawing the plot in the rest, and writes it as PNG to `path`.
fn save_chart(
    path: &Path,
    title: &str,
    legend: &[LegendEntry],
    draw: impl FnOnce(&DrawingArea<TextBackend<'_, BitMapBackend<'_>>, Shift>) -> Drawn,
) -> Result<()> {
    let (width, height) = CHART_SIZE;
    let mut pixels = vec![0u8; width as usize * height as usize * 3];
    let drawn = FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT)
        .map_err(|e| format!("the bundled chart font does not load: {e}"))
        .and_then(|font| {
            let bitmap = BitMapBackend::with_buffer(&mut pixels, (width, height));
            let root = TextBackend::new(bitmap, font).into_drawing_area();
            root.fill(&WHITE).map_err(draw_error)?;
            let body = root.titled(title, (FONT, 18)).map_err(draw_error)?;
            let (plot, legend_area) = body.split_horizontally(width - LEGEND_WIDTH);
            draw(&plot)?;
            draw_legend(&legend_area, legend)?;
            root.present().map_err(draw_error)
        });
    drawn
        .and_then(|()| {
            image::save_buffer(path, &pixels, width, height, image::ExtendedColorType::Rgb8)
                .map_err(|e| e.to_string())
        })
        .map_err(|message| Error::Write {
            path: path.to_path_buf(),
            message,
        })
}

/// The outcome of drawing a chart: an error message on failure.
type Drawn = std::result::Result<(), String>;

fn draw_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> String {
    format!("drawing failed: {e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_labels_are_short() {
        assert_eq!(rays_label(1e6), "1M");
        assert_eq!(rays_label(3e10), "30G");
        assert_eq!(rays_label(1e12), "1T");
        assert_eq!(ms_label(0.05), "0.05");
        assert_eq!(ms_label(2.5), "2.5");
        assert_eq!(ms_label(120.4), "120");
    }
}
