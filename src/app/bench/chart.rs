//! Speed-against-accuracy records, their Pareto front, and the charts.
//!
//! A [`Measurement`] is one run of one method at one setting: wall time of
//! the stage the method affects and error against a converged reference of
//! the same quantity. Runs are kept as CSV (`bench.csv`) and drawn per study
//! as time (x, log) against error (y, log), one curve per method, the Pareto
//! front drawn over them. A reference measured against itself has error 0,
//! which a log axis cannot show: it is drawn as a triangle on the bottom edge.

use super::measurement::{pareto_front, CostUnit, Measurement};
use crate::util::fmath;
use plotters::prelude::*;
use std::path::Path;

/// Registers DejaVu Sans (Debian's fonts-dejavu-core) for chart text.
fn ensure_font() -> Result<(), ChartError> {
    static ONCE: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    ONCE.get_or_init(|| {
        const CANDIDATES: &[&str] = &[
            "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
            "/usr/share/fonts/TTF/DejaVuSans.ttf",
            "/usr/share/fonts/dejavu/DejaVuSans.ttf",
        ];
        for p in CANDIDATES {
            if let Ok(bytes) = std::fs::read(p) {
                // The font table wants 'static bytes: leak one small file once.
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                return plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
                    .map_err(|_| format!("{p} is not a usable font"));
            }
        }
        Err("no DejaVuSans.ttf found (apt-get install fonts-dejavu-core)".to_string())
    })
    .clone()
    .map_err(ChartError::Font)
}

#[derive(Debug, thiserror::Error)]
pub enum ChartError {
    #[error("chart font: {0}")]
    Font(String),
    #[error("drawing {path}: {message}")]
    Draw { path: String, message: String },
}

impl ChartError {
    /// Never the user's input: a font or drawing failure (exit status 1).
    pub fn is_input(&self) -> bool {
        false
    }
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

/// Draws one study (all measurements with `study`) to `stem.png` and `stem.svg`.
pub fn draw_study(ms: &[Measurement], study: &str, stem: &Path) -> Result<(), ChartError> {
    ensure_font()?;
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    let err = |p: &Path, e: String| ChartError::Draw { path: p.display().to_string(), message: e };
    // The bitmap is drawn into memory and encoded by the `png` crate (the
    // renderer's PNG writer), not by plotters' `image`-based encoder.
    let mut rgb = vec![0u8; CHART_W as usize * CHART_H as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (CHART_W, CHART_H)).into_drawing_area();
        draw_on(root, ms, study).map_err(|e| err(&png, e))?;
    }
    write_png(&png, &rgb).map_err(|e| err(&png, e))?;
    {
        let root = SVGBackend::new(&svg, (CHART_W, CHART_H)).into_drawing_area();
        draw_on(root, ms, study).map_err(|e| err(&svg, e))?;
    }
    Ok(())
}

/// Chart size in pixels (PNG) and user units (SVG).
const CHART_W: u32 = 900;
const CHART_H: u32 = 600;

/// Writes 8-bit RGB pixels (`CHART_W` x `CHART_H`, rows top to bottom) as a PNG.
fn write_png(path: &Path, rgb: &[u8]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), CHART_W, CHART_H);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| e.to_string())?;
    w.write_image_data(rgb).map_err(|e| e.to_string())?;
    w.finish().map_err(|e| e.to_string())
}

