//! One figure per channel, like the paper's Figs. 1 and 2: y_i with g_i, e_i, u_i and η̂_i against t.

use quell::study::QUANTILES as Q;
use std::io;
use std::path::Path;
use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use quell::scenario::SignalNames;
use quell::sim::SimResult;
use quell::TimeUnit;

use crate::output::write_atomic;

mod envelope;

const SIZE: (u32, u32) = (1000, 1650);
static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        // DejaVu Sans (see assets/DejaVuSans.LICENSE), so PNGs render on machines without fonts.
        let _ =
            plotters::style::register_font("sans-serif", FontStyle::Normal, include_bytes!("../assets/DejaVuSans.ttf"));
    });
}

type Series = (String, Vec<(f64, f64)>);

/// A panel's chart with two linear f64 axes.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The finite values' range, widened to a non-empty one (±1 around a single value, [−1, 1] for none).
fn value_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.filter(|v| v.is_finite()).fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo < hi {
        (lo, hi)
    } else if lo == hi {
        (lo - 1.0, hi + 1.0)
    } else {
        (-1.0, 1.0)
    }
}

/// [lo, hi] widened about its middle to at least `relative` × its largest magnitude.
fn widened(lo: f64, hi: f64, relative: f64) -> (f64, f64) {
    let (mid, half) = (0.5 * (lo + hi), 0.5 * relative * lo.abs().max(hi.abs()));
    if hi - lo >= 2.0 * half {
        (lo, hi)
    } else {
        (mid - half, mid + half)
    }
}

/// The label of tick value `v` on an axis spanning [lo, hi]: scientific notation when the axis's
/// largest magnitude is below 1e-3 or at least 1e5 (plotters' default prints 1e-6 as "0.0"), plain
/// decimals otherwise; either with the digits that tell ticks about (hi − lo)/10 apart from each
/// other, and no trailing zeros.
fn tick_label(v: f64, lo: f64, hi: f64) -> String {
    let scale = lo.abs().max(hi.abs());
    let spacing = if hi > lo { (hi - lo) / 10.0 } else { scale };
    // A tick at zero computed as lo + k·step can come out as −8.5e-22.
    if v.abs() <= 1e-6 * spacing || !v.is_finite() || !scale.is_normal() {
        return if v.is_finite() { "0".into() } else { v.to_string() };
    }
    // The small offset keeps log10(1e-7) = −7.000…01 at −7.
    let exponent = |x: f64| (x.log10() + 1e-9).floor();
    let spacing_exp = exponent(spacing);
    if !(1e-3..1e5).contains(&scale) {
        let digits = (exponent(scale) - spacing_exp).clamp(0.0, 6.0) as usize;
        let s = format!("{v:.digits$e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa =
            if mantissa.contains('.') { mantissa.trim_end_matches('0').trim_end_matches('.') } else { mantissa };
        format!("{mantissa}e{exp}")
    } else {
        let decimals = (-spacing_exp).clamp(0.0, 9.0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.') } else { &s };
        if s == "-0" {
            "0".into()
        } else {
            s.into()
        }
    }
}

/// One panel of a run's figure: `series` against t (in `time`, the plant's unit of time), with
/// dashed lines at `limit`'s levels (its label, u_min and u_max; an infinite one not drawn) and the
/// view widened to show them, the time
/// axis to `t_right` where that is later, and `column` px right of the plotting area for legends
/// that do not fit beside the data (a figure's panels share both, so that their axes line up).
fn panel<DB: DrawingBackend + Strokes>(
    area: &DrawingArea<DB, Shift>,
    (title, ylabel): (&str, &str),
    series: &[Series],
    (limit, t_right, column): (Option<Limit<'_>>, Option<f64>, u32),
    time: TimeUnit,
) -> Result<(), String> {
    let levels = limit_levels(limit);
    let (((t0, t1), (y0, y1)), legend) = panel_view(area, series, limit, (t_right, column));
    let mut chart = run_panel(area, title, column).build_cartesian_2d(t0..t1, y0..y1).map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_desc(format!("t, {time}"))
        .y_desc(ylabel)
        .x_label_formatter(&|v| tick_label(*v, t0, t1))
        .y_label_formatter(&|v| tick_label(*v, y0, y1))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    let mut entries = lines(&mut chart, series)?;
    if let Some((label, _)) = limit {
        limit_lines(&mut chart, &levels, (t0, t1))?;
        entries.push((label.to_string(), LIMIT_GREY.into(), true));
    }
    match legend {
        Legend::None => Ok(()),
        Legend::Inside(font, size) => {
            label_entries(&mut chart, &entries)?;
            draw_legend(&mut chart, legend_corner(series, ((t0, t1), (y0, y1)), size).0, font)
        }
        Legend::Outside(font, width) => {
            // Beside the plotting area, top-aligned with it, on the panel's own area (plotters
            // clips a chart's legend to its plotting area).
            let (x, y) = chart.plotting_area().get_pixel_range();
            let base = area.get_base_pixel();
            legend_beside(area, (x.end - base.0 + 8, y.start - base.1), &entries, (font, width))
        }
    }
}

/// A legend box `width` px wide (the estimate [`legend_box`] sized the figure's column for) at
/// `(x, y)` of `area` (its top left, px): per entry a 20 px line in its colour (dashed where asked)
/// and its label in `font` px, in the style of [`draw_legend`].
fn legend_beside<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    entries: &[Entry],
    (font, width): (u32, u32),
) -> Result<(), String> {
    let row = font as i32 + 6;
    let (w, h) = (width as i32, 10 + row * entries.len() as i32);
    let text = ("sans-serif", font).into_font().color(&BLACK);
    area.draw(&Rectangle::new([(x, y), (x + w, y + h)], WHITE.mix(0.85).filled())).map_err(|e| e.to_string())?;
    area.draw(&Rectangle::new([(x, y), (x + w, y + h)], BLACK)).map_err(|e| e.to_string())?;
    for (j, (name, color, dashed)) in entries.iter().enumerate() {
        let mid = y + 5 + row * j as i32 + row / 2;
        let line = vec![(x + 6, mid), (x + 26, mid)];
        if *dashed {
            area.draw(&plotters::element::DashedPathElement::new(line, 6, 4, color.stroke_width(2)))
        } else {
            area.draw(&PathElement::new(line, color.stroke_width(2)))
        }
        .map_err(|e| e.to_string())?;
        area.draw(&Text::new(name.as_str(), (x + 32, mid - font as i32 / 2 - 1), text.clone()))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Where a panel's legend goes: nowhere (too many entries: the colours are the key), inside the
/// plotting area at the corner that hides the fewest samples (its font and box as fractions of the
/// area), or right of it (its font and width in px), where a box taller than most of the panel
/// would hide the data in every corner (η̂'s eight or twelve entries over its transients).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Legend {
    None,
    Inside(u32, (f64, f64)),
    Outside(u32, u32),
}

impl Legend {
    /// The px a figure's legend column needs for this legend (0 inside or without one).
    fn column(self) -> u32 {
        match self {
            Legend::Outside(_, width) => width + 16,
            _ => 0,
        }
    }
}

/// A panel's legend at `position`, in the figures' one style: a boxed, nearly opaque white field,
/// labels of `font` px.
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font: u32,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", font))
        .draw()
        .map_err(|e| e.to_string())
}

/// The plotting area's size in pixels of a panel drawn on `area`: the area less the margins (8 px,
/// 24 + a legend `column` on the right), the axis label areas (72 px left, 36 below) and the
/// 20 px caption's ~30 px.
fn plotting_size<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, column: u32) -> (f64, f64) {
    let (w, h) = area.dim_in_pixel();
    ((f64::from(w) - 104.0 - f64::from(column)).max(1.0), (f64::from(h) - 82.0).max(1.0))
}

/// A panel's legend: its font (px) and its box as fractions `size` of the plotting area
/// `(w, h)`, or `None` without one. It holds about eight entries at 14 px and fourteen at 10 px;
/// beyond that (η̂ of a large regressor) it would spill out of the panel, and the colours are the
/// only key.
fn legend_box(series: &[Series], limit: Option<&str>, (w, h): (f64, f64)) -> Option<(u32, (f64, f64))> {
    let font: u32 = match series.len() {
        0..=8 => 14,
        9..=MAX_LEGEND => 10,
        _ => return None,
    };
    let entries = (series.len() + usize::from(limit.is_some())) as f64;
    let names = series.iter().map(|(name, _)| name.as_str()).chain(limit);
    let longest = names.map(|name| name.chars().count()).max().unwrap_or(0) as f64;
    // A 20 px line, the label at ~0.6 em a character, a row per entry, and the ~12 px between the
    // box and the corner (without them a flat e = 0 just below the estimate was hidden by the box).
    let f = f64::from(font);
    Some((font, ((48.0 + 0.6 * f * longest) / w, (20.0 + entries * (f + 6.0)) / h)))
}

/// A panel's view ((t0, t1), (y0, y1)).
type View = ((f64, f64), (f64, f64));

/// A panel's view ((t0, t1), (y0, y1)) over `series` (and `limit`'s levels), its time axis
/// reaching `t_right` at least, with room above the data for its legend or the legend placed right
/// of the plotting area ([`with_headroom`]; `column` px are kept there).
fn panel_view<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    series: &[Series],
    limit: Option<Limit<'_>>,
    (t_right, column): (Option<f64>, u32),
) -> (View, Legend) {
    let (t0, t1) = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|(t, _)| *t))
        .fold((f64::MAX, f64::MIN), |(a, b), t| (a.min(t), b.max(t)));
    let (t0, t1) = if t0 < t1 { (t0, t1) } else { (0.0, 1.0) };
    let t1 = t_right.map_or(t1, |t| t1.max(t));
    let levels = limit_levels(limit);
    let (lo, hi) = value_range(series.iter().flat_map(|(_, p)| p.iter().map(|(_, v)| *v)).chain(levels));
    let pad = 0.05 * (hi - lo);
    let view = ((t0, t1), (lo - pad, hi + pad));
    let plotting = plotting_size(area, column);
    match legend_box(series, limit.map(|(label, _)| label), plotting) {
        Some((font, size)) => match with_headroom(series, view, size) {
            Some(y1) => (((t0, t1), (view.1 .0, y1)), Legend::Inside(font, size)),
            None => (view, Legend::Outside(font, (size.0 * plotting.0).ceil() as u32)),
        },
        None => (view, Legend::None),
    }
}

/// A run figure's panel before its coordinates: the title and the room for the axes' labels, and
/// `column` px right of the plotting area for the figure's legends that do not fit inside.
fn run_panel<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    title: &'b str,
    column: u32,
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(title, ("sans-serif", caption_size(title, area.dim_in_pixel().0, 20)))
        .margin(8)
        .margin_right(24 + column)
        .x_label_area_size(36)
        .y_label_area_size(72);
    builder
}

/// The font size (px, `size` at most, 11 at least) at which a caption of `title` fits `width` px:
/// plotters centres a caption and cuts what passes the area's edges (a u_f panel's "Input 1 (…)"
/// had lost its first letter), at ~0.55 em a character.
fn caption_size(title: &str, width: u32, size: u32) -> u32 {
    let chars = title.chars().count().max(1) as f64;
    let fits = (f64::from(width.saturating_sub(16)) / (0.55 * chars)).floor() as u32;
    fits.clamp(11, size)
}

/// How a backend draws a curve's 2 px line.
trait Strokes {
    /// Whether its wide lines are polygons whose joins spike at sharp turns: plotters' bitmap draws
    /// each segment of a 2 px line as a polygon with an unlimited miter, so a nearly reversing turn
    /// (a decimated slice's lowest-to-highest zigzag, a staircase) drew a spike far past the data and
    /// the axes. SVG viewers limit miters themselves.
    const SPIKES: bool;
}

impl Strokes for BitMapBackend<'_> {
    const SPIKES: bool = true;
}

impl Strokes for SVGBackend<'_> {
    const SPIKES: bool = false;
}

/// A reference's path is a band rather than a line when it runs more than this many times the
/// plot's width (in pixels): a dashed line over it would hide the output that tracks it.
const BAND: f64 = 6.0;

/// The length of `points`' path in pixels of a `w` × `h` area showing `x` × `y`.
fn path_pixels(points: &[(f64, f64)], (w, h): (u32, u32), x: &std::ops::Range<f64>, y: &std::ops::Range<f64>) -> f64 {
    let (sx, sy) = (w as f64 / (x.end - x.start), h as f64 / (y.end - y.start));
    let finite = points.iter().filter(|(t, v)| t.is_finite() && v.is_finite());
    finite.clone().zip(finite.skip(1)).map(|(a, b)| (sx * (b.0 - a.0)).hypot(sy * (b.1 - a.1))).sum()
}

