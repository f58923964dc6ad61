//! The tracking error from each time on, on a logarithmic axis: the panel that shows an adaptive
//! loop converging over decades, which the linear panel of e flattens under its transient (a
//! distillation column's 0.42 excursion against a tail of 1e-5), and reads as the summary's tail
//! figure: at t, the largest |e| the run has from t on.

use plotters::coord::Shift;
use plotters::prelude::*;
use quell::TimeUnit;

use super::{pick, Series, Strokes, SLICES};

/// m(t) = max over s ≥ t of |v(s)|, at the first sample of each slice of [t0, t1] (as many as
/// [`super::decimated`] keeps) and at the last; non-increasing. Non-finite values are skipped, and
/// points where m is 0 left out (no logarithm).
pub(super) fn from_t_on(points: &[(f64, f64)], (t0, t1): (f64, f64)) -> Vec<(f64, f64)> {
    let mut suffix = vec![0.0f64; points.len()];
    let mut running = 0.0f64;
    for (k, &(_, v)) in points.iter().enumerate().rev() {
        if v.is_finite() {
            running = running.max(v.abs());
        }
        suffix[k] = running;
    }
    let scale = if t1 > t0 { SLICES as f64 / (t1 - t0) } else { 0.0 };
    let slice = |t: f64| (((t - t0) * scale).max(0.0) as usize).min(SLICES - 1);
    let mut kept: Vec<(f64, f64)> = Vec::new();
    let mut last_slice = None;
    for (k, &(t, _)) in points.iter().enumerate() {
        let first = last_slice.replace(slice(t)) != Some(slice(t));
        if (first || k + 1 == points.len()) && t.is_finite() && suffix[k] > 0.0 {
            kept.push((t, suffix[k]));
        }
    }
    kept
}

/// Decades below the largest value that the axis shows at most: below that the envelope is the
/// integrator's rounding, not the loop.
const DECADES: f64 = 14.0;

/// The log axis of values from `lo` to `hi`: half a decade of room above and below, at most
/// [`DECADES`] below the peak, widened to whole decades so that at least two are labelled (a
/// diverged run's error, flat at its final 4.4e4, had an axis from 1.5e4 to 1.3e5 with the one
/// label 1e5); 0.1 to 10 for values all 0.
fn log_range(lo: f64, hi: f64) -> (f64, f64) {
    if hi <= 0.0 {
        return (0.1, 10.0);
    }
    let decade = |v: f64, round: fn(f64) -> f64| 10f64.powf(round(v.log10()));
    (decade((lo / 3.0).max(hi * 10f64.powf(-DECADES)), f64::floor), decade(hi * 3.0, f64::ceil))
}

/// The time from which every point is below the axis's `lo`: the first after the last on the axis
/// (a series that is not monotone, a stopped run's |e|, may dip below it and come back: a bicycle's
/// e₁(0) = 0 had been read as "below 1e-14 from t = 0 on" and its whole growth left undrawn).
fn below_axis<'a>(points: impl Iterator<Item = &'a (f64, f64)>, lo: f64) -> Option<f64> {
    let all: Vec<&(f64, f64)> = points.collect();
    match all.iter().rposition(|&&(_, v)| v >= lo) {
        Some(k) => all.get(k + 1).map(|&&(t, _)| t),
        None => all.first().map(|&&(t, _)| t),
    }
}

