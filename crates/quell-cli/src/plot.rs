//! One figure per channel, like the paper's Figs. 1 and 2: y_i with g_i, e_i, u_i and η̂_i against t.

use std::io;
use std::path::Path;
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;
use quell::sim::SimResult;

use crate::output::write_atomic;

const SIZE: (u32, u32) = (1000, 1150);
static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        // DejaVu Sans (see assets/DejaVuSans.LICENSE), so PNGs render on machines without fonts.
        let _ =
            plotters::style::register_font("sans-serif", FontStyle::Normal, include_bytes!("../assets/DejaVuSans.ttf"));
    });
}

type Series = (String, Vec<(f64, f64)>);

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    ylabel: &str,
    series: &[Series],
) -> Result<(), String> {
    let (t0, t1) = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|(t, _)| *t))
        .fold((f64::MAX, f64::MIN), |(a, b), t| (a.min(t), b.max(t)));
    let (lo, hi) = series
        .iter()
        .flat_map(|(_, p)| p.iter().map(|(_, v)| *v))
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    let (t0, t1) = if t0 < t1 { (t0, t1) } else { (0.0, 1.0) };
    let (lo, hi) = if lo < hi {
        (lo, hi)
    } else if lo == hi {
        (lo - 1.0, hi + 1.0)
    } else {
        (-1.0, 1.0)
    };
    let pad = 0.05 * (hi - lo);
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 20))
        .margin(8)
        .margin_right(24)
        .x_label_area_size(36)
        .y_label_area_size(64)
        .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .max_light_lines(2)
        .x_desc("t, s")
        .y_desc(ylabel)
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, (name, points)) in series.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let style = color.stroke_width(2);
        chart
            .draw_series(LineSeries::new(points.iter().copied().filter(|(_, v)| v.is_finite()), style))
            .map_err(|e| e.to_string())?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())
}

/// Draws the figure; `background` paints it white first (a bitmap buffer can start white instead).
fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    r: &SimResult,
    i: usize,
    background: bool,
) -> Result<(), String> {
    if background {
        root.fill(&WHITE).map_err(|e| e.to_string())?;
    }
    let col = |sig: &[f64]| r.t.iter().copied().zip(r.column(sig, r.m, i)).collect::<Vec<_>>();
    let c = i + 1;
    let areas = root.split_evenly((4, 1));
    panel(
        &areas[0],
        &format!("Channel {c}: output and reference"),
        "y, g",
        &[(format!("g{c} (reference)"), col(&r.g)), (format!("y{c}"), col(&r.y))],
    )?;
    panel(&areas[1], &format!("Channel {c}: tracking error"), "e = y − g", &[(format!("e{c}"), col(&r.e))])?;
    panel(&areas[2], &format!("Channel {c}: adaptive command (25)"), "u", &[(format!("u{c}"), col(&r.u))])?;
    let etas: Vec<Series> = (0..r.q)
        .map(|j| {
            let pts = r.t.iter().copied().zip(r.eta.iter().skip(i * r.q + j).step_by(r.m * r.q).copied()).collect();
            (format!("η{c}_{}", j + 1), pts)
        })
        .collect();
    panel(&areas[3], &format!("Channel {c}: adjustable parameters (33)"), "η", &etas)?;
    root.present().map_err(|e| e.to_string())
}

/// Writes `channel{i+1}.png` and `.svg` into `dir`, each atomically.
pub fn plot_channel(dir: &Path, r: &SimResult, i: usize) -> io::Result<()> {
    register_font();
    let png = dir.join(format!("channel{}.png", i + 1));
    let mut rgb = vec![255u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area(), r, i, false)
        .map_err(|e| io::Error::other(format!("{}: {e}", png.display())))?;
    write_atomic(&png, |w| {
        let mut encoder = png::Encoder::new(w, SIZE.0, SIZE.1);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        // Fast deflate: about twice the file size of the default level, a third of the time.
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        writer.write_image_data(&rgb).map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    })?;
    let mut svg = String::new();
    draw(SVGBackend::with_string(&mut svg, SIZE).into_drawing_area(), r, i, true).map_err(io::Error::other)?;
    write_atomic(&dir.join(format!("channel{}.svg", i + 1)), |w| w.write_all(svg.as_bytes()))
}