/// M4 decimation (Jugel et al., "M4: A Visualization-Oriented Time Series Data Aggregation", VLDB
/// 2014): per pixel column of a plot `w` pixels wide over t in `x`, the column's first, lowest,
/// highest and last points, in time order. A line through them rasterizes as through all of them;
/// 20,001 rows of a 2000 s run drew 1.2 MB SVGs. A non-finite point is kept and ends its column.
fn m4(points: &[(f64, f64)], x: &std::ops::Range<f64>, w: u32) -> Vec<(f64, f64)> {
    if points.len() <= 4 * w as usize {
        return points.to_vec();
    }
    let scale = w as f64 / (x.end - x.start);
    let finite = |k: usize| points[k].0.is_finite() && points[k].1.is_finite();
    let column = |k: usize| ((points[k].0 - x.start) * scale).floor();
    let mut out = Vec::with_capacity(4 * w as usize + 8);
    let mut i = 0;
    while i < points.len() {
        if !finite(i) {
            out.push(points[i]);
            i += 1;
            continue;
        }
        let (first, c) = (i, column(i));
        let (mut lo, mut hi) = (i, i);
        i += 1;
        while i < points.len() && finite(i) && column(i) == c {
            if points[i].1 < points[lo].1 {
                lo = i;
            }
            if points[i].1 > points[hi].1 {
                hi = i;
            }
            i += 1;
        }
        let mut keep = [first, lo, hi, i - 1];
        keep.sort_unstable();
        for (j, &k) in keep.iter().enumerate() {
            if j == 0 || k != keep[j - 1] {
                out.push(points[k]);
            }
        }
    }
    out
}

/// Each series as a line of its own colour, with its legend entry. A reference ("… (reference)")
/// is drawn last and dashed: an output that tracks it would hide a solid line beneath. A reference
/// fast enough to fill a band ([`BAND`]) is drawn first instead, solid and faint, for the outputs to
/// show over it. Where the backend's wide lines spike ([`Strokes`]), 2 px is three 1 px lines a
/// pixel apart in t and in the value.
fn lines<DB: DrawingBackend + Strokes>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    series: &[Series],
) -> Result<Vec<Entry>, String> {
    let (w, h) = chart.plotting_area().dim_in_pixel();
    let (x, y) = (chart.x_range(), chart.y_range());
    let band = |points: &[(f64, f64)]| path_pixels(points, (w, h), &x, &y) > BAND * w as f64;
    let reference = |name: &str| name.ends_with("(reference)");
    let (under, over): (Vec<_>, Vec<_>) =
        series.iter().enumerate().filter(|(_, (n, _))| reference(n)).partition(|(_, (_, points))| band(points));
    let outputs = series.iter().enumerate().filter(|(_, (n, _))| !reference(n));
    let pixel = ((x.end - x.start) / w.max(1) as f64, (y.end - y.start) / h.max(1) as f64);
    let offsets: &[(f64, f64)] = if DB::SPIKES { &[(0.0, 0.0), (pixel.0, 0.0), (0.0, pixel.1)] } else { &[(0.0, 0.0)] };
    let width = if DB::SPIKES { 1 } else { 2 };
    let faint = under.iter().map(|&(k, _)| k).collect::<Vec<_>>();
    for (k, (name, points)) in under.into_iter().chain(outputs).chain(over) {
        let points = m4(points, &x, w);
        let color = if faint.contains(&k) { pick(k).mix(0.35) } else { pick(k) };
        if let [point] = points[..] {
            // One row (a run that ended before its second): a line of one point draws nothing.
            chart.draw_series(std::iter::once(Circle::new(point, 3, color.filled()))).map_err(|e| e.to_string())?;
            continue;
        }
        let shifted = |(dt, dv): (f64, f64)| points.iter().map(move |&(t, v)| (t + dt, v + dv));
        for &offset in offsets {
            if faint.contains(&k) {
                chart.draw_series(LineSeries::new(shifted(offset), color.stroke_width(1)))
            } else if reference(name) {
                chart.draw_series(DashedLineSeries::new(shifted(offset), 8, 5, color.stroke_width(width)))
            } else {
                // A 2 px SVG line over a 1 px one: on steep segments the wide line's polygons broke
                // up (a transient of ±300 V in 1 ms drew as detached slivers).
                if !DB::SPIKES {
                    chart
                        .draw_series(LineSeries::new(shifted(offset), color.stroke_width(1)))
                        .map_err(|e| e.to_string())?;
                }
                chart.draw_series(LineSeries::new(shifted(offset), color.stroke_width(width)))
            }
            .map_err(|e| e.to_string())?;
        }
    }
    // The key in the series' own order (not the drawing's, which puts references first or last),
    // each entry drawn as its line is.
    Ok(series
        .iter()
        .enumerate()
        .map(|(k, (name, _))| match faint.contains(&k) {
            true => (name.clone(), pick(k).mix(0.35), false),
            false => (name.clone(), pick(k), reference(name)),
        })
        .collect())
}

/// A legend entry: its label, its line's colour, and whether that line is dashed.
type Entry = (String, RGBAColor, bool);

/// Gives the chart's own legend `entries`, in their order.
fn label_entries<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    entries: &[Entry],
) -> Result<(), String> {
    for (name, color, dashed) in entries.iter().cloned() {
        chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
            .map_err(|e| e.to_string())?
            .label(name)
            .legend(move |(x, y)| match dashed {
                true => {
                    plotters::element::DashedPathElement::new(vec![(x, y), (x + 20, y)], 6, 4, color.stroke_width(2))
                        .into_dyn()
                }
                false => PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)).into_dyn(),
            });
    }
    Ok(())
}

/// An actuator limit drawn on a panel: its legend label and its levels (u_min, u_max).
type Limit<'a> = (&'a str, [f64; 2]);

/// The finite levels of `limit`.
fn limit_levels(limit: Option<Limit<'_>>) -> Vec<f64> {
    limit.map_or(vec![], |(_, levels)| levels.into_iter().filter(|u| u.is_finite()).collect())
}

/// The colour of a limit's dashed lines and their legend entry.
const LIMIT_GREY: RGBColor = RGBColor(90, 90, 90);