fn draw_on<DB: DrawingBackend>(root: DrawingArea<DB, plotters::coord::Shift>, ms: &[Measurement], study: &str) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let sel: Vec<&Measurement> = ms.iter().filter(|m| m.study == study && m.cost > 0.0 && m.error >= 0.0 && m.error.is_finite()).collect();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    if !sel.iter().any(|m| m.error > 0.0) {
        return Err(format!("study '{study}' has no finite positive measurements"));
    }
    let (mut t0, mut t1, mut e0, mut e1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for m in &sel {
        t0 = t0.min(m.cost);
        t1 = t1.max(m.cost);
        if m.error > 0.0 {
            e0 = e0.min(m.error);
            e1 = e1.max(m.error);
        }
    }
    // Pad a little in log space so end points are not on the frame.
    let (t0, t1) = (t0 / 1.5, t1 * 1.5);
    let (e0, e1) = (e0 / 1.5, e1 * 1.5);
    // Where an error of exactly 0 (a reference against itself) is drawn.
    let floor = e0 * 1.05;
    let shown = |m: &Measurement| (m.cost, if m.error > 0.0 { m.error } else { floor });
    let metric = sel[0].metric.clone();
    let stage = sel[0].stage.clone();
    let unit = sel[0].unit;
    let against = unit.quantity();
    let x_desc = match unit {
        CostUnit::Seconds => format!("wall time of {stage} (s)"),
        CostUnit::Megabytes => format!("{stage} ({})", unit.symbol()),
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{study}: {against} against error"), ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(
            (t0..t1).log_scale().with_key_points(nice_ticks(t0, t1)),
            (e0..e1).log_scale().with_key_points(nice_ticks(e0, e1)),
        )
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_label_formatter(&|x| sig(*x))
        .y_label_formatter(&|y| sig(*y))
        .x_desc(x_desc)
        .y_desc(format!("error ({metric})"))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| e.to_string())?;

    let mut methods: Vec<&str> = Vec::new();
    for m in &sel {
        if !methods.contains(&m.method.as_str()) {
            methods.push(&m.method);
        }
    }
    for (k, method) in methods.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let mut pts: Vec<&&Measurement> = sel.iter().filter(|m| m.method == *method).collect();
        pts.sort_by(|a, b| a.param.total_cmp(&b.param));
        let series: Vec<(f64, f64)> = pts.iter().filter(|m| m.error > 0.0).map(|m| (m.cost, m.error)).collect();
        chart
            .draw_series(LineSeries::new(series.clone(), color.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(method.to_string())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        chart.draw_series(series.iter().map(|&p| Circle::new(p, 4, color.filled()))).map_err(|e| e.to_string())?;
        // Error 0: a triangle on the bottom edge.
        chart
            .draw_series(pts.iter().filter(|m| m.error == 0.0).map(|m| TriangleMarker::new(shown(m), 7, color.filled())))
            .map_err(|e| e.to_string())?;
        // Label each point with its parameter value; the scene's own setting
        // is marked with a star.
        chart
            .draw_series(pts.iter().map(|m| {
                let star = if m.scene_setting { " *" } else { "" };
                let text = if m.error == 0.0 { format!("reference, error 0{star}") } else { format!("{}{star}", short_num(m.param)) };
                EmptyElement::at(shown(m)) + Text::new(text, (6, -14), ("sans-serif", 12).into_font().color(&color))
            }))
            .map_err(|e| e.to_string())?;
    }
    // The Pareto front over all methods of this study.
    let all: Vec<(f64, f64)> = sel.iter().map(|m| (m.cost, m.error)).collect();
    let front: Vec<(f64, f64)> = pareto_front(&all).into_iter().map(|i| shown(sel[i])).collect();
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))
        .map_err(|e| e.to_string())?
        .label("Pareto front (* = scene setting)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    chart.draw_series(front.iter().map(|&p| Circle::new(p, 8, BLACK.stroke_width(1)))).map_err(|e| e.to_string())?;
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

/// Tick positions for a log axis over [lo, hi]: 1, 2 and 5 times powers of
/// ten, or every 1..9 times a power of ten when that leaves fewer than three
/// (a range narrower than a decade). Labelling every 1..9 on a wide axis runs
/// the labels together.
fn nice_ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Vec::new();
    }
    let (k0, k1) = (fmath::log10(lo).floor() as i32, fmath::log10(hi).ceil() as i32);
    let pick = |ms: &[f64]| -> Vec<f64> {
        (k0..=k1).flat_map(|k| ms.iter().map(move |m| m * fmath::powi(10f64, k))).filter(|&x| x >= lo && x <= hi).collect()
    };
    let coarse = pick(&[1.0, 2.0, 5.0]);
    if coarse.len() >= 3 {
        coarse
    } else {
        pick(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    }
}