/// A panel of `series` (positive values) against t on a logarithmic value axis, from `t0` to
/// `t_right`.
pub(super) fn log_panel<DB: DrawingBackend + Strokes>(
    area: &DrawingArea<DB, Shift>,
    (title, ylabel): (&str, &str),
    series: &[Series],
    (t0, t_right, column): (f64, f64, u32),
    time: TimeUnit,
) -> Result<(), String> {
    let points = series.iter().flat_map(|(_, p)| p.iter());
    let (lo, hi) = points.clone().fold((f64::INFINITY, 0.0f64), |(lo, hi), &(_, v)| (lo.min(v), hi.max(v)));
    let (t0, t1) = if t0 < t_right { (t0, t_right) } else { (t0, t0 + 1.0) };
    // Below the axis the curve ends, and the title says from when (drawn at the axis, its run at
    // 1e-90 looked like a floor at 1e-14).
    let (lo, hi) = log_range(lo, hi);
    let below = below_axis(points.clone(), lo);
    let title = match (below, points.clone().next()) {
        (Some(t), _) => format!("{title}; below 1e-{DECADES} of its peak from t = {} {time} on", crate::run::short(t)),
        (None, None) => format!("{title}: e ≡ 0"),
        (None, Some(_)) => title.to_string(),
    };
    let mut chart = super::run_panel(area, &title, column)
        .build_cartesian_2d(t0..t1, (lo..hi).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_desc(format!("t, {time}"))
        .y_desc(ylabel)
        .x_label_formatter(&|v| super::tick_label(*v, t0, t1))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (name, points)) in series.iter().enumerate().filter(|(_, (_, p))| !p.is_empty()) {
        let style = pick(k).stroke_width(if DB::SPIKES { 1 } else { 2 });
        let on_axis: Vec<(f64, f64)> = points.iter().copied().filter(|&(_, v)| v >= lo).collect();
        // One point (a run that ended before its second row) as a dot: a line of one draws nothing.
        let drawn = match on_axis[..] {
            [point] => chart.draw_series(std::iter::once(Circle::new(point, 3, pick(k).filled()))),
            _ => chart.draw_series(LineSeries::new(on_axis, style)),
        };
        drawn
            .map_err(|e| e.to_string())?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], pick(k).stroke_width(2)));
    }
    if series.iter().all(|(_, p)| p.is_empty()) {
        return Ok(());
    }
    super::draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 14)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Below the axis from the first point after the last on it: a dip that comes back is not; a
    /// curve that falls off for good is, from where it fell; one wholly below, from its start.
    #[test]
    fn a_series_is_below_the_axis_from_where_it_leaves_it_for_good() {
        let dip = [(0.0, 1e-20), (1.0, 1.0), (2.0, 1e-20), (3.0, 5.0)];
        assert_eq!(below_axis(dip.iter(), 1e-10), None);
        let falls = [(0.0, 1.0), (1.0, 1e-3), (2.0, 1e-20), (3.0, 1e-30)];
        assert_eq!(below_axis(falls.iter(), 1e-10), Some(2.0));
        assert_eq!(below_axis([(0.0, 1e-20), (1.0, 1e-30)].iter(), 1e-10), Some(0.0));
        assert_eq!(below_axis([].iter(), 1e-10), None);
    }

    /// m(t) of e = e^{−t} sin 40t over 10 s: non-increasing, never above e^{−t} nor below the
    /// largest crest after t, e^{−(t + T/2)} sin(…) ≥ 0.99 e^{−t − 0.079} (a half period T/2 =
    /// 0.079 s holds a crest, sampled 5e-5 s apart); zeros are left out.
    #[test]
    fn the_curve_is_the_largest_magnitude_from_each_time_on() {
        let points: Vec<(f64, f64)> =
            (0..=200_000).map(|k| k as f64 * 5e-5).map(|t| (t, (-t).exp() * (40.0 * t).sin())).collect();
        let m = from_t_on(&points, (0.0, 10.0));
        assert!(m.len() > SLICES / 2 && m.len() <= SLICES + 1, "{}", m.len());
        assert!(m.windows(2).all(|w| w[0].0 < w[1].0 && w[0].1 >= w[1].1));
        let half = std::f64::consts::PI / 40.0;
        for &(t, a) in m.iter().filter(|&&(t, _)| t < 10.0 - half) {
            assert!(a <= (-t).exp() * (1.0 + 1e-12) && a >= 0.99 * (-t - half).exp(), "m({t}) = {a}");
        }
        assert!(from_t_on(&[(0.0, 0.0), (1.0, 0.0)], (0.0, 1.0)).is_empty());
    }

    /// Whole decades, two labels at least: a flat error, the paper's channel 1 (20.7 to 0.011), a
    /// run far below its peak (cut 14 decades down), none at all.
    #[test]
    fn a_log_axis_spans_whole_decades() {
        let close = |(a, b): (f64, f64), (c, d): (f64, f64)| (a / c - 1.0).abs() < 1e-12 && (b / d - 1.0).abs() < 1e-12;
        assert!(close(log_range(4.4e4, 4.4e4), (1e4, 1e6)));
        assert!(close(log_range(0.011, 20.7), (1e-3, 100.0)));
        assert!(close(log_range(1e-90, 1.0), (1e-14, 10.0)));
        assert_eq!(log_range(0.0, 0.0), (0.1, 10.0));
    }
}
