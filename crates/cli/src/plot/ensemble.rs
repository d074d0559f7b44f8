//! The picture of an ensemble, drawn with plotters as SVG or PNG: over a 2-D grid a heat map
//! of the first recorded quantity with a colour bar, over one axis a line, over random draws
//! a histogram. Unlike the hand-written figures beside it, it has a colour scale and a raster
//! form; plotters draws both from one description. A PNG's text is set in the DejaVu Sans the
//! binary carries, so it looks the same on every machine.
//!
//! It draws from a [`Picture`]: the first recorded quantity of every run, a number a run,
//! taken as the rows come; a histogram's bins follow from the range of all of them, and a
//! heat map has a cell a run, so every value is kept (8 bytes a run).

use std::error::Error;
use std::path::Path;

use ::ensemble::{Sink, Table};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

/// The picture's size in pixels: the chart, and the colour bar beside a heat map.
const SIZE: (u32, u32) = (760, 600);
const BAR_WIDTH: u32 = 120;
/// The colour of a run that failed.
const FAILED: RGBColor = RGBColor(200, 200, 200);
/// The size of the numbers on the axes, and of the axes' names.
const LABELS: u32 = 14;
const NAMES: u32 = 16;

type Drawn = Result<(), Box<dyn Error>>;

/// What the picture shows, by the ensemble's shape.
enum Kind {
    HeatMap,
    Line,
    Histogram,
}

/// What the picture of an ensemble draws: the first recorded quantity's name and its value
/// in each run, in run order, with the grid's axes.
#[derive(Clone, Debug)]
pub struct Picture {
    name: String,
    /// The column of the first recorded quantity.
    column: usize,
    values: Vec<f64>,
    axes: Vec<(String, Vec<f64>)>,
    random: bool,
}

impl Picture {
    /// The picture of a table with `header`'s columns and axes, with no run yet.
    pub fn new(header: &Table) -> Picture {
        Picture {
            name: header.columns.get(header.varied).cloned().unwrap_or_default(),
            column: header.varied,
            values: Vec::new(),
            axes: header.axes.clone(),
            random: header.random,
        }
    }

    /// The picture of a table kept whole.
    pub fn of(table: &Table) -> Picture {
        let mut picture = Picture::new(table);
        for (row, failure) in table.rows.iter().zip(&table.failures) {
            picture.row(0, row, failure.as_deref());
        }
        picture
    }
}

impl Sink for Picture {
    fn row(&mut self, _run: usize, row: &[f64], _failure: Option<&str>) {
        self.values.push(row[self.column]);
    }
}

/// Writes the ensemble's picture to `path` (whole or not at all), as SVG or PNG by its
/// extension; an ensemble with more than two grid axes has none.
pub fn ensemble(table: &Picture, title: &str, path: &Path) -> Result<(), String> {
    let kind = kind(table.random, table.axes.len())?;
    register_font()?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let drawn = match ext {
        "svg" => {
            let mut svg = String::new();
            let drawn = draw(
                SVGBackend::with_string(&mut svg, SIZE).into_drawing_area(),
                &kind,
                table,
                title,
            );
            drawn.and_then(|()| crate::write_atomically(path, &svg).map_err(Into::into))
        }
        "png" => {
            // Drawn into pixels here and encoded by the png crate: plotters' own encoder goes
            // through the `image` crate and its JPEG decoder, most of a fresh build's
            // dependencies for the one format written.
            let mut rgb = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
            let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
            draw(root, &kind, table, title).and_then(|()| {
                let png = png_of(&rgb, SIZE)?;
                crate::write_atomically_by(path, |tmp| std::fs::write(tmp, &png))
                    .map_err(Into::into)
            })
        }
        _ => return Err(format!("cannot tell the format of {}: use .svg or .png", path.display())),
    };
    drawn.map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// Eight-bit RGB pixels, row by row, as a PNG file's bytes.
fn png_of(rgb: &[u8], (width, height): (u32, u32)) -> Result<Vec<u8>, Box<dyn Error>> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()?;
    Ok(bytes)
}

/// Whether an ensemble varied so has a picture, before it is run.
pub fn check(vary: &[engine::input::Vary]) -> Result<(), String> {
    let random = vary.iter().any(|v| v.spread.is_random());
    kind(random, vary.iter().filter(|v| !v.spread.is_random()).count()).map(|_| ())
}

/// The picture of an ensemble with random draws or with `axes` grid axes.
fn kind(random: bool, axes: usize) -> Result<Kind, String> {
    match (random, axes) {
        (true, _) => Ok(Kind::Histogram),
        (false, 1) => Ok(Kind::Line),
        (false, 2) => Ok(Kind::HeatMap),
        (false, n) => Err(format!(
            "--plot draws one or two grid axes, or random draws; this ensemble has {n} axes"
        )),
    }
}

/// Draws the picture on `root`, whichever the backend.
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    kind: &Kind,
    table: &Picture,
    title: &str,
) -> Drawn
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    match kind {
        Kind::HeatMap => heat_map(table, title, &root)?,
        Kind::Line => line(table, title, &root)?,
        Kind::Histogram => histogram(table, title, &root)?,
    }
    root.present()?;
    Ok(())
}

/// Gives plotters the embedded font under the family name the charts ask for.
fn register_font() -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "the embedded font could not be read".to_string())
}

/// The least and greatest finite values, widened when they coincide.
fn range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (low, high) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
    if low > high {
        return None;
    }
    let pad = if low == high { 0.5 * low.abs().max(1.0) } else { 0.0 };
    Some((low - pad, high + pad))
}

/// The distance between neighbouring values of a grid axis.
fn spacing(values: &[f64]) -> f64 {
    match values {
        [a, b, ..] => (b - a).abs(),
        _ => 1.0,
    }
}

