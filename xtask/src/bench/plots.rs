//! The report's plots (SVG, plotters).

#[allow(unused_imports)]
use super::*;

pub(crate) type Curve = (String, Vec<(f64, f64)>);

pub(crate) fn plot_err(name: &str) -> impl Fn(String) -> BenchError + '_ {
    move |detail| BenchError::Plot {
        name: name.to_string(),
        detail,
    }
}

pub(crate) fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return 0.1..10.0;
    }
    let (lo, hi) = if hi / lo < 10.0 {
        (lo / 3.0, hi * 3.0)
    } else {
        (lo / 1.5, hi * 1.5)
    };
    lo..hi
}

/// A line plot with markers, log y axis, log or linear x axis, as an SVG string.
pub(crate) struct PlotSpec<'a> {
    file: &'a str,
    title: &'a str,
    x_desc: &'a str,
    y_desc: &'a str,
    log_x: bool,
    /// Where the legend goes; with `UpperLeft` the log y range is extended upwards so that the
    /// legend sits above the data.
    legend: SeriesLabelPosition,
    size: (u32, u32),
}

pub(crate) fn line_plot(spec: &PlotSpec<'_>, curves: &[Curve]) -> Result<String, BenchError> {
    let PlotSpec {
        file,
        title,
        x_desc,
        y_desc,
        log_x,
        ..
    } = *spec;
    let err = plot_err(file);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, spec.size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let ys = log_range(curves.iter().flat_map(|c| c.1.iter().map(|p| p.1)));
        let ys = if matches!(spec.legend, SeriesLabelPosition::UpperLeft) {
            // The legend needs about 17 px per entry of the plot height (size − captions and
            // axis labels); give it that fraction f of the log range: log H = f·D / (1 − f).
            let plot_height = f64::from(spec.size.1) - 110.0;
            let f = ((curves.len() as f64 * 17.0 + 24.0) / plot_height).min(0.6);
            let decades = (ys.end / ys.start).log10();
            ys.start..ys.end * 10f64.powf(f * decades / (1.0 - f))
        } else {
            ys
        };
        let xs: Vec<f64> = curves.iter().flat_map(|c| c.1.iter().map(|p| p.0)).collect();
        let mut builder = ChartBuilder::on(&root);
        builder
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(75);
        macro_rules! finish {
            ($chart:expr) => {{
                let mut chart = $chart.map_err(|e| err(e.to_string()))?;
                chart
                    .configure_mesh()
                    .x_desc(x_desc)
                    .y_desc(y_desc)
                    .label_style(("sans-serif", 14))
                    .axis_desc_style(("sans-serif", 15))
                    .y_label_formatter(&|v| format!("{v:.0e}"))
                    .x_label_formatter(&|v| {
                        if log_x {
                            format_count(v.round() as usize)
                        } else {
                            format!("{v:.0}")
                        }
                    })
                    .draw()
                    .map_err(|e| err(e.to_string()))?;
                for (i, (name, points)) in curves.iter().enumerate() {
                    let color = Palette99::pick(i).to_rgba();
                    let pts: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1 > 0.0).collect();
                    chart
                        .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                        .map_err(|e| err(e.to_string()))?
                        .label(name.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
                    chart
                        .draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
                        .map_err(|e| err(e.to_string()))?;
                }
                chart
                    .configure_series_labels()
                    .position(spec.legend.clone())
                    .label_font(("sans-serif", 13))
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| err(e.to_string()))?;
            }};
        }
        if log_x {
            let xr = log_range(xs.into_iter());
            finish!(builder.build_cartesian_2d(xr.log_scale(), ys.log_scale()));
        } else {
            let hi = xs.iter().copied().fold(1.0f64, f64::max);
            let lo = xs.iter().copied().fold(hi, f64::min);
            let pad = ((hi - lo) * 0.05).max(0.5);
            finish!(builder.build_cartesian_2d((lo - pad)..(hi + pad), ys.log_scale()));
        }
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(buf)
}

/// The SVG files of the report: (file name, content).
///
/// # Errors
/// [`BenchError::Plot`].
pub fn plots(report: &Report) -> Result<Vec<(String, String)>, BenchError> {
    let mut out = Vec::new();
    let f3 = &report.figure3;
    let curves: Vec<Curve> = f3
        .times
        .iter()
        .zip(&f3.errors)
        .map(|(t, errs)| {
            (
                format!("t = {t}"),
                f3.ks
                    .iter()
                    .zip(errs)
                    .map(|(&k, &e)| (k as f64, e.max(1e-17)))
                    .collect(),
            )
        })
        .collect();
    let name = "figure3_spectral_error.svg";
    out.push((
        name.to_string(),
        line_plot(
            &PlotSpec {
                file: name,
                title: &format!("Spectral (k eigenpairs) vs rational K_t e_i, n = {}", f3.n),
                x_desc: "k (eigenpairs)",
                y_desc: "relative L-inf error",
                log_x: false,
                legend: SeriesLabelPosition::MiddleRight,
                size: (900, 560),
            },
            &curves,
        )?,
    ));
    for f2 in &report.figure2 {
        let curves: Vec<Curve> = f2
            .times
            .iter()
            .zip(&f2.matrix)
            .map(|(t, row)| {
                (
                    format!("t = {t}"),
                    row.iter().enumerate().map(|(j, &k)| ((j + 1) as f64, k)).collect(),
                )
            })
            .collect();
        let name = format!("figure2_condition_r{}.svg", f2.degree);
        out.push((
            name.clone(),
            line_plot(
                &PlotSpec {
                    file: &name,
                    title: &format!("cond_2(tL - z_j B), degree {}, n = {}", f2.degree, f2.n),
                    x_desc: "pole index j",
                    y_desc: "2-norm condition number",
                    log_x: false,
                    legend: SeriesLabelPosition::UpperLeft,
                    size: (900, 560),
                },
                &curves,
            )?,
        ));
    }
    for (name, field, y, symbol) in [
        ("scaling_time.svg", 0, "seconds", "p"),
        ("scaling_memory.svg", 1, "peak heap bytes", "q"),
    ] {
        let curves: Vec<Curve> = report
            .series
            .iter()
            .map(|s| {
                let p = s.points(
                    &report.sizes,
                    |m| {
                        if field == 0 {
                            m.seconds
                        } else {
                            m.peak_bytes as f64
                        }
                    },
                );
                let e = fit_exponent(&p).map_or(String::new(), |e| format!(" ({symbol} = {e:.2})"));
                (format!("{}{e}", s.name), p)
            })
            .filter(|c| !c.1.is_empty())
            .collect();
        out.push((
            name.to_string(),
            line_plot(
                &PlotSpec {
                    file: name,
                    title: &format!("{y} against n (log-log, fitted exponent {symbol})"),
                    x_desc: "n (vertices)",
                    y_desc: y,
                    log_x: true,
                    legend: SeriesLabelPosition::UpperLeft,
                    size: (1100, 760),
                },
                &curves,
            )?,
        ));
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------