/// Dashed grey lines at `levels` across `(t0, t1)` (their legend entry is the caller's).
fn limit_lines<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    levels: &[f64],
    (t0, t1): (f64, f64),
) -> Result<(), String> {
    for &level in levels {
        let line = DashedLineSeries::new([(t0, level), (t1, level)], 6, 4, LIMIT_GREY.stroke_width(1));
        chart.draw_series(line).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// The view's top end y1 with the legend box (`size`) inside the plotting area; where the box would
/// hide samples in every corner, the top raised by the box's height where the box is flatter than
/// wide (a few entries), or `None` for a tall, narrow box (η̂'s eight or twelve entries covered its
/// transients), which goes beside the plotting area (the time axis had been extended instead, and
/// every panel of the figure ran 12–33 % past t_end over nothing).
fn with_headroom(
    series: &[Series],
    ((t0, t1), (y0, y1)): ((f64, f64), (f64, f64)),
    (width, height): (f64, f64),
) -> Option<f64> {
    let (_, hidden) = legend_corner(series, ((t0, t1), (y0, y1)), (width, height));
    // 2 % of the axis between the data and the box.
    let gap = 0.02;
    match hidden {
        0 => Some(y1),
        _ if height <= width && height < 0.6 => Some(y0 + (y1 - y0) / (1.0 - height - gap)),
        _ if width < 0.4 => None,
        _ => Some(y1),
    }
}

/// The corner of a panel whose legend box (`size`, as fractions of the plotting area) covers the
/// fewest samples of `series` in the view `((t0, t1), (y0, y1))`, with how many it covers: the
/// upper right unless it hides more than another corner does.
fn legend_corner(
    series: &[Series],
    ((t0, t1), (y0, y1)): ((f64, f64), (f64, f64)),
    size: (f64, f64),
) -> (SeriesLabelPosition, usize) {
    let corners = [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ];
    let inside = |&(right, upper): &(bool, bool), (t, v): (f64, f64)| {
        let (x, y) = ((t - t0) / (t1 - t0), (v - y0) / (y1 - y0));
        (if right { x >= 1.0 - size.0 } else { x <= size.0 }) && (if upper { y >= 1.0 - size.1 } else { y <= size.1 })
    };
    let hidden = |corner: &(bool, bool)| {
        series.iter().flat_map(|(_, p)| p.iter()).filter(|&&point| inside(corner, point)).count()
    };
    // The first of the corners hiding the fewest: the upper right on a tie.
    let best = corners.into_iter().map(|(corner, right, upper)| (corner, hidden(&(right, upper)))).min_by_key(|c| c.1);
    best.unwrap_or((SeriesLabelPosition::UpperRight, 0))
}

/// The k-th series' colour: matplotlib's "tab20" order, its ten strong colours first (told apart in
/// print and by most colour vision), then their light companions, then again (plotters' Palette99,
/// used before past ten, drew black and yellow lines, a black one looking like a grid line).
fn pick(k: usize) -> RGBAColor {
    const TAB20: [(u8, u8, u8); 20] = [
        (31, 119, 180),
        (255, 127, 14),
        (44, 160, 44),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (127, 127, 127),
        (188, 189, 34),
        (23, 190, 207),
        (174, 199, 232),
        (255, 187, 120),
        (152, 223, 138),
        (255, 152, 150),
        (197, 176, 213),
        (196, 156, 148),
        (247, 182, 210),
        (199, 199, 199),
        (219, 219, 141),
        (158, 218, 229),
    ];
    let (r, g, b) = TAB20[k % TAB20.len()];
    RGBColor(r, g, b).to_rgba()
}

/// The most series a panel's legend lists ([`panel`]).
const MAX_LEGEND: usize = 14;

/// Draws channel i's figure (on a white background, see [`write_figure`]); the titles name the
/// channel's output and input where the scenario names them.
fn draw<DB: DrawingBackend + Strokes>(
    root: DrawingArea<DB, Shift>,
    r: &SimResult,
    i: usize,
    names: &SignalNames,
) -> Result<(), String> {
    let span = (r.t.first().copied().unwrap_or(0.0), r.t.last().copied().unwrap_or(0.0));
    let col = |sig: &[f64]| decimated(samples(r, sig, i), span);
    let (c, time) = (i + 1, r.time_unit);
    let named = |given: &Option<Vec<String>>| {
        given.as_ref().and_then(|v| v.get(i)).map_or(String::new(), |n| format!(" ({n})"))
    };
    let (channel, input) =
        (format!("Channel {c}{}", named(&names.outputs)), format!("Input {c}{}", named(&names.inputs)));
    let areas = root.split_evenly((6, 1));
    // A run that stopped early says so where its curves end.
    use quell::sim::Outcome;
    let ended = match &r.outcome {
        None | Some(Outcome::Completed) => String::new(),
        Some(Outcome::Diverged { t, signal, .. }) => {
            format!(" (diverged at t = {} {time}: {signal})", quell::settings::fmt_instant(*t))
        }
        Some(Outcome::Interrupted { t }) => {
            format!(" (interrupted at t = {} {time})", quell::settings::fmt_instant(*t))
        }
        Some(
            Outcome::StepSizeTooSmall { t } | Outcome::TooManySteps { t, .. } | Outcome::HistoryTooLarge { t, .. },
        ) => format!(" (failed at t = {} {time}: summary.json's outcome says why)", quell::settings::fmt_instant(*t)),
    };
    let tracking = [(format!("g{c} (reference)"), col(&r.g)), (format!("y{c}"), col(&r.y))];
    let error = [(format!("e{c}"), col(&r.e))];
    // A sampled run's commands are held between samples ([`SimResult::commands_held`]).
    let held = |sig: &[f64]| if r.commands_held() { decimated(staircase(samples(r, sig, i)), span) } else { col(sig) };
    let command = [(format!("u{c}"), held(&r.u))];
    // The plant input u_f (5), what the actuator must deliver, in its own panel: in a plant's units
    // (newtons, volts) it can be 1e5 times u. The true actuator's limit is drawn where u_f's peak
    // reaches a tenth of it, and its distance told otherwise (the lines would flatten the curve).
    let uf = held(&r.u_f);
    let (uf_title, label, levels) = uf_panel(r, i, &input, &uf);
    let limit = label.as_deref().map(|label| (label, levels));
    let plant_input = [(format!("uf{c}"), uf)];
    let (etas, eta_title) = eta_panel(r, i, span, &channel);
    let panels: [PanelSpec; 5] = [
        (format!("{channel}: output and reference{}{ended}", sampled_at(r)), "y, g", &tracking, None),
        (format!("{channel}: tracking error"), "e = y − g", &error, None),
        (format!("{channel}: adaptive command (25)"), "u", &command, None),
        (uf_title, "u_f", &plant_input, limit),
        (eta_title, "η", &etas, None),
    ];
    let (t_right, column) = shared_axes(&panels, &areas[..5]);
    for ((title, ylabel, series, limit), area) in panels.iter().zip(areas.iter()) {
        panel(area, (title, ylabel), series, (*limit, Some(t_right), column), time)?;
    }
    let (tail, title) = error_on_log_axis(r, i, span, (&channel, !ended.is_empty()));
    envelope::log_panel(&areas[5], (&title, "|e|"), &tail, (span.0, t_right, column), time)?;
    root.present().map_err(|e| e.to_string())
}

/// One time axis for a figure's panels, and one column right of them for the legends that do not
/// fit beside their data (η̂'s), so that the panels line up: (t_right, column px). A column narrows
/// every plotting area, so a legend that fitted inside may not any more: it is widened until no
/// panel needs more (it only grows; two or three passes).
fn shared_axes<DB: DrawingBackend>(panels: &[PanelSpec<'_>], areas: &[DrawingArea<DB, Shift>]) -> (f64, u32) {
    let views = |column: u32| {
        panels.iter().zip(areas.iter()).map(move |((_, _, s, l), a)| panel_view(a, s, *l, (None, column)))
    };
    let mut column = 0;
    for _ in 0..4 {
        let needed = views(column).map(|(_, legend)| legend.column()).max().unwrap_or(0).max(column);
        if needed == column {
            break;
        }
        column = needed;
    }
    (views(column).map(|(view, _)| view.0 .1).fold(f64::MIN, f64::max), column)
}

/// ", sampled at T_s = 0.1 s" for a sampled-data run (at 1 ms its staircases cannot be seen, and
/// the figure had looked like the continuous loop's); "" for a continuous one.
fn sampled_at(r: &SimResult) -> String {
    match r.stats {
        quell::sim::RunStats::Sampled { sample_time, .. } => {
            format!(", sampled at T_s = {} {}", crate::run::short(sample_time), r.time_unit)
        }
        _ => String::new(),
    }
}

/// The last panel's series and title: channel i's error from each time on, on a log axis
/// (convergence over decades); for a run that `stopped` early, |e(t)| itself: the largest from t
/// on is its last spike's everywhere (a flat line for a blow-up, whose onset the linear panels,
/// scaled to that spike, hide too).
fn error_on_log_axis(
    r: &SimResult,
    i: usize,
    span: (f64, f64),
    (channel, stopped): (&str, bool),
) -> ([Series; 1], String) {
    let c = i + 1;
    let e: Vec<(f64, f64)> = samples(r, &r.e, i).collect();
    if stopped {
        (
            // Zeros (an e(0) of 0) have no logarithm: left out, as the envelope leaves them (a
            // bicycle's e₁(0) = 0 had emptied the panel under a title saying e stayed below 1e-14).
            [(format!("|e{c}(t)|"), decimated(e.iter().map(|&(t, v)| (t, v.abs())).filter(|&(_, v)| v > 0.0), span))],
            format!("{channel}: tracking error |e(t)|, log scale (the run stopped early: its growth)"),
        )
    } else {
        (
            [(format!("max |e{c}(s)|, s ≥ t"), envelope::from_t_on(&e, span))],
            format!("{channel}: largest tracking error from t on, log scale"),
        )
    }
}

/// Channel i's η̂_i (33), one series per entry, and the panel's title (`channel` names it).
fn eta_panel(r: &SimResult, i: usize, span: (f64, f64), channel: &str) -> (Vec<Series>, String) {
    let c = i + 1;
    let etas: Vec<Series> = (0..r.q)
        .map(|j| {
            let eta = r.eta.iter().skip(i * r.q + j).step_by(r.m * r.q).copied();
            let pts = decimated(r.t.iter().copied().zip(eta), span);
            (format!("η{c}_{}", j + 1), pts)
        })
        .collect();
    let title = if etas.len() > MAX_LEGEND {
        format!("{channel}: adjustable parameters (33), η{c}_1 … η{c}_{} in the palette's order", etas.len())
    } else {
        format!("{channel}: adjustable parameters (33)")
    };
    (etas, title)
}

/// The u_f panel's title, and its limit's label and levels (u_min, u_max) where it draws them:
/// where u_f's peak reaches a tenth of them, its share of them in the title otherwise (the lines
/// would flatten the curve), and where the limit clipped u_f what the controller asked for.
fn uf_panel(r: &SimResult, i: usize, input: &str, uf: &[(f64, f64)]) -> (String, Option<String>, [f64; 2]) {
    let levels = r.limits(i);
    // u_f's share of its limits: of u_max above 0, of u_min below.
    let share = (uf.iter())
        .map(|&(_, v)| if v >= 0.0 { v / levels[1] } else { v / levels[0] })
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let mut title = format!("{input}: plant input u_f (5), what the actuator delivers");
    let symmetric = levels[0] == -levels[1];
    let label = match levels.map(|u| u.is_finite()) {
        [false, false] => None,
        _ if symmetric => Some(format!("±truth.u_max[{i}] = {}", crate::run::short(levels[1]))),
        _ => Some(format!(
            "truth.u_min[{i}], u_max[{i}] = {}, {}",
            crate::run::short(levels[0]),
            crate::run::short(levels[1])
        )),
    };
    if label.is_some() && share < 0.1 {
        // Two significant digits below 0.1 % ("0.0 %" hid a peak of 0.0018 %).
        let of = if symmetric { "truth.u_max" } else { "truth.u_min, u_max" };
        title += &format!("; peak {} of {of}", quell::settings::fmt_percent(share));
    }
    // Where the limit clipped it, how much the controller asked for (summary.json's max_uf).
    let asked = r.max_uf(i);
    if r.limited.get(i).is_some_and(|&n| n > 0) || levels[1].max(-levels[0]) < asked {
        // A magnitude: with a range that is not symmetric, which end it neared is not known.
        let what = if symmetric { "" } else { "|u_f| " };
        title += &format!("; the controller asked for {what}up to {}", quell::settings::fmt_4(asked));
    }
    (title, label.filter(|_| share >= 0.1), levels)
}

/// A panel of a channel's figure: its title, value axis label, series and actuator limit.
type PanelSpec<'a> = (String, &'a str, &'a [Series], Option<Limit<'a>>);

/// Channel i's samples (t, value) of `signal`, a signal of m columns.
fn samples<'a>(r: &'a SimResult, signal: &'a [f64], i: usize) -> impl Iterator<Item = (f64, f64)> + 'a {
    r.t.iter().copied().zip(r.column(signal, r.m, i))
}

/// The corners of a zero-order hold through `points`: each value kept until the next point's t.
fn staircase(points: impl Iterator<Item = (f64, f64)>) -> impl Iterator<Item = (f64, f64)> {
    let mut held = None;
    points.flat_map(move |(t, v)| held.replace(v).map(|u| (t, u)).into_iter().chain([(t, v)]))
}

/// How many equal slices of a run's time span [`decimated`] keeps points of: two per pixel column.
const SLICES: usize = 2 * SIZE.0 as usize;

/// The points of a series a figure draws: in each of [`SLICES`] equal slices of `(t0, t1)`, the
/// first, lowest, highest and last finite points there, in their order (M4 aggregation, Jugel et
/// al., VLDB 2014). The line through them covers each pixel column as the whole series would, so a
/// run of 10⁷ rows draws as fast and as small as one of 10⁴ (its SVG was 200 MB a channel at 10⁶),
/// and a series of at most one point a slice is kept whole.
fn decimated(points: impl Iterator<Item = (f64, f64)>, (t0, t1): (f64, f64)) -> Vec<(f64, f64)> {
    let scale = if t1 > t0 { SLICES as f64 / (t1 - t0) } else { 0.0 };
    let slice = |t: f64| (((t - t0) * scale).max(0.0) as usize).min(SLICES - 1);
    let mut kept = Vec::new();
    // The slice under way and its first, lowest, highest and last points, each with its index.
    type Four = [(usize, (f64, f64)); 4];
    let mut open: Option<(usize, Four)> = None;
    let flush = |kept: &mut Vec<(f64, f64)>, mut four: Four| {
        four.sort_by_key(|&(k, _)| k);
        let mut last = None;
        for (k, point) in four {
            if last.replace(k) != Some(k) {
                kept.push(point);
            }
        }
    };
    for (k, (t, v)) in points.enumerate().filter(|(_, (_, v))| v.is_finite()) {
        let s = slice(t);
        match &mut open {
            Some((current, [_, low, high, last])) if *current == s => {
                if v < low.1 .1 {
                    *low = (k, (t, v));
                }
                if v > high.1 .1 {
                    *high = (k, (t, v));
                }
                *last = (k, (t, v));
            }
            _ => {
                if let Some((_, four)) = open.replace((s, [(k, (t, v)); 4])) {
                    flush(&mut kept, four);
                }
            }
        }
    }
    if let Some((_, four)) = open {
        flush(&mut kept, four);
    }
    kept
}

/// Writes `channel{i+1}.png` and `.svg` into `dir`, each atomically; t in the run's unit of time.
pub fn plot_channel(dir: &Path, r: &SimResult, i: usize, names: &SignalNames) -> io::Result<()> {
    let name = format!("channel{}", i + 1);
    write_figure(dir, &name, SIZE, |root| draw(root, r, i, names), |root| draw(root, r, i, names))
}

/// Writes an RGB buffer of `size` as a PNG, atomically.
fn write_png(path: &Path, rgb: &[u8], size: (u32, u32)) -> io::Result<()> {
    write_atomic(path, |w| {
        let mut encoder = png::Encoder::new(w, size.0, size.1);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        // Fast deflate: about twice the file size of the default level, a third of the time.
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        writer.write_image_data(rgb).map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    })
}

/// How a sweep's grid axis is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
enum AxisScale {
    /// The numbers themselves.
    Linear,
    /// log10 of the numbers: positive values spanning two decades or more (μ from 1 to 1000 piled
    /// its low points at the left edge of a linear axis).
    Log,
    /// Positions 0, 1, … labelled by the values (vectors, matrices).
    Positions,
}

/// A grid axis's values as plot coordinates and how they are drawn ([`AxisScale`]).
fn axis_coords(values: &[String]) -> (Vec<f64>, AxisScale) {
    match values.iter().map(|v| v.parse::<f64>()).collect::<Result<Vec<f64>, _>>() {
        Ok(x)
            if x.iter().all(|v| v.is_finite() && *v > 0.0)
                && x.iter().fold(0.0f64, |m, v| m.max(*v)) >= 100.0 * x.iter().fold(f64::MAX, |m, v| m.min(*v)) =>
        {
            (x.iter().map(|v| v.log10()).collect(), AxisScale::Log)
        }
        Ok(x) if x.iter().all(|v| v.is_finite()) => (x, AxisScale::Linear),
        _ => ((0..values.len()).map(|k| k as f64).collect(), AxisScale::Positions),
    }
}

/// A decade's label on a log axis at log10 position `v` ("0.01", "1", "1000", "1e5"); none between.
fn decade_label(v: f64) -> String {
    if (v - v.round()).abs() > 1e-6 {
        return String::new();
    }
    let k = v.round() as i32;
    if (-3..=4).contains(&k) {
        format!("{}", 10f64.powi(k))
    } else {
        format!("1e{k}")
    }
}

/// A grid axis's values as tick labels ([`short_value`]: 1.6e6, not 1600000.0).
fn short_values(values: &[String]) -> Vec<String> {
    values.iter().map(|v| short_value(v)).collect()
}

/// A grid value as a tick label: every number in it to 4 significant digits
/// (`[0.0, -6.666666666666667]` reads `[0, -6.667]`), the rest as written.
fn short_value(value: &str) -> String {
    let number = |c: char| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-');
    let mut out = String::new();
    let mut rest = value;
    while let Some(start) = rest.find(number) {
        out.push_str(&rest[..start]);
        let len = rest[start..].find(|c: char| !number(c)).unwrap_or(rest.len() - start);
        let token = &rest[start..start + len];
        match token.parse::<f64>() {
            Ok(v) if v.is_finite() => {
                let short = if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e5) {
                    let t = format!("{v:.3e}");
                    let (mantissa, exp) = t.split_once('e').unwrap_or((&t, "0"));
                    format!("{}e{exp}", mantissa.trim_end_matches('0').trim_end_matches('.'))
                } else {
                    // 4 significant digits, trailing zeros dropped.
                    let magnitude = if v == 0.0 { 0.0 } else { v.abs().log10().floor() };
                    let decimals = (3.0 - magnitude).clamp(0.0, 12.0) as usize;
                    let t = format!("{v:.decimals$}");
                    let t = if t.contains('.') { t.trim_end_matches('0').trim_end_matches('.') } else { &t };
                    if t == "-0" {
                        "0".to_string()
                    } else {
                        t.to_string()
                    }
                };
                out.push_str(if short.len() < token.len() { &short } else { token });
            }
            _ => out.push_str(token),
        }
        rest = &rest[start + len..];
    }
    out.push_str(rest);
    out
}

/// A grid key as an axis label, with the plant's unit of time `unit` where its values are times
/// (delays, β, the simulation's times).
fn key_label(key: &str, unit: &str) -> String {
    const TIMES: [&str; 4] = ["simulation.t_end", "simulation.sample_time", "simulation.output_step", "design.beta"];
    let delays =
        key.strip_suffix(']').map_or(key, |k| k.rsplit_once('[').map_or(k, |(head, _)| head)).ends_with("delays");
    if delays || TIMES.contains(&key) {
        format!("{key}, {unit}")
    } else {
        key.to_string()
    }
}

/// The figures a sweep plots, one row each: the error, the adaptive command u (25), the plant
/// input u_f (5) that the actuator must deliver, and the settling time.
#[derive(Clone, Copy, PartialEq)]
enum SweepFigure {
    TailRmsE,
    MaxU,
    MaxUf,
    SettleT,
}

impl SweepFigure {
    const ALL: [SweepFigure; 4] = [SweepFigure::TailRmsE, SweepFigure::MaxU, SweepFigure::MaxUf, SweepFigure::SettleT];

    /// The axis label; the settling time's carries the study's unit of time.
    fn label(self, unit: &str) -> String {
        match self {
            SweepFigure::TailRmsE => "tail RMS e".into(),
            SweepFigure::MaxU => "max |u|".into(),
            SweepFigure::MaxUf => "max |u_f| (plant input, as asked)".into(),
            SweepFigure::SettleT => format!("settling time, {unit}"),
        }
    }

    /// Whose figure it is: input i's for the plant input u_f (a plant need not pair its inputs with
    /// its outputs: a distillation column's reflux is not its top composition), channel i's else.
    fn whose(self, study: &quell::study::StudyMeta, i: usize) -> String {
        match self {
            SweepFigure::MaxUf => study.input(i),
            _ => study.channel(i),
        }
    }

    /// Its quantiles over a grid point's runs.
    fn quantiles(self, c: &quell::study::ChannelQuantiles) -> &quell::study::Quantiles {
        match self {
            SweepFigure::TailRmsE => &c.tail_rms_e,
            SweepFigure::MaxU => &c.max_u,
            SweepFigure::MaxUf => &c.max_uf,
            SweepFigure::SettleT => &c.settle_t,
        }
    }

    /// Its value in one run: `None` for a settling time never reached.
    fn of_run(self, c: &quell::sim::ChannelFigures) -> Option<f64> {
        match self {
            SweepFigure::TailRmsE => Some(c.tail_rms_e),
            SweepFigure::MaxU => Some(c.max_u),
            SweepFigure::MaxUf => Some(c.max_uf),
            SweepFigure::SettleT => c.settle_t,
        }
    }
}

/// 1-D grid: rows = figures, columns = channels; the median with 25–75 % and 5–95 % bands.
fn draw_sweep_1d<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, s: &quell::study::Summary) -> Result<(), String> {
    let (x, scale) = axis_coords(&s.study.grid[0].values);
    let rows = sweep_1d_rows(s);
    let height = root.dim_in_pixel().1 as i32;
    let (figures, outcomes) = root.split_vertically(height * SweepFigure::ALL.len() as i32 / rows as i32);
    let areas = figures.split_evenly((SweepFigure::ALL.len(), s.study.m));
    for (f, figure) in SweepFigure::ALL.into_iter().enumerate() {
        for i in 0..s.study.m {
            draw_sweep_panel(&areas[f * s.study.m + i], s, (&x, scale), figure, i)?;
        }
    }
    if rows > SweepFigure::ALL.len() {
        draw_outcomes_panel(&outcomes, s, (&x, scale))?;
    }
    root.present().map_err(|e| e.to_string())
}