/// A tick label with at most three significant digits.
fn sig(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let digits = (2 - fmath::log10(x.abs()).floor() as i32).max(0) as usize;
    if x.abs() >= 1e-3 && x.abs() < 1e5 {
        // Trailing zeros dropped: "0.08", "2", "0.125".
        let s = format!("{x:.digits$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.1e}")
    }
}

fn short_num(x: f64) -> String {
    if x.abs() >= 1000.0 && x == x.trunc() {
        format!("{}k", x / 1000.0)
    } else if x == x.trunc() {
        format!("{x}")
    } else {
        format!("{x:.3}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Oracle: a point is on the front iff no other point dominates it.
    #[test]
    fn pareto_front_matches_brute_force() {
        use rand::Rng;
        let mut r = crate::util::rng::rng(&[12345]);
        let mut rnd = || r.random_range(0..1000u32) as f64 / 10.0;
        for _ in 0..50 {
            let pts: Vec<(f64, f64)> = (0..30).map(|_| (rnd(), rnd())).collect();
            let mut fast = pareto_front(&pts);
            fast.sort();
            let mut brute: Vec<usize> = (0..pts.len())
                .filter(|&i| {
                    !(0..pts.len())
                        .any(|j| j != i && pts[j].0 <= pts[i].0 && pts[j].1 <= pts[i].1 && (pts[j].0 < pts[i].0 || pts[j].1 < pts[i].1))
                })
                .collect();
            // Exact duplicates: keep the first only, as the sweep does.
            brute.dedup_by(|a, b| pts[*a] == pts[*b]);
            let mut seen = Vec::new();
            brute.retain(|&i| {
                let dup = seen.contains(&pts[i]);
                seen.push(pts[i]);
                !dup
            });
            brute.sort();
            assert_eq!(fast, brute, "{pts:?}");
        }
    }

    #[test]
    fn log_ticks_are_one_two_five_unless_the_range_is_narrow() {
        let close = |a: &[f64], b: &[f64]| a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x / y - 1.0).abs() < 1e-12);
        assert!(close(&nice_ticks(0.03, 3.0), &[0.05, 0.1, 0.2, 0.5, 1.0, 2.0]), "{:?}", nice_ticks(0.03, 3.0));
        assert!(close(&nice_ticks(0.045, 0.12), &[0.05, 0.06, 0.07, 0.08, 0.09, 0.1]), "{:?}", nice_ticks(0.045, 0.12));
        assert!(nice_ticks(0.0, 1.0).is_empty());
        assert_eq!([sig(0.08), sig(2.0), sig(0.125), sig(150.0), sig(2e-5)], ["0.08", "2", "0.125", "150", "2.0e-5"]);
    }

    #[test]
    fn chart_files_are_written() {
        let dir = std::env::temp_dir().join(format!("aurora-chart-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ms: Vec<Measurement> = (1..6)
            .map(|k| Measurement {
                study: "demo".into(),
                method: if k % 2 == 0 { "a".into() } else { "b".into() },
                param_name: "n".into(),
                param: k as f64,
                stage: "render".into(),
                cost: 0.1 * k as f64,
                unit: CostUnit::Seconds,
                // The last point is a reference: error 0.
                error: if k == 5 { 0.0 } else { 1.0 / k as f64 },
                metric: "rel".into(),
                scene_setting: k == 2,
            })
            .collect();
        draw_study(&ms, "demo", &dir.join("demo")).unwrap();
        let png = std::fs::read(dir.join("demo.png")).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let svg = std::fs::read_to_string(dir.join("demo.svg")).unwrap();
        assert!(svg.contains("<svg") && svg.contains("Pareto front"));
        assert!(svg.contains("reference, error 0") && svg.contains("2 *"), "zero-error and scene markers drawn");
        if std::env::var_os("AURORA_KEEP_CHART").is_none() {
            std::fs::remove_dir_all(&dir).unwrap();
        }
    }
}