fn heat_map<DB: DrawingBackend>(
    table: &Picture,
    title: &str,
    root: &DrawingArea<DB, Shift>,
) -> Drawn
where
    DB::ErrorType: 'static,
{
    let name = table.name.as_str();
    let (xs, ys) = (&table.axes[0], &table.axes[1]);
    let (dx, dy) = (spacing(&xs.1), spacing(&ys.1));
    let x = range(xs.1.iter().copied()).unwrap_or((0.0, 1.0));
    let y = range(ys.1.iter().copied()).unwrap_or((0.0, 1.0));
    let z = range(table.values.iter().copied()).unwrap_or((0.0, 1.0));
    let (chart_area, bar_area) = root.split_horizontally(SIZE.0 - BAR_WIDTH);
    let mut chart = ChartBuilder::on(&chart_area)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(
            (x.0 - dx / 2.0)..(x.1 + dx / 2.0),
            (y.0 - dy / 2.0)..(y.1 + dy / 2.0),
        )?;
    chart
        .configure_mesh()
        .disable_mesh()
        .label_style(("sans-serif", LABELS))
        .axis_desc_style(("sans-serif", NAMES))
        .x_desc(xs.0.as_str())
        .y_desc(ys.0.as_str())
        .draw()?;
    // Runs are in grid order, the second axis fastest: row k is cell (k / ny, k % ny).
    let ny = ys.1.len();
    chart.draw_series(table.values.iter().enumerate().map(|(k, v)| {
        let (cx, cy) = (xs.1[k / ny], ys.1[k % ny]);
        let v = *v;
        let colour =
            if v.is_finite() { ViridisRGB::get_color_normalized(v, z.0, z.1) } else { FAILED };
        Rectangle::new(
            [(cx - dx / 2.0, cy - dy / 2.0), (cx + dx / 2.0, cy + dy / 2.0)],
            colour.filled(),
        )
    }))?;
    colour_bar(&bar_area, name, z)
}

/// A vertical bar of the colour scale from `z.0` to `z.1`, labelled with `name`.
fn colour_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, name: &str, z: (f64, f64)) -> Drawn
where
    DB::ErrorType: 'static,
{
    let mut bar = ChartBuilder::on(area)
        .margin_top(44)
        .margin_bottom(56)
        .margin_left(4)
        .margin_right(4)
        .right_y_label_area_size(78)
        .build_cartesian_2d(0.0..1.0, z.0..z.1)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .label_style(("sans-serif", LABELS))
        .axis_desc_style(("sans-serif", NAMES))
        .y_desc(name)
        .draw()?;
    let steps = 128;
    let height = (z.1 - z.0) / steps as f64;
    bar.draw_series((0..steps).map(|k| {
        let low = z.0 + height * k as f64;
        let colour = ViridisRGB::get_color_normalized(low + height / 2.0, z.0, z.1);
        Rectangle::new([(0.0, low), (1.0, low + height)], colour.filled())
    }))?;
    Ok(())
}

fn line<DB: DrawingBackend>(table: &Picture, title: &str, root: &DrawingArea<DB, Shift>) -> Drawn
where
    DB::ErrorType: 'static,
{
    let name = table.name.as_str();
    let axis = &table.axes[0];
    let x = range(axis.1.iter().copied()).unwrap_or((0.0, 1.0));
    let y = range(table.values.iter().copied()).unwrap_or((0.0, 1.0));
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", LABELS))
        .axis_desc_style(("sans-serif", NAMES))
        .x_desc(axis.0.as_str())
        .y_desc(name)
        .draw()?;
    // A failed run breaks the line rather than joining its neighbours across it.
    let points: Vec<(f64, f64)> = axis.1.iter().zip(&table.values).map(|(x, v)| (*x, *v)).collect();
    for piece in points.split(|(_, v)| !v.is_finite()).filter(|p| !p.is_empty()) {
        chart.draw_series(LineSeries::new(piece.iter().copied(), BLUE.stroke_width(2)))?;
        chart.draw_series(piece.iter().map(|p| Circle::new(*p, 2, BLUE.filled())))?;
    }
    Ok(())
}

fn histogram<DB: DrawingBackend>(
    table: &Picture,
    title: &str,
    root: &DrawingArea<DB, Shift>,
) -> Drawn
where
    DB::ErrorType: 'static,
{
    let name = table.name.as_str();
    let values: Vec<f64> = table.values.iter().copied().filter(|v| v.is_finite()).collect();
    let x = range(values.iter().copied()).unwrap_or((0.0, 1.0));
    // About √n bins, between 5 and 60: enough to show a shape, few enough to fill each.
    let bins = ((values.len() as f64).sqrt().round() as usize).clamp(5, 60);
    let width = (x.1 - x.0) / bins as f64;
    let mut counts = vec![0usize; bins];
    for v in &values {
        let bin = (((v - x.0) / width) as usize).min(bins - 1);
        counts[bin] += 1;
    }
    let tallest = counts.iter().copied().max().unwrap_or(1).max(1);
    let mut chart = ChartBuilder::on(root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(56)
        .build_cartesian_2d(x.0..x.1, 0.0..tallest as f64 * 1.05)?;
    chart
        .configure_mesh()
        .label_style(("sans-serif", LABELS))
        .axis_desc_style(("sans-serif", NAMES))
        .x_desc(name)
        .y_desc("runs")
        .draw()?;
    chart.draw_series(counts.iter().enumerate().map(|(k, n)| {
        let left = x.0 + width * k as f64;
        Rectangle::new([(left, 0.0), (left + width, *n as f64)], BLUE.mix(0.6).filled())
    }))?;
    Ok(())
}