/// The 1-D figure's rows of panels: the four figures, and a fifth of the outcomes where some grid
/// point has runs that did not complete (a delay-margin study's result, which the figures' empty
/// panels had only hinted at).
fn sweep_1d_rows(s: &quell::study::Summary) -> usize {
    SweepFigure::ALL.len() + usize::from(s.points.iter().any(|p| p.completed < p.runs))
}

/// The grid axis's span over the values at `x`: one value alone gets a span around it that keeps
/// its sign (a delay of 0.1 had an axis from −0.9).
fn grid_span(x: &[f64], scale: AxisScale) -> (f64, f64) {
    let (x0, x1) = x.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let half = if scale == AxisScale::Linear && x0 != 0.0 { 0.5 * x0.abs() } else { 1.0 };
    if x0 < x1 && scale == AxisScale::Linear {
        // A hair wider, so that the end values are ticks: 3.3 / 0.1 rounds below 33, and a grid from
        // 2.7 to 3.3 had no label at its last point.
        let hair = 1e-9 * (x1 - x0);
        (x0 - hair, x1 + hair)
    } else if x0 < x1 {
        (x0, x1)
    } else {
        (x0 - half, x0 + half)
    }
}

/// The right margin of a grid panel: where the positions carry the values, room for half the last
/// value's label (13 px sans-serif, about 0.6 em a character; a matrix's "[[166.7, 0], [0, 166.7]]"
/// was cut at the figure's edge).
fn grid_right_margin(scale: AxisScale, values: &[String]) -> u32 {
    match (scale, values.last()) {
        // At most 140 px: a 15-state matrix's label had squeezed every panel to a sliver.
        (AxisScale::Positions, Some(last)) => {
            ((last.chars().count() as f64 * 13.0 * 0.6 / 2.0).ceil() as u32 + 8).clamp(56, 140)
        }
        _ => 28,
    }
}

/// How many ticks a grid axis of `scale` over `n` values asks for.
fn grid_labels(scale: AxisScale, n: usize) -> usize {
    match scale {
        // As many as the grid has values (up to 12), so that a tick can fall on each.
        AxisScale::Linear => n.clamp(6, 12),
        AxisScale::Log => 12,
        AxisScale::Positions => n.min(12),
    }
}

/// A grid axis's tick label at `v`, for the axis of `scale` spanning (x0, x1) over `values`.
fn grid_tick(v: f64, scale: AxisScale, values: &[String], (x0, x1): (f64, f64)) -> String {
    match scale {
        // Tick values like 2.8000000000000003 read as 2.8, and 1e-7 not as 0 (the y axis's rule).
        AxisScale::Linear => tick_label(v, x0, x1),
        AxisScale::Log => decade_label(v),
        // A value's label only at its own position, not at the ticks between.
        AxisScale::Positions if (v - v.round()).abs() < 1e-6 => {
            values.get(v.round() as usize).cloned().unwrap_or_default()
        }
        AxisScale::Positions => String::new(),
    }
}

/// The bottom row of a 1-D sweep: per grid value, the share of its runs that diverged, failed and
/// were stopped by `[runaway]`, in % (summary.json's `diverged_fraction`, `failed_fraction`,
/// `stopped_fraction`).
fn draw_outcomes_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &quell::study::Summary,
    (x, scale): (&[f64], AxisScale),
) -> Result<(), String> {
    let (x0, x1) = grid_span(x, scale);
    let values = short_values(&s.study.grid[0].values);
    let mut chart = ChartBuilder::on(area)
        .caption("Runs that did not complete, per grid value", ("sans-serif", 18))
        .margin(8)
        .margin_right(grid_right_margin(scale, &values))
        .x_label_area_size(36)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, -5.0..105.0)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_labels(grid_labels(scale, values.len()))
        .x_desc(key_label(&s.study.grid[0].key, &s.study.time_unit))
        .y_desc("% of the point's runs")
        .y_labels(6)
        .x_label_formatter(&|v| grid_tick(*v, scale, &values, (x0, x1)))
        .y_label_formatter(&|v| tick_label(*v, 0.0, 100.0))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|e| e.to_string())?;
    let shares = [
        ("diverged", s.points.iter().map(|p| p.diverged_fraction).collect::<Vec<_>>()),
        ("failed", s.points.iter().map(|p| p.failed_fraction).collect()),
        ("stopped", s.points.iter().map(|p| p.stopped_fraction).collect()),
    ];
    let series: Vec<Series> = shares
        .into_iter()
        .map(|(name, share)| {
            (name.to_string(), s.points.iter().zip(share).map(|(p, f)| (x[p.point], 100.0 * f)).collect())
        })
        .collect();
    for (k, (name, pts)) in series.iter().enumerate() {
        let color = pick(k + 3);
        chart.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2))).map_err(|e| e.to_string())?;
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(|e| e.to_string())?
            .label(name.as_str())
            .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
    }
    // Where the box hides the fewest points (the upper left had covered 79 % diverged at τ₂ = 2.7 s).
    let (corner, _) = legend_corner(&series, ((x0, x1), (-5.0, 105.0)), (0.15, 0.3));
    draw_legend(&mut chart, corner, 14)
}

/// The grid axis's description under a sweep panel: the key and its unit, the scale, and with
/// draws what the bands are over (the completed draws, counted where some did not complete).
fn grid_axis_desc(s: &quell::study::Summary, scale: AxisScale) -> String {
    let mut x_desc = key_label(&s.study.grid[0].key, &s.study.time_unit);
    if scale == AxisScale::Log {
        x_desc += " (log scale)";
    }
    if s.study.draws > 1 {
        // Over the completed draws only: say how many those are where some did not complete.
        let done = s.points.iter().map(|p| p.completed);
        let (fewest, most) = done.fold((usize::MAX, 0), |(a, b), c| (a.min(c), b.max(c)));
        let of = match (fewest, most) {
            _ if fewest >= s.study.draws => format!("{} draws", s.study.draws),
            (f, m) if f == m => format!("the completed draws ({f} of {})", s.study.draws),
            (f, m) => format!("the completed draws ({f}–{m} of {})", s.study.draws),
        };
        x_desc += &format!("; median and 25–75, 5–95 % bands of {of}");
    }
    x_desc + &partial(s)
}

/// "; partial: 47 runs done of the study's 84 (--resume completes it)" for a sweep stopped before
/// its end (its empty grid values had looked like values with nothing to show); "" otherwise.
fn partial(s: &quell::study::Summary) -> String {
    if s.partial {
        format!("; partial: {} runs done of the study's {} (--resume completes it)", s.runs_done, s.study.runs)
    } else {
        String::new()
    }
}

/// One panel of [`draw_sweep_1d`]: channel i's `figure` against the grid's values at `x`, drawn
/// as `scale` says.
fn draw_sweep_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    s: &quell::study::Summary,
    (x, scale): (&[f64], AxisScale),
    figure: SweepFigure,
    i: usize,
) -> Result<(), String> {
    let axis = &s.study.grid[0];
    let label = figure.label(&s.study.time_unit);
    let raw = |p: f64| s.points.iter().filter_map(move |pt| figure.quantiles(&pt.channels[i]).at(p));
    // Positive values spanning two decades or more (an error falling from 1e-2 to 1e-5 along
    // the grid) are drawn on a log axis; on a linear one all but the largest lay flat.
    let (lo, hi) = value_range([Q[0], Q[4]].iter().flat_map(|&p| raw(p)));
    let log = lo > 0.0 && hi >= 100.0 * lo;
    let at = |p: f64| -> Vec<(f64, f64)> {
        s.points
            .iter()
            .filter_map(|pt| {
                figure.quantiles(&pt.channels[i]).at(p).map(|v| (x[pt.point], if log { v.log10() } else { v }))
            })
            .collect()
    };
    let (lo, hi) = value_range([Q[0], Q[2], Q[4]].iter().flat_map(|&p| at(p)).map(|(_, v)| v));
    let empty = at(0.5).is_empty();
    // A linear axis spans at least 2 % of the values: a change of 0.24 % along the grid (channel
    // 2's tail against μ₁) had filled the panel as a jump, as if the channels were coupled.
    let (lo, hi) = widened(lo, hi, if log { 1e-3 } else { 0.02 });
    let (x0, x1) = grid_span(x, scale);
    let pad = 0.05 * (hi - lo);
    let (y0, y1) = (lo - pad, hi + pad);
    let values = short_values(&axis.values);
    let mut chart = ChartBuilder::on(area)
        .caption(format!("{}: {label}", figure.whose(&s.study, i)), ("sans-serif", 18))
        .margin(8)
        .margin_right(grid_right_margin(scale, &values))
        .x_label_area_size(36)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    let fmt = |v: &f64| grid_tick(*v, scale, &values, (x0, x1));
    let x_desc = grid_axis_desc(s, scale);
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_labels(grid_labels(scale, axis.values.len()))
        .x_desc(x_desc)
        .y_desc(if log { format!("{label} (log scale)") } else { label.to_string() })
        .y_labels(if empty { 0 } else { 10 })
        .x_label_formatter(&fmt)
        .y_label_formatter(&|v| if log { decade_label(*v) } else { tick_label(*v, y0, y1) })
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(|e| e.to_string())?;
    // A settling time some draws never reached: its upper quantiles are "never", beyond any value
    // on the axis, so their bands run to its top (they had vanished, leaving a median alone that
    // looked certain where a quarter of the draws never settled).
    let settling = matches!(figure, SweepFigure::SettleT);
    let never = |pt: &quell::study::PointSummary| pt.channels[i].never_settled.filter(|&f| settling && f > 0.0);
    let most_never = s.points.iter().filter_map(never).fold(0.0, f64::max);
    let band_at = |p: f64| -> Vec<(f64, f64)> {
        s.points
            .iter()
            .filter_map(|pt| match figure.quantiles(&pt.channels[i]).at(p) {
                Some(v) => Some((x[pt.point], if log { v.log10() } else { v })),
                None => never(pt).map(|_| (x[pt.point], y1)),
            })
            .collect()
    };
    let medians = draw_quantile_bands(&mut chart, (&at, &band_at), pick(i), 0.01 * (x1 - x0))?;
    if most_never > 0.0 {
        let note = never_settled_note(most_never, medians < s.points.len());
        missing_median_note(&mut chart, note, (empty, &at(0.5)), (x0, x1), (y0, y1))?;
    } else if medians < s.points.len() {
        let note = missing_median(figure, empty);
        missing_median_note(&mut chart, note, (empty, &at(0.5)), (x0, x1), (y0, y1))?;
    }
    Ok(())
}

/// The settling-time panel's note where draws never settled: the largest share at a grid point,
/// and that the bands run to the top (and, `median_missing`, why some points have no median).
fn never_settled_note(most: f64, median_missing: bool) -> [String; 2] {
    let then = if median_missing {
        "bands run to the top; no median where half or more"
    } else {
        "their bands run to the top"
    };
    [format!("up to {} of a point's completed draws never settled:", quell::settings::fmt_percent(most)), then.into()]
}

/// A figure's quantile at level p at each grid point, as (x, value) points.
type QuantileCurve<'a> = &'a dyn Fn(f64) -> Vec<(f64, f64)>;

/// The 5–95 % and 25–75 % bands of the quantile curves `band_at(p)` and the median line of
/// `at(0.5)`, in `color` (a band of one point: a bar `half_width` either side of it); returns the
/// number of points that have a median.
fn draw_quantile_bands<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    (at, band_at): (QuantileCurve<'_>, QuantileCurve<'_>),
    color: RGBAColor,
    half_width: f64,
) -> Result<usize, String> {
    for (a, b, alpha) in [(Q[0], Q[4], 0.15), (Q[1], Q[3], 0.3)] {
        let style = color.mix(alpha).filled();
        for span in band_spans(&band_at(a), &band_at(b)) {
            if let [(x, lo, hi)] = span[..] {
                let bar = Rectangle::new([(x - half_width, lo), (x + half_width, hi)], style);
                chart.draw_series(std::iter::once(bar)).map_err(|e| e.to_string())?;
            } else {
                let ring = span.iter().map(|&(x, lo, _)| (x, lo)).chain(span.iter().rev().map(|&(x, _, hi)| (x, hi)));
                chart
                    .draw_series(std::iter::once(Polygon::new(ring.collect::<Vec<_>>(), style)))
                    .map_err(|e| e.to_string())?;
            }
        }
    }
    let median = at(0.5);
    chart.draw_series(LineSeries::new(median.iter().copied(), color.stroke_width(2))).map_err(|e| e.to_string())?;
    chart.draw_series(median.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(|e| e.to_string())?;
    Ok(median.len())
}

/// The runs of consecutive points (x, low, high) that have both quantiles: a band is drawn over
/// each, so that a point without its upper quantile (a settling time that 5 % of the draws never
/// reached) breaks the band there instead of removing it from every point.
fn band_spans(low: &[(f64, f64)], high: &[(f64, f64)]) -> Vec<Vec<(f64, f64, f64)>> {
    let mut xs: Vec<f64> = low.iter().chain(high).map(|p| p.0).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let value = |v: &[(f64, f64)], x: f64| v.iter().find(|p| p.0 == x).map(|p| p.1);
    let mut spans = vec![Vec::new()];
    for x in xs {
        match (value(low, x), value(high, x)) {
            (Some(lo), Some(hi)) => spans.last_mut().expect("one span at least").push((x, lo, hi)),
            _ => spans.push(Vec::new()),
        }
    }
    spans.retain(|s| !s.is_empty());
    spans
}

/// Writes `lines` in the first corner of a panel spanning `xs` × `ys` that no point of `curve`
/// lies under (top left, bottom left, top right, bottom right; else the one with the fewest), or
/// in the middle of an `empty` one. (Bottom left had been taken whenever the top left was not: a
/// curve rising from there ran under the note.)
fn missing_median_note<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    lines: [String; 2],
    (empty, curve): (bool, &[(f64, f64)]),
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), String> {
    let (x, y) = match empty {
        false => {
            let (left, top) = note_corner(curve, (x0, x1), (y0, y1));
            (x0 + left * (x1 - x0), y0 + top * (y1 - y0))
        }
        true => (x0 + 0.1 * (x1 - x0), 0.5 * (y0 + y1)),
    };
    let font = ("sans-serif", 13).into_font().color(&RGBColor(90, 90, 90));
    let ats = [(x, y), (x, y - 0.07 * (y1 - y0))];
    chart
        .draw_series(lines.into_iter().zip(ats).map(|(line, at)| Text::new(line, at, font.clone())))
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// [`missing_median_note`]'s corner, as fractions of the panel (its left edge, its first line's
/// height): the note spans 0.65 of the width and 0.2 of the height below its first line.
fn note_corner(curve: &[(f64, f64)], (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> (f64, f64) {
    const CORNERS: [(f64, f64); 4] = [(0.02, 0.97), (0.02, 0.19), (0.33, 0.97), (0.33, 0.19)];
    // The curve's points and 20 along each segment between them (a line from (0, 0.5) to
    // (60, 1) crossed the top-left note with no point under it; diff review).
    let along: Vec<(f64, f64)> = (curve.windows(2))
        .flat_map(|w| (0..20).map(move |k| (k as f64 / 20.0, w[0], w[1])))
        .map(|(t, a, b)| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)))
        .chain(curve.last().copied())
        .collect();
    let under = |&(left, top): &(f64, f64)| {
        let inside = |&&(x, y): &&(f64, f64)| {
            let (u, v) = ((x - x0) / (x1 - x0), (y - y0) / (y1 - y0));
            (left - 0.02..=left + 0.65).contains(&u) && (top - 0.2..=top + 0.03).contains(&v)
        };
        along.iter().filter(inside).count()
    };
    *CORNERS.iter().find(|c| under(c) == 0).unwrap_or_else(|| CORNERS.iter().min_by_key(|c| under(c)).expect("four"))
}

/// Why a sweep panel lacks the median at some (`all`: every) grid point, in two short lines: no
/// completed run there, or, for the settling time, half its runs or more never settled
/// (summary.json's `never_settled`).
fn missing_median(figure: SweepFigure, all: bool) -> [String; 2] {
    let head = if all { "no grid point has a median:" } else { "some grid points have no median:" };
    let why = match figure {
        SweepFigure::SettleT => "no completed run, or half or more never settled (summary.json's never_settled)",
        _ => "no completed run there (summary.json's outcomes)",
    };
    [head.into(), why.into()]
}

/// A colour from dark blue (t = 0) through green to yellow (t = 1), roughly viridis.
fn ramp(t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0);
    let stops =
        [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
    let k = (t * 4.0).floor().min(3.0) as usize;
    let u = t * 4.0 - k as f64;
    let (a, b) = (stops[k], stops[k + 1]);
    let mix = |x: f64, y: f64| (x + u * (y - x)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// 2-D grid: per channel, a heat map of the median tail RMS e (log colour scale), the value in
/// each cell.
fn draw_sweep_2d<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, s: &quell::study::Summary) -> Result<(), String> {
    let (ax, ay) = (&s.study.grid[0], &s.study.grid[1]);
    let (nx, ny) = (ax.values.len(), ay.values.len());
    let areas = root.split_evenly((1, s.study.m));
    for (i, area) in areas.iter().enumerate() {
        let cell = |pt: &quell::study::PointSummary| pt.channels[i].tail_rms_e.p50.filter(|v| *v > 0.0);
        let logs: Vec<f64> = s.points.iter().filter_map(cell).map(f64::log10).collect();
        let (lo, span, digits) = colour_scale(&logs);
        // The colours' scale beside the cells: each channel has its own.
        let (cells, scale) = area.split_horizontally(area.dim_in_pixel().0.saturating_sub(COLOUR_BAR) as i32);
        if !logs.is_empty() {
            colour_bar(&scale, lo, span)?;
        }
        // Grey cells, "—", have no median: say so where there are any; a cell whose runs did not all
        // complete counts them (a cell of 1 completed run in 6 had been drawn as the map's best).
        let grey = if s.points.iter().any(|pt| cell(pt).is_none()) { " (—: no completed run)" } else { "" };
        let labelled = nx * ny <= 144;
        let short = s.points.iter().any(|pt| pt.completed < pt.runs);
        let counted = if labelled && short { " (k/n: completed of a cell's runs)" } else { "" };
        let title = format!("{}: median tail RMS e{grey}{counted}{}", s.study.channel(i), partial(s));
        let size = caption_size(&title, cells.dim_in_pixel().0, 18);
        let mut chart = ChartBuilder::on(&cells)
            .caption(title, ("sans-serif", size))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..nx as f64 - 0.5, -0.5..ny as f64 - 0.5)
            .map_err(|e| e.to_string())?;
        let (xv, yv) = (short_values(&ax.values), short_values(&ay.values));
        let fx = move |v: &f64| xv.get(v.round().max(0.0) as usize).cloned().unwrap_or_default();
        let fy = move |v: &f64| yv.get(v.round().max(0.0) as usize).cloned().unwrap_or_default();
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(nx.min(12))
            .y_labels(ny.min(12))
            .x_desc(key_label(&ax.key, &s.study.time_unit))
            .y_desc(key_label(&ay.key, &s.study.time_unit))
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(|e| e.to_string())?;
        for pt in &s.points {
            let (gx, gy) = (pt.point / ny, pt.point % ny);
            let (x, y) = (gx as f64, gy as f64);
            let (shade, text) = match cell(pt) {
                Some(v) => ((v.log10() - lo) / span, format!("{v:.digits$e}")),
                None => (1.0, "—".to_string()),
            };
            let color = if text == "—" { RGBColor(200, 200, 200) } else { ramp(shade) };
            let ink = if shade > 0.6 { BLACK } else { WHITE };
            chart
                .draw_series(std::iter::once(Rectangle::new([(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)], color.filled())))
                .map_err(|e| e.to_string())?;
            if labelled {
                chart
                    .draw_series(std::iter::once(Text::new(
                        text,
                        (x - 0.3, y + 0.1),
                        ("sans-serif", 12).into_font().color(&ink),
                    )))
                    .map_err(|e| e.to_string())?;
                if pt.completed < pt.runs {
                    let share = format!("{}/{}", pt.completed, pt.runs);
                    let font = ("sans-serif", 12).into_font().color(&ink);
                    chart
                        .draw_series(std::iter::once(Text::new(share, (x - 0.3, y - 0.15), font)))
                        .map_err(|e| e.to_string())?;
                }
            }
        }
    }
    root.present().map_err(|e| e.to_string())
}

/// The width of a heat map's colour bar, its labels included (px).
const COLOUR_BAR: u32 = 110;

/// A heat map's colour bar: [`ramp`] over log10 of the values from `lo` to `lo + span`, labelled
/// with the values and titled with what they are.
/// The least span of a heat map's colours, in decades: a factor of 2.
const MIN_COLOUR_SPAN: f64 = std::f64::consts::LOG10_2;

/// A heat map's colour scale over the decades `logs`: its lowest decade and span, over a factor of
/// 2 at least about the medians (a spread of 0.08 % had run from dark blue to yellow, as if μ
/// mattered; helper tryout, 2026-12-06), and the cell labels' decimals that tell them apart.
fn colour_scale(logs: &[f64]) -> (f64, f64, usize) {
    let (lo, hi) = logs.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
    let span = (hi - lo).max(MIN_COLOUR_SPAN);
    (0.5 * (lo + hi - span), span, telling_digits(hi - lo))
}

/// Decimals (of `{:.De}`) that tell apart values spanning `decades` (log10 of the largest over the
/// smallest): 2 from a 10 % spread, up to 5.
fn telling_digits(decades: f64) -> usize {
    let spread = 10f64.powf(decades) - 1.0;
    match spread > 0.0 {
        true => ((-spread.log10()).ceil().max(2.0) as usize).min(5),
        false => 2,
    }
}

fn colour_bar<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, lo: f64, span: f64) -> Result<(), String> {
    let mut bar = ChartBuilder::on(area)
        .caption("tail RMS e", ("sans-serif", 13))
        .margin_top(22)
        .margin_bottom(48)
        .margin_left(14)
        .margin_right(4)
        .right_y_label_area_size(62)
        .build_cartesian_2d(0.0..1.0, lo..lo + span)
        .map_err(|e| e.to_string())?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(6)
        // A space between the tick and the label: "-1.0e-5" read as a negative value.
        .y_label_formatter(&|v| format!(" {:.1e}", 10f64.powf(*v)))
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(|e| e.to_string())?;
    const STEPS: usize = 64;
    let band = |k: usize| lo + span * k as f64 / STEPS as f64;
    bar.draw_series(
        (0..STEPS).map(|k| {
            Rectangle::new([(0.0, band(k)), (1.0, band(k + 1))], ramp((k as f64 + 0.5) / STEPS as f64).filled())
        }),
    )
    .map_err(|e| e.to_string())?;
    Ok(())
}

/// Writes `<name>.png` and `<name>.svg` of `size` into `dir`, each atomically, drawn by `png` and
/// `svg` (the same drawing on the two backends).
fn write_figure(
    dir: &Path,
    name: &str,
    size: (u32, u32),
    png: impl FnOnce(DrawingArea<BitMapBackend, Shift>) -> Result<(), String>,
    svg: impl FnOnce(DrawingArea<SVGBackend, Shift>) -> Result<(), String>,
) -> io::Result<()> {
    register_font();
    let path = dir.join(format!("{name}.png"));
    let mut rgb = vec![255u8; (size.0 * size.1 * 3) as usize];
    png(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area())
        .map_err(|e| io::Error::other(format!("{}: {e}", path.display())))?;
    write_png(&path, &rgb, size)?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| io::Error::other(e.to_string()))?;
        svg(root).map_err(io::Error::other)?;
    }
    write_atomic(&dir.join(format!("{name}.svg")), |w| w.write_all(text.as_bytes()))
}

/// The empirical distribution function of sorted `x` among `draws` draws (those without a value
/// lie above every x) as the corners of its staircase: up by 1/draws at each value.
fn ecdf(x: &[f64], draws: usize) -> Vec<(f64, f64)> {
    let n = draws.max(1) as f64;
    x.iter().enumerate().flat_map(|(k, &v)| [(v, k as f64 / n), (v, (k + 1) as f64 / n)]).collect()
}

/// ", of the completed; 20 stopped (by [runaway]), 3 diverged, 1 failed" where some draws did not
/// complete: their figures are not drawn (a stopped draw's peaks are a runaway's), and "have a
/// value" had read as if they had none.
fn not_completed(rows: &[quell::study::Row]) -> String {
    use quell::study::Outcome;
    let count = |o: Outcome| rows.iter().filter(|r| r.outcome == o).count();
    let parts: Vec<String> =
        [(Outcome::Stopped, "stopped (by [runaway])"), (Outcome::Diverged, "diverged"), (Outcome::Failed, "failed")]
            .into_iter()
            .filter_map(|(o, name)| Some(count(o)).filter(|&n| n > 0).map(|n| format!("{n} {name}")))
            .collect();
    if parts.is_empty() {
        String::new()
    } else {
        format!(", of the completed; {}", parts.join(", "))
    }
}

/// No grid, only draws (a Monte Carlo study): per channel and figure, the empirical distribution
/// function over the draws, the fraction of all draws at or below a value. Diverged, failed and
/// never-settled draws lie above every value, so a curve ends at the share of draws that have one.
fn draw_distributions<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    s: &quell::study::Summary,
    rows: &[quell::study::Row],
) -> Result<(), String> {
    let areas = root.split_evenly((SweepFigure::ALL.len(), s.study.m));
    let draws = rows.len();
    for (f, figure) in SweepFigure::ALL.into_iter().enumerate() {
        let label = figure.label(&s.study.time_unit);
        for i in 0..s.study.m {
            let mut values: Vec<f64> = rows
                .iter()
                .filter_map(|r| r.completed().get(i).and_then(|c| figure.of_run(c)))
                .filter(|v| v.is_finite())
                .collect();
            values.sort_by(f64::total_cmp);
            let (lo, hi) = value_range(values.iter().copied());
            let log = values.first().is_some_and(|&v| v > 0.0) && hi >= 100.0 * lo;
            let x: Vec<f64> = if log { values.iter().map(|v| v.log10()).collect() } else { values.clone() };
            let (x0, x1) = value_range(x.iter().copied());
            let (x0, x1) = if log { (x0.floor(), x1.ceil()) } else { widened(x0, x1, 1e-3) };
            let pad = if log { 0.0 } else { 0.05 * (x1 - x0) };
            let (x0, x1) = (x0 - pad, x1 + pad);
            let mut chart = ChartBuilder::on(&areas[f * s.study.m + i])
                .caption(format!("{}: {label}", figure.whose(&s.study, i)), ("sans-serif", 18))
                .margin(8)
                .margin_right(28)
                .x_label_area_size(36)
                .y_label_area_size(60)
                .build_cartesian_2d(x0..x1, 0.0..1.02)
                .map_err(|e| e.to_string())?;
            let x_desc = format!(
                "{label}{}; {} of {} draws have a value{}",
                if log { " (log scale)" } else { "" },
                values.len(),
                rows.len(),
                not_completed(rows)
            );
            chart
                .configure_mesh()
                .max_light_lines(2)
                .x_labels(if log { 12 } else { 6 })
                .x_desc(x_desc)
                .y_desc("fraction of draws ≤ value")
                .x_label_formatter(&|v| if log { decade_label(*v) } else { tick_label(*v, x0, x1) })
                .y_label_formatter(&|v| tick_label(*v, 0.0, 1.0))
                .label_style(("sans-serif", 13))
                .draw()
                .map_err(|e| e.to_string())?;
            if x.is_empty() {
                let why = if figure == SweepFigure::SettleT { "no draw settled" } else { "no draw completed" };
                missing_median_note(&mut chart, [why.into(), String::new()], (true, &[]), (x0, x1), (0.0, 1.02))?;
                continue;
            }
            let color = pick(i);
            chart.draw_series(LineSeries::new(ecdf(&x, draws), color.stroke_width(2))).map_err(|e| e.to_string())?;
        }
    }
    root.present().map_err(|e| e.to_string())
}

/// Writes sweep.png and sweep.svg: for a 1-D or 2-D grid, the figures against the grid; without
/// a grid, their distributions over the draws. A grid of three keys or more has no figure (`false`).
pub fn plot_sweep(dir: &Path, s: &quell::study::Summary, rows: &[quell::study::Row]) -> io::Result<bool> {
    // A channel gets 640 px: the grid axis's description (key, unit, bands, completed draws) fits
    // on one line.
    let size = |height| ((640 * s.study.m as u32).max(700), height);
    let height = 300 * SweepFigure::ALL.len() as u32;
    match s.study.grid.len() {
        1 => {
            let height = 300 * sweep_1d_rows(s) as u32;
            write_figure(dir, "sweep", size(height), |r| draw_sweep_1d(r, s), |r| draw_sweep_1d(r, s))
        }
        0 => write_figure(
            dir,
            "sweep",
            size(height),
            |r| draw_distributions(r, s, rows),
            |r| draw_distributions(r, s, rows),
        ),
        2 => write_figure(dir, "sweep", size(520), |r| draw_sweep_2d(r, s), |r| draw_sweep_2d(r, s)),
        _ => return Ok(false),
    }?;
    Ok(true)
}

/// "Channel 1 (heading)" where the scenario names its outputs, else "Channel 1" (0-based `i`).
fn channel_title(i: usize, outputs: &[String]) -> String {
    outputs.get(i).map_or(format!("Channel {}", i + 1), |n| format!("Channel {} ({n})", i + 1))
}

/// tune.png/.svg: per channel, the objective against μ_i (log scale), the chosen μ_i marked.
fn draw_tune<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    r: &quell::study::TuneResult,
    (unit, outputs): (TimeUnit, &[String]),
) -> Result<(), String> {
    let areas = root.split_evenly((1, r.channels.len()));
    let objective = match r.objective {
        quell::study::Objective::SettleT => format!("settle_t, {unit}"),
        other => other.name().to_string(),
    };
    for (c, area) in r.channels.iter().zip(areas.iter()) {
        if c.curve.is_empty() {
            // A tuning stopped before this channel's first evaluation.
            let title = format!("{}: not evaluated (tuning stopped)", channel_title(c.channel, outputs));
            area.titled(&title, ("sans-serif", 18)).map_err(|e| e.to_string())?;
            continue;
        }
        // Coordinates by hand: log10 μ on x (plotters' own log axis spun for minutes over a
        // 600-decade range), and log10 of the objective where it spans two decades (an error
        // falling from 1e-3 to 1e-10 along μ: linear, all but the largest lay flat).
        let (lo, hi) = value_range(c.curve.iter().filter_map(|p| p.objective));
        let log_y = lo > 0.0 && hi >= 100.0 * lo;
        let y_of = |v: f64| if log_y { v.log10() } else { v };
        let at = |p: &quell::study::TunePoint| p.objective.map(|o| (p.mu.log10(), y_of(o)));
        let pts: Vec<(f64, f64)> = c.curve.iter().filter_map(at).collect();
        let (m0, m1) = value_range(c.curve.iter().map(|p| p.mu.log10()));
        let (m0, m1) = if m0 < m1 { (m0 - 0.05 * (m1 - m0), m1 + 0.05 * (m1 - m0)) } else { (m0 - 0.3, m0 + 0.3) };
        let (lo, hi) = if log_y { (lo.log10().floor(), hi.log10().ceil()) } else { widened(lo, hi, 1e-3) };
        let pad = if log_y { 0.0 } else { 0.05 * (hi - lo) };
        let (y0, y1) = (lo - pad - if log_y { 0.3 } else { 0.0 }, hi + pad + if log_y { 0.3 } else { 0.0 });
        // Evaluations without an objective (not completed, beyond a limit, never settled) are
        // marked in a band of their own below the axis's values, not at a value (at its bottom edge
        // they read as points near the chosen one).
        let none: Vec<f64> = c.curve.iter().filter(|p| p.objective.is_none()).map(|p| p.mu.log10()).collect();
        let band = if none.is_empty() { 0.0 } else { 0.12 * (y1 - y0) };
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{}: {} against μ{}", channel_title(c.channel, outputs), r.objective.name(), c.channel + 1),
                ("sans-serif", 18),
            )
            .margin(10)
            .margin_right(24)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(m0..m1, y0 - band..y1)
            .map_err(|e| e.to_string())?;
        let y_desc = if log_y { format!("{objective} (log scale)") } else { objective.clone() };
        chart
            .configure_mesh()
            .x_desc(format!("μ{} (others at the scenario's; log scale)", c.channel + 1))
            .y_desc(y_desc)
            .x_labels(12)
            // Decades over a wide range; over less than two, each tick's μ to three digits.
            .x_label_formatter(&|v| if m1 - m0 >= 2.0 { decade_label(*v) } else { format!("{:.3}", 10f64.powf(*v)) })
            .y_label_formatter(&|v| match *v < y0 - 1e-9 * (y1 - y0) {
                true => String::new(),
                false if log_y => decade_label(*v),
                false => tick_label(*v, y0, y1),
            })
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(|e| e.to_string())?;
        let color = pick(c.channel);
        for run in feasible_runs(c.curve.iter().map(at)) {
            chart.draw_series(LineSeries::new(run, color.stroke_width(2))).map_err(|e| e.to_string())?;
        }
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(|e| e.to_string())?;
        if !none.is_empty() {
            mark_without_objective(&mut chart, &none, (m0, m1), (y0 - band, y0))?;
        }
        if let Some(best) = c.chosen.as_ref().and_then(at) {
            chart
                .draw_series(std::iter::once(Circle::new(best, 7, BLACK.stroke_width(2))))
                .map_err(|e| e.to_string())?;
        }
    }
    root.present().map_err(|e| e.to_string())
}

/// The runs of consecutive points among `points` (in order of μ; `None` for an evaluation without
/// an objective): the tuning curve's line joins neighbours within a run only. Across an infeasible
/// μ it had read as feasible there (two μ beyond a voltage limit between good ones; helper tryout,
/// 2026-12-06).
fn feasible_runs(points: impl Iterator<Item = Option<(f64, f64)>>) -> Vec<Vec<(f64, f64)>> {
    let mut runs = vec![Vec::new()];
    for p in points {
        match p {
            Some(xy) => runs.last_mut().expect("never empty").push(xy),
            None if runs.last().is_some_and(|r| !r.is_empty()) => runs.push(Vec::new()),
            None => {}
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

/// The evaluations at log10 μ `none`, which have no objective, as crosses in the band (b, y0)
/// below a line at y0, with the note saying what they are at the band's top (its μ span (m0, m1)):
/// at the panel's top it had been drawn over the frame and the first tick label.
fn mark_without_objective<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    none: &[f64],
    (m0, m1): (f64, f64),
    (b, y0): (f64, f64),
) -> Result<(), String> {
    let (y, grey) = (b + 0.3 * (y0 - b), RGBColor(120, 120, 120));
    chart.draw_series(LineSeries::new([(m0, y0), (m1, y0)], grey.stroke_width(1))).map_err(|e| e.to_string())?;
    chart
        .draw_series(none.iter().map(|&mu| Cross::new((mu, y), 5, grey.stroke_width(2))))
        .map_err(|e| e.to_string())?;
    let note = format!("× {} without an objective: not completed, beyond a limit or never settled", none.len());
    let font = ("sans-serif", 12).into_font().color(&grey).pos(Pos::new(HPos::Left, VPos::Top));
    let at = (m0 + 0.01 * (m1 - m0), y0 - 0.08 * (y0 - b));
    chart.draw_series(std::iter::once(Text::new(note, at, font))).map_err(|e| e.to_string())?;
    Ok(())
}

/// Writes tune.png and tune.svg.
pub fn plot_tune(dir: &Path, r: &quell::study::TuneResult, unit: TimeUnit, outputs: &[String]) -> io::Result<()> {
    let size = (560 * r.channels.len().max(1) as u32, 460);
    let labels = (unit, outputs);
    write_figure(dir, "tune", size, |root| draw_tune(root, r, labels), |root| draw_tune(root, r, labels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The note goes where the curve is not: top left; bottom left under a curve that starts high;
    /// top right where a curve rises from the bottom left (a boiler's tail RMS rose from there
    /// under the note; helper tryout, 2026-12-06).
    #[test]
    fn heat_map_labels_tell_close_medians_apart() {
        // 1.230102e-3 … 1.231129e-3 (a TRMS's medians): 0.08 %, four decimals; 10 % and more, two.
        assert_eq!(telling_digits((1.231129e-3f64 / 1.230102e-3).log10()), 4);
        assert_eq!(format!("{:.4e}", 1.230102e-3), "1.2301e-3");
        assert_eq!(telling_digits(1.1f64.log10()), 2);
        assert_eq!(telling_digits(3.0), 2);
        assert_eq!(telling_digits(0.0), 2);
        assert_eq!(telling_digits(1e-12), 5);
    }

    #[test]
    fn a_caption_shrinks_to_fit_its_panel() {
        // 87 characters in 1,000 px at 20 px (~957 px) → 20; the u_f title with the controller's
        // ask, 104 characters → 17; a title that would need less than 11 px keeps 11.
        assert_eq!(caption_size(&"x".repeat(87), 1000, 20), 20);
        assert_eq!(caption_size(&"x".repeat(104), 1000, 20), 17);
        assert_eq!(caption_size(&"x".repeat(400), 1000, 20), 11);
    }

    #[test]
    fn the_missing_median_note_avoids_the_curve() {
        let panel = ((0.0, 60.0), (0.0, 1.0));
        assert_eq!(note_corner(&[(0.0, 0.5), (5.0, 0.55)], panel.0, panel.1), (0.02, 0.97));
        assert_eq!(note_corner(&[(0.0, 0.95), (5.0, 0.6)], panel.0, panel.1), (0.02, 0.19));
        assert_eq!(note_corner(&[(0.0, 0.02), (2.0, 0.4), (5.0, 0.98)], panel.0, panel.1), (0.33, 0.97));
        // A segment crossing the top left with no point under it.
        assert_eq!(note_corner(&[(0.0, 0.5), (60.0, 1.0)], panel.0, panel.1), (0.02, 0.19));
    }

    /// A point without its upper quantile breaks the band there; the points with both keep theirs
    /// (the active-suspension study's settling-time band had vanished at every point because one
    /// point's 95 % quantile was "never settled").
    #[test]
    fn the_tuning_curve_breaks_at_an_infeasible_mu() {
        let p = |x: f64| Some((x, 2.0 * x));
        let runs = feasible_runs([None, p(1.0), p(2.0), None, None, p(3.0), None].into_iter());
        assert_eq!(runs, vec![vec![(1.0, 2.0), (2.0, 4.0)], vec![(3.0, 6.0)]]);
        assert!(feasible_runs([None, None].into_iter()).is_empty());
    }

    #[test]
    fn a_band_breaks_where_a_point_lacks_a_quantile() {
        let low = [(0.0, 1.0), (4.0, 2.0), (7.0, 3.0)];
        let full = [(0.0, 5.0), (4.0, 6.0), (7.0, 7.0)];
        assert_eq!(band_spans(&low, &full), vec![vec![(0.0, 1.0, 5.0), (4.0, 2.0, 6.0), (7.0, 3.0, 7.0)]]);
        let upper = [(0.0, 5.0), (4.0, 6.0)];
        assert_eq!(band_spans(&low, &upper), vec![vec![(0.0, 1.0, 5.0), (4.0, 2.0, 6.0)]]);
        let middle = [(0.0, 5.0), (7.0, 7.0)];
        assert_eq!(band_spans(&low, &middle), vec![vec![(0.0, 1.0, 5.0)], vec![(7.0, 3.0, 7.0)]]);
        assert!(band_spans(&[], &[]).is_empty());
    }
    use plotters::prelude::SeriesLabelPosition;

    #[test]
    fn m4_keeps_each_pixel_columns_first_last_lowest_and_highest_points() {
        // A sine of 50 periods in 100,001 points, in a plot 500 px wide (200 points a column).
        let points: Vec<(f64, f64)> =
            (0..=100_000).map(|k| k as f64 * 1e-3).map(|t| (t, (t * std::f64::consts::PI).sin())).collect();
        let x = 0.0..100.0;
        let thin = m4(&points, &x, 500);
        assert!(thin.len() <= 4 * 500 + 4 && thin.len() > 1000, "{}", thin.len());
        assert!(thin.windows(2).all(|p| p[0].0 < p[1].0), "in time order");
        assert!(thin.iter().all(|p| points.contains(p)), "a subset");
        assert_eq!((thin[0], thin[thin.len() - 1]), (points[0], points[points.len() - 1]));
        // Each column's extremes, by hand from the input.
        for c in 0..500 {
            let in_column = |p: &&(f64, f64)| (p.0 * 5.0).floor() == c as f64;
            let extremes = |v: &[(f64, f64)]| {
                let vs: Vec<f64> = v.iter().filter(in_column).map(|p| p.1).collect();
                (vs.iter().copied().fold(f64::MAX, f64::min), vs.iter().copied().fold(f64::MIN, f64::max))
            };
            assert_eq!(extremes(&thin), extremes(&points), "column {c}");
        }
        // A NaN is kept where it was; few points are left as they are.
        let mut gap = points.clone();
        gap[50_000].1 = f64::NAN;
        assert_eq!(m4(&gap, &x, 500).iter().filter(|p| p.1.is_nan()).count(), 1);
        assert_eq!(m4(&points[..1000], &x, 500), points[..1000].to_vec());
    }

    #[test]
    fn the_legend_goes_to_the_corner_that_hides_the_fewest_samples() {
        let view = ((0.0, 10.0), (-1.0, 1.0));
        let series = |points: Vec<(f64, f64)>| vec![("y".to_string(), points)];
        // A curve rising from the lower left to the upper right: the legend leaves the upper right.
        let rising = series((0..=100).map(|k| (0.1 * k as f64, -1.0 + 0.02 * k as f64)).collect());
        let (corner, _) = legend_corner(&rising, view, (0.2, 0.2));
        assert!(matches!(corner, SeriesLabelPosition::UpperLeft), "{corner:?}");
        // A flat line at zero hides nothing in any corner: the upper right.
        let flat = series((0..=100).map(|k| (0.1 * k as f64, 0.0)).collect());
        assert!(matches!(legend_corner(&flat, view, (0.2, 0.2)).0, SeriesLabelPosition::UpperRight));
        // Eight sines filling the panel hide samples in every corner: the axis is raised by the
        // box's height, and then the upper right hides none (the legend over the η̂ transients).
        let sines: Vec<Series> = (0..8)
            .map(|j| {
                (
                    format!("η1_{j}"),
                    (0..=400).map(|k| (0.025 * k as f64, (0.025 * k as f64 * (j + 1) as f64).sin())).collect(),
                )
            })
            .collect();
        let y1 = with_headroom(&sines, ((0.0, 10.0), (-1.0, 1.0)), (0.3, 0.25)).unwrap();
        assert!((y1 - (-1.0 + 2.0 / 0.73)).abs() < 1e-12, "{y1}");
        assert_eq!(legend_corner(&sines, ((0.0, 10.0), (-1.0, y1)), (0.3, 0.25)).1, 0);
        // A tall box (twelve entries over most of the panel's height): beside the plotting area.
        assert_eq!(with_headroom(&sines, ((0.0, 10.0), (-1.0, 1.0)), (0.1, 0.9)), None);
        assert_eq!(with_headroom(&flat, view, (0.2, 0.2)), Some(1.0));
    }

    /// η̂'s eight entries over transients filling the panel go beside the plotting area, and the
    /// time axis ends at the data's end (it had been extended 12–33 % past t_end for the box, on
    /// every panel of the figure; three helper tryouts took it for a defect); the legend's column is
    /// its estimated width and a gap.
    #[test]
    fn a_tall_legend_goes_beside_the_panel_and_the_time_axis_ends_with_the_data() {
        let (w, h) = (1000u32, 275u32);
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let sines: Vec<Series> = (0..8)
            .map(|j| {
                (
                    format!("η1_{j}"),
                    (0..=400).map(|k| (0.25 * k as f64, (0.025 * k as f64 * (j + 1) as f64).sin())).collect(),
                )
            })
            .collect();
        let ((t, _), legend) = panel_view(&root, &sines, None, (None, 0));
        assert_eq!(t, (0.0, 100.0));
        // 48 + 0.6·14·4 px for "η1_0" at 14 px.
        assert_eq!(legend, Legend::Outside(14, (48.0f64 + 0.6 * 14.0 * 4.0).ceil() as u32));
        assert_eq!(legend.column(), 82 + 16);
        // A line that leaves a corner free keeps its legend there, also in a figure with a column.
        let ramp: Vec<Series> = vec![("y1".into(), (0..=100).map(|k| (k as f64, k as f64)).collect())];
        let ((t, _), legend) = panel_view(&root, &ramp, None, (None, 98));
        assert!(t == (0.0, 100.0) && matches!(legend, Legend::Inside(14, _)), "{legend:?}");
    }

    #[test]
    fn a_zigzag_is_drawn_within_its_panel() {
        // A sampled command reversing at every step (what a decimated slice or a staircase draws):
        // plotters' 2 px polygons put spikes past the data and below the x axis (53 px on a servo's
        // u_f); three 1 px lines keep every pixel of the curve's colour inside the plotting area.
        register_font();
        let points: Vec<(f64, f64)> =
            (0..4000).map(|k| (k as f64 * 1e-3, if k % 2 == 0 { 0.3 } else { -0.3 } + 1e-3 * k as f64)).collect();
        let (w, h) = (600u32, 300u32);
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            panel(&root, ("zigzag", "u"), &[("u1".into(), points)], (None, None, 0), TimeUnit::default()).unwrap();
            root.present().unwrap();
        }
        let pixel = |x: u32, y: u32| {
            let i = ((y * w + x) * 3) as usize;
            (rgb[i], rgb[i + 1], rgb[i + 2])
        };
        // The x axis: the lowest row that is mostly black.
        let axis = (0..h).rev().find(|&y| (0..w).filter(|&x| pixel(x, y) == (0, 0, 0)).count() > w as usize / 2);
        let axis = axis.expect("an x axis");
        let blue =
            |(r, g, b): (u8, u8, u8)| (r as i32 - 31).abs() + (g as i32 - 119).abs() + (b as i32 - 180).abs() < 60;
        let below = (axis + 2..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| blue(pixel(x, y))).count();
        assert_eq!(below, 0, "{below} pixels of the curve below the x axis at row {axis}");
    }

    /// The bands of a grid point alone (one grid value, or the only point with completed draws)
    /// are a bar around it: only its median dot had been drawn, on an axis scaled to the bands
    /// (tryout, 2026-12-05). The bar spans the 5–95 % values and nothing beyond.
    /// A grid of small values (a state's x0 of 1e-7 and 2e-7) had every tick labelled "0": the x
    /// axis now labels ticks as the y axis does.
    #[test]
    fn small_grid_values_keep_their_digits_on_the_axis() {
        assert_eq!(tick_label(1.2e-7, 1e-7, 2e-7), "1.2e-7");
        assert_eq!(tick_label(-1.5e-7, -2e-7, -1e-7), "-1.5e-7");
        assert_eq!(tick_label(2.8000000000000003, 2.0, 4.0), "2.8");
    }

    #[test]
    fn the_bands_of_a_point_alone_are_a_bar() {
        let (w, h) = (400u32, 300u32);
        let mut rgb = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            let mut chart = ChartBuilder::on(&root).build_cartesian_2d(0.0..2.0, 0.0..10.0).unwrap();
            let at = |p: f64| vec![(1.0, 2.0 + 6.0 * p)]; // 5 %: 2.3, 95 %: 7.7
            draw_quantile_bands(&mut chart, (&at, &at), BLUE.into(), 0.1).unwrap();
            root.present().unwrap();
        }
        let tinted = |x: u32, y: u32| {
            let i = ((y * w + x) * 3) as usize;
            rgb[i] < 250 && rgb[i + 2] > rgb[i]
        };
        // x = 1 is column 200; values 2.3 and 7.7 are rows 300·(1 − v/10).
        let column: Vec<u32> = (0..h).filter(|&y| tinted(200, y)).collect();
        let (top, bottom) = (column.first().copied().unwrap_or(0), column.last().copied().unwrap_or(0));
        assert!((67..=71).contains(&top) && (228..=232).contains(&bottom), "bar from row {top} to {bottom}");
        assert!(!tinted(200 - 25, 150) && tinted(200 - 15, 150), "the bar is 0.1 either side: 20 px");
    }

    #[test]
    fn an_output_shows_over_a_reference_too_fast_to_draw_as_a_line() {
        // 300 periods of a reference across 600 px, tracked exactly by y: dashed on top, the
        // reference covered 96 % of y's pixels (y kept 4,094 of 97,693 blue ones). Drawn first and
        // faint it leaves y whole. A slow reference keeps its dashes over y.
        register_font();
        let (w, h) = (600u32, 300u32);
        let blue_pixels = |periods: f64, with_reference: bool| {
            let points: Vec<(f64, f64)> = (0..4000)
                .map(|k| k as f64 / 4000.0)
                .map(|t| (t, (std::f64::consts::TAU * periods * t).sin()))
                .collect();
            // Without the reference, an empty series of that name: the same legend, so the same
            // headroom above the data (`with_headroom`) and the same scale.
            let reference = if with_reference { points.clone() } else { Vec::new() };
            let series = vec![("y1".to_string(), points), ("g1 (reference)".to_string(), reference)];
            let mut rgb = vec![255u8; (w * h * 3) as usize];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
                panel(&root, ("tracking", "y"), &series, (None, None, 0), TimeUnit::default()).unwrap();
                root.present().unwrap();
            }
            rgb.chunks(3).filter(|p| (p[0], p[1], p[2]) == (31, 119, 180)).count()
        };
        let (alone, under) = (blue_pixels(300.0, false), blue_pixels(300.0, true));
        assert!(under as f64 >= 0.9 * alone as f64, "y keeps {under} of its {alone} pixels under a fast reference");
        let (alone, slow) = (blue_pixels(2.0, false), blue_pixels(2.0, true));
        assert!((slow as f64) < 0.8 * alone as f64, "a slow reference is drawn dashed over y: {slow} of {alone}");
    }

    #[test]
    fn a_held_signal_keeps_each_value_until_the_next_sample() {
        let corners: Vec<_> = staircase([(0.0, 1.0), (0.5, 3.0), (1.0, -2.0)].into_iter()).collect();
        assert_eq!(corners, [(0.0, 1.0), (0.5, 1.0), (0.5, 3.0), (1.0, 3.0), (1.0, -2.0)]);
        assert_eq!(staircase(std::iter::empty()).count(), 0);
    }

    #[test]
    fn a_long_series_is_drawn_from_each_slices_extremes_and_a_short_one_whole() {
        // 10⁶ samples of a 50 Hz sine over 10 s with one spike of 7 and one NaN: at most four
        // points a slice, and every slice's first, lowest, highest and last sample among them.
        let n = 1_000_000;
        let t = |k: usize| 10.0 * k as f64 / (n - 1) as f64;
        let value = |k: usize| match k {
            123_457 => 7.0,
            654_321 => f64::NAN,
            _ => (2.0 * std::f64::consts::PI * 50.0 * t(k)).sin(),
        };
        let kept = decimated((0..n).map(|k| (t(k), value(k))), (0.0, 10.0));
        assert!(kept.len() <= 4 * SLICES, "{} points", kept.len());
        assert!(kept.windows(2).all(|w| w[0].0 < w[1].0), "in the order of t");
        assert!(kept.iter().all(|p| p.1.is_finite()));
        assert!(kept.contains(&(t(123_457), 7.0)), "the spike is kept");
        // Slice by slice, against a direct pass: its extremes and ends are among the kept points.
        let width = 10.0 / SLICES as f64;
        for s in (0..SLICES).step_by(97) {
            let inside: Vec<(f64, f64)> = (0..n)
                .map(|k| (t(k), value(k)))
                .filter(|&(tk, v)| ((tk / width) as usize).min(SLICES - 1) == s && v.is_finite())
                .collect();
            let low = inside.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
            let high = inside.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
            for point in [inside[0], low, high, inside[inside.len() - 1]] {
                assert!(kept.contains(&point), "slice {s}: {point:?}");
            }
        }
        // The paper's 1,001 rows fall one to a slice: kept whole, NaN aside.
        let short: Vec<(f64, f64)> = (0..=1000).map(|k| (0.1 * k as f64, (0.3 * k as f64).cos())).collect();
        assert_eq!(decimated(short.iter().copied(), (0.0, 100.0)), short);
        assert_eq!(
            decimated([(1.0, 2.0), (1.0, f64::NAN), (1.0, 3.0)].into_iter(), (1.0, 1.0)),
            [(1.0, 2.0), (1.0, 3.0)]
        );
    }

    #[test]
    fn grids_over_two_decades_are_drawn_on_a_log_axis() {
        let strings = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (x, scale) = axis_coords(&strings(&["1.0", "10.0", "100.0", "1000.0"]));
        assert_eq!((x, scale), (vec![0.0, 1.0, 2.0, 3.0], AxisScale::Log));
        assert_eq!(axis_coords(&strings(&["2.0", "20.0", "200.0"])).1, AxisScale::Log);
        assert_eq!(axis_coords(&strings(&["2.0", "20.0", "199.0"])).1, AxisScale::Linear);
        assert_eq!(axis_coords(&strings(&["0.0", "10.0", "1000.0"])).1, AxisScale::Linear);
        assert_eq!(axis_coords(&strings(&["[1.0, 2.0]", "[3.0, 4.0]"])).1, AxisScale::Positions);
        let labels: Vec<String> = [-4.0, -2.0, 0.0, 0.5, 3.0, 7.0].iter().map(|&v| decade_label(v)).collect();
        assert_eq!(labels, ["1e-4", "0.01", "1", "", "1000", "1e7"]);
    }

    #[test]
    fn tune_panels_name_the_output_where_the_scenario_does() {
        // Two channels stopped before their first evaluation: the titles only.
        let r: quell::study::TuneResult = serde_json::from_str(
            r#"{"objective": "settle_t", "channels": [{"channel": 1, "curve": [], "chosen": null}, {"channel": 2, "curve": [], "chosen": null}],
                "mu": [1.0, 1.0], "joint": null, "joint_difference": [null, null], "reproduced": [false, false]}"#,
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        for (outputs, titles) in [
            (vec!["heading".to_string(), "speed".into()], ["Channel 1 (heading)", "Channel 2 (speed)"]),
            (vec![], ["Channel 1:", "Channel 2:"]),
        ] {
            plot_tune(dir.path(), &r, TimeUnit::default(), &outputs).unwrap();
            let svg = std::fs::read_to_string(dir.path().join("tune.svg")).unwrap();
            for title in titles {
                assert!(svg.contains(title), "{title} missing");
            }
        }
    }

    #[test]
    fn grid_keys_that_are_times_carry_the_unit() {
        for (key, label) in [
            ("truth.delays[1]", "truth.delays[1], min"),
            ("plant.delays", "plant.delays, min"),
            ("design.beta", "design.beta, min"),
            ("simulation.sample_time", "simulation.sample_time, min"),
            ("design.mu[0]", "design.mu[0]"),
            ("truth.A[1][2]", "truth.A[1][2]"),
        ] {
            assert_eq!(super::key_label(key, "min"), label);
        }
    }

    #[test]
    fn the_distribution_rises_by_one_draw_at_each_value_to_the_share_with_a_value() {
        // Four of five draws have a value (one diverged): the staircase ends at 4/5.
        let corners = super::ecdf(&[0.5, 1.0, 1.0, 3.0], 5);
        assert_eq!(
            corners,
            [(0.5, 0.0), (0.5, 0.2), (1.0, 0.2), (1.0, 0.4), (1.0, 0.4), (1.0, 0.6), (3.0, 0.6), (3.0, 0.8)]
        );
        assert!(super::ecdf(&[], 0).is_empty());
    }

    #[test]
    fn sweep_axes_do_not_magnify_differences_below_a_thousandth() {
        // Channel 2's tail RMS e across μ_1 (paper's example): 0.90294628…0.90294634 filled the
        // panel as if μ_1 mattered; now the axis spans 0.1 % of the value about its middle.
        let (lo, hi) = widened(0.90294628, 0.90294634, 1e-3);
        assert!((hi - lo - 0.90294634e-3).abs() < 1e-12 && lo < 0.90294628 && hi > 0.90294634, "{lo} {hi}");
        // A real spread is kept as it is, negative values too.
        assert_eq!(widened(0.2, 3.6, 1e-3), (0.2, 3.6));
        assert_eq!(widened(-5.0, -4.0, 1e-3), (-5.0, -4.0));
    }

    #[test]
    fn tick_labels_tell_small_and_large_ticks_apart() {
        // An η̂ axis of micro-units: plotters' default printed every tick as "0.0".
        let ticks: Vec<String> = (0..=5).map(|k| tick_label(k as f64 * 2e-7, 0.0, 1e-6)).collect();
        assert_eq!(ticks, ["0", "2e-7", "4e-7", "6e-7", "8e-7", "1e-6"]);
        assert_eq!(tick_label(1.5e-6, -1e-6, 2e-6), "1.5e-6");
        assert_eq!(tick_label(-2.5e-5, -3e-5, 3e-5), "-2.5e-5");
        // Forces in newtons: 2.5e5, not 250000.0.
        assert_eq!(tick_label(2.5e5, 0.0, 4e5), "2.5e5");
        assert_eq!(tick_label(1.2e6, -2e6, 2e6), "1.2e6");
        // Ordinary ranges keep decimals, as many as the spacing needs.
        assert_eq!(tick_label(0.25, 0.0, 0.5), "0.25");
        assert_eq!(tick_label(0.3, 0.0, 0.5), "0.3");
        assert_eq!(tick_label(-1.0, -4.5, 2.0), "-1");
        assert_eq!(tick_label(600.0, 0.0, 600.0), "600");
        assert_eq!(tick_label(1e-17, -0.5, 0.5), "0");
        // A narrow band around a large offset: enough digits to tell the ticks apart.
        assert_eq!(tick_label(100.05, 100.0, 100.1), "100.05");
        assert_eq!(tick_label(0.0, -1.0, 1.0), "0");
        assert_eq!(tick_label(-8.5e-22, -6.5e-6, 2e-7), "0");
    }

    #[test]
    fn grid_values_shorten_to_four_significant_digits() {
        use super::short_value;
        assert_eq!(short_value("[0.0, -6.666666666666667, 0.6666666666666666]"), "[0, -6.667, 0.6667]");
        assert_eq!(short_value("[[1.23456e-13, 2.5e6], [12345.678]]"), "[[1.235e-13, 2.5e6], [12346]]");
        assert_eq!(short_value("0.004"), "0.004");
        // The heat map's rows and columns too (they had read 1600000.0).
        assert_eq!(super::short_values(&["1600000.0".into(), "400000.0".into()]), ["1.6e6", "4e5"]);
        assert_eq!(short_value("\"dop853\""), "\"dop853\"");
        assert_eq!(short_value("-1.2000000000000002"), "-1.2");
    }
}
