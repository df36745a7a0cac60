//! `grasp-torque sweep`: σ(N) against σ*, with rows, iterations and time, as text,
//! JSON, CSV and an SVG figure (the paper's Figure 9, quantitative).

use super::format::g;
use super::{load, Format, Spacing};
use anyhow::{bail, Context, Result};
use grasp_torque::sweep::{sweep, Sweep, SweepConfig, MAX_REPEATS};
use grasp_torque::{Backend, SfceSpacing};
use plotters::coord::combinators::WithKeyPoints;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub(crate) struct SweepArgs {
    /// The problem file (JSON).
    problem: PathBuf,
    /// Values of N: a range `3..64` (inclusive) or a list `4,8,16,32`.
    #[arg(long, default_value = "3..64")]
    sides: String,
    /// Values of K for SFCe contacts: a range `1..8` or a list.
    #[arg(long, default_value = "2")]
    latitudes: String,
    /// SFCe latitude placement: paper (eq. 13) or uniform (ellipse angle).
    #[arg(long, value_enum)]
    sfce_spacing: Option<Spacing>,
    /// Backend for the linearised problems.
    #[arg(long, default_value = "active-set")]
    backend: String,
    /// Timed solves per row (the median is reported).
    #[arg(long, default_value_t = 21)]
    repeats: usize,
    /// Write every row as CSV here.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write the figure as SVG here.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Output format on stdout.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
}

/// `a..b` (inclusive) or `a,b,c`, each value in `lo..=hi`.
fn parse_values(flag: &str, text: &str, lo: usize, hi: usize) -> Result<Vec<usize>> {
    let parse = |s: &str| -> Result<usize> {
        let v: usize = s
            .trim()
            .parse()
            .with_context(|| format!("{flag}: `{}` is not a whole number", s.trim()))?;
        if !(lo..=hi).contains(&v) {
            bail!("{flag}: {v} is outside {lo}..{hi}");
        }
        Ok(v)
    };
    let values = if let Some((a, b)) = text.split_once("..") {
        let (a, b) = (parse(a)?, parse(b)?);
        if a > b {
            bail!("{flag}: empty range {a}..{b}");
        }
        (a..=b).collect()
    } else {
        text.split(',').map(parse).collect::<Result<Vec<_>>>()?
    };
    if values.is_empty() {
        bail!("{flag}: no values");
    }
    Ok(values)
}

pub(crate) fn run(args: &SweepArgs) -> Result<u8> {
    let p = load(&args.problem)?;
    let sides = parse_values("--sides", &args.sides, 3, grasp_torque::cone::MAX_SIDES)?;
    let latitudes = parse_values(
        "--latitudes",
        &args.latitudes,
        1,
        grasp_torque::cone::MAX_LATITUDES,
    )?;
    let backend: Backend = args
        .backend
        .parse()
        .map_err(|e: String| anyhow::anyhow!("--backend: {e}"))?;
    if !(1..=MAX_REPEATS).contains(&args.repeats) {
        bail!(
            "--repeats: expected 1 to {MAX_REPEATS}, got {}",
            args.repeats
        );
    }
    let config = SweepConfig {
        sides,
        latitudes,
        spacing: args.sfce_spacing.map(|s| match s {
            Spacing::Paper => SfceSpacing::Paper,
            Spacing::Uniform => SfceSpacing::Uniform,
        }),
        backend,
        repeats: args.repeats,
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:30}] {pos}/{len} linearisations, {elapsed}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message("sweep");
    let result = sweep(&p, &config, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })?;
    bar.finish_and_clear();
    if let Some(path) = &args.csv {
        write_csv(path, &result)?;
    }
    if let Some(path) = &args.svg {
        plot(path, &args.problem.display().to_string(), &result)
            .map_err(|e| anyhow::anyhow!("--svg {}: {e}", path.display()))?;
    }
    match args.format {
        Format::Json => outln!("{}", serde_json::to_string_pretty(&to_json(&result))?),
        Format::Text => print_text(
            &args.problem,
            &result,
            p.contacts
                .iter()
                .any(|c| matches!(c, grasp_torque::ContactModel::SfcElliptic { .. })),
        )?,
    }
    Ok(0)
}

fn to_json(s: &Sweep) -> serde_json::Value {
    json!({
        "exact_objective": s.exact_objective,
        "exact_time_us": s.exact_time_us,
        "exact_backend": s.exact_backend.map(|b| b.name()),
        "exact_cross_check": s.exact_cross_check,
        "repeats": s.repeats,
        "rows": s.rows.iter().map(|r| json!({
            "sides": r.sides,
            "latitudes": r.latitudes,
            "status": r.status.as_str(),
            "objective": r.objective,
            "gap": r.gap,
            "constraint_rows": r.constraint_rows,
            "iterations": r.iterations,
            "solve_time_us": r.solve_time_us,
        })).collect::<Vec<_>>(),
    })
}

fn write_csv(path: &Path, s: &Sweep) -> Result<()> {
    let mut f = std::fs::File::create(path).with_context(|| format!("--csv {}", path.display()))?;
    writeln!(f, "sides,latitudes,status,objective,exact_objective,gap,constraint_rows,iterations,solve_time_us,repeats")?;
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x}"));
    for r in &s.rows {
        writeln!(
            f,
            "{},{},{},{},{},{},{},{},{},{}",
            r.sides,
            r.latitudes,
            r.status.as_str(),
            opt(r.objective),
            opt(s.exact_objective),
            opt(r.gap),
            r.constraint_rows,
            r.iterations,
            r.solve_time_us,
            s.repeats
        )?;
    }
    Ok(())
}

fn print_text(problem: &Path, s: &Sweep, sfce: bool) -> Result<()> {
    outln!("problem {}", problem.display());
    match (s.exact_objective, s.exact_time_us, s.exact_backend) {
        (Some(e), Some(t), Some(b)) => {
            outln!("exact cones ({b}): σ* = {}  ({:.1} µs)", g(e, 10), t);
            if let Some(c) = s.exact_cross_check {
                let rel = (c - e).abs() / e.abs().max(c.abs()).max(f64::MIN_POSITIVE);
                outln!(
                    "  cross-check (clarabel): σ* = {}  (relative difference {rel:.1e})",
                    g(c, 10)
                );
            }
        }
        _ => outln!("exact cones: unavailable (no exact backend compiled in, or not optimal)"),
    }
    outln!(
        "gap = (σ(N) − σ*)/σ*, relative; time: median of {} solves per row\n",
        s.repeats
    );
    // K (SFCe latitudes) matters only with SFCe contacts.
    let k_head = if sfce {
        format!("{:>3} ", "K")
    } else {
        String::new()
    };
    outln!(
        "{:>5} {k_head}{:>6} {:>16} {:>11} {:>6} {:>10}",
        "N",
        "rows",
        "σ(N)",
        "gap",
        "iter",
        "time µs"
    );
    for r in &s.rows {
        let k = if sfce {
            format!("{:>3} ", r.latitudes)
        } else {
            String::new()
        };
        outln!(
            "{:>5} {k}{:>6} {:>16} {:>11} {:>6} {:>10.2}",
            r.sides,
            r.constraint_rows,
            r.objective
                .map_or(r.status.as_str().to_string(), |o| g(o, 10)),
            r.gap.map_or("—".into(), |x| g(x, 3)),
            r.iterations,
            r.solve_time_us
        );
    }
    if s.gaps_clamped > 0 {
        outln!(
            "\n{} gap(s) slightly below 0 (within the exact solver's tolerance {:.0e} of σ*) shown as 0",
            s.gaps_clamped,
            grasp_torque::sweep::GAP_FLOOR
        );
    }
    Ok(())
}

type DrawResult<T> = std::result::Result<T, Box<dyn std::error::Error>>;

fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}

/// Tick positions for the N axis: the "nice" values inside the sweep, thinned to at
/// most about 14, so that small N (3–9, where σ changes most) are labelled too.
fn n_ticks(nmin: f64, nmax: f64) -> Vec<f64> {
    let dense = [
        3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 12.0, 14.0, 16.0, 20.0, 24.0, 32.0, 40.0, 48.0,
        64.0, 96.0, 128.0, 192.0, 256.0, 384.0, 512.0, 1024.0, 2048.0, 4096.0,
    ];
    let sparse = [
        3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 48.0, 64.0, 128.0, 256.0, 512.0, 1024.0,
        2048.0, 4096.0,
    ];
    let inside = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .copied()
            .filter(|x| (nmin..=nmax).contains(x))
            .collect()
    };
    let d = inside(&dense);
    if d.len() <= 14 {
        d
    } else {
        inside(&sparse)
    }
}

/// Decade ticks over `[lo, hi]` (with 2 and 5 between when the range is narrow), and
/// the decade-aligned range they span.
fn log_ticks(lo: f64, hi: f64) -> (f64, f64, Vec<f64>) {
    let a = lo.log10().floor() as i32;
    let b = (hi.log10().ceil() as i32).max(a + 1);
    let mut t = Vec::new();
    for e in a..=b {
        let d = 10f64.powi(e);
        t.push(d);
        if b - a <= 2 && e < b {
            t.push(2.0 * d);
            t.push(5.0 * d);
        }
    }
    (10f64.powi(a), 10f64.powi(b), t)
}

/// The series legend, framed, in a corner the panel leaves free.
fn legend<'a, X: Ranged, Y: Ranged>(
    c: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    pos: SeriesLabelPosition,
) -> DrawResult<()> {
    c.configure_series_labels()
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(pos)
        .draw()?;
    Ok(())
}

/// One series over N: a line, its points, and a legend entry drawn the same way.
fn line_with_points<'a, Y: Ranged<ValueType = f64>>(
    c: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<WithKeyPoints<LogCoord<f64>>, Y>>,
    pts: Vec<(f64, f64)>,
    colour: RGBAColor,
    label: String,
) -> DrawResult<()> {
    c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?
        .label(label)
        .legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (20, 0)], colour.stroke_width(2))
                + Circle::new((10, 0), 3, colour.filled())
        });
    c.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, colour.filled())))?;
    Ok(())
}

/// Three panels over N (log scale, every nice N labelled): σ(N) with σ* as its
/// asymptote; the relative gap (log scale; zero gaps marked at the floor); iterations
/// (left axis, integers) and median solve time (right axis). Each panel leaves its
/// top free for the legend, so no legend covers data.
fn plot(path: &Path, title: &str, s: &Sweep) -> DrawResult<()> {
    let root = SVGBackend::new(path, (900, 1050)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(&format!("Linearisation sweep: {title}"), ("sans-serif", 22))?;
    let panels = root.split_evenly((3, 1));
    let nmin = s.rows.iter().map(|r| r.sides).min().unwrap_or(3) as f64;
    let nmax = (s.rows.iter().map(|r| r.sides).max().unwrap_or(4) as f64).max(nmin + 1.0);
    let xs = || {
        (nmin * 0.95..nmax * 1.05)
            .log_scale()
            .with_key_points(n_ticks(nmin, nmax))
    };
    let mut ks: Vec<usize> = s.rows.iter().map(|r| r.latitudes).collect();
    ks.sort_unstable();
    ks.dedup();
    let colour = |i: usize| Palette99::pick(i).to_rgba();
    let name = |k: usize| {
        if ks.len() > 1 {
            format!(", K = {k}")
        } else {
            String::new()
        }
    };
    let series =
        |k: usize, f: &dyn Fn(&grasp_torque::sweep::SweepRow) -> Option<f64>| -> Vec<(f64, f64)> {
            s.rows
                .iter()
                .filter(|r| r.latitudes == k)
                .filter_map(|r| f(r).map(|v| (r.sides as f64, v)))
                .collect()
        };

    // Panel 1: σ(N) and σ*; the top third is left for the legend.
    let objs: Vec<f64> = s
        .rows
        .iter()
        .filter_map(|r| r.objective)
        .chain(s.exact_objective)
        .collect();
    let (lo, hi) = min_max(&objs);
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 1e-3).max(1e-12);
    let top = hi + pad + (hi - lo + 2.0 * pad) * 0.5;
    let mut c = ChartBuilder::on(&panels[0])
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .caption(
            "σ(N) = Σ τ² with N-sided inscribed cones, and the exact-cone optimum σ*",
            ("sans-serif", 16),
        )
        .build_cartesian_2d(xs(), (lo - pad)..top)?;
    c.configure_mesh()
        .x_desc("N (sides)")
        .y_desc("σ")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| g(*v, 5))
        .draw()?;
    for (i, &k) in ks.iter().enumerate() {
        line_with_points(
            &mut c,
            series(k, &|r| r.objective),
            colour(i),
            format!("σ(N){}", name(k)),
        )?;
    }
    if let Some(e) = s.exact_objective {
        c.draw_series(DashedLineSeries::new(
            vec![(nmin * 0.95, e), (nmax * 1.05, e)],
            8,
            5,
            BLACK.stroke_width(2),
        ))?
        .label(format!("σ* = {} (exact cones)", g(e, 8)))
        .legend(|(x, y)| {
            DashedPathElement::new(vec![(x, y), (x + 20, y)], 5, 3, BLACK.stroke_width(2))
        });
    }
    legend(&mut c, SeriesLabelPosition::UpperRight)?;

    // Panel 2: relative gap, log scale over whole decades; zero gaps at the floor.
    let gaps: Vec<f64> = s
        .rows
        .iter()
        .filter_map(|r| r.gap)
        .filter(|&g| g > 0.0)
        .collect();
    let zeros: Vec<(usize, f64)> = s
        .rows
        .iter()
        .filter(|r| r.gap == Some(0.0))
        .map(|r| (r.latitudes, r.sides as f64))
        .collect();
    if !gaps.is_empty() {
        let (glo, ghi) = min_max(&gaps);
        let (ylo, yhi, ticks) = log_ticks(glo, ghi * 10.0);
        let mut c = ChartBuilder::on(&panels[1])
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .caption(
                "relative gap (σ(N) − σ*)/σ*; hollow markers on the floor: gap 0 (N-gon vertex at the optimum)",
                ("sans-serif", 16),
            )
            .build_cartesian_2d(xs(), (ylo..yhi).log_scale().with_key_points(ticks))?;
        c.configure_mesh()
            .x_desc("N (sides)")
            .y_desc("gap")
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()?;
        for (i, &k) in ks.iter().enumerate() {
            let pts = series(k, &|r| r.gap)
                .into_iter()
                .filter(|p| p.1 > 0.0)
                .collect();
            line_with_points(&mut c, pts, colour(i), format!("gap{}", name(k)))?;
            let at_floor: Vec<(f64, f64)> = zeros
                .iter()
                .filter(|z| z.0 == k)
                .map(|z| (z.1, ylo))
                .collect();
            if !at_floor.is_empty() {
                c.draw_series(
                    at_floor
                        .into_iter()
                        .map(|p| Circle::new(p, 5, colour(i).stroke_width(2))),
                )?
                .label(format!("gap 0{}", name(k)))
                .legend(move |(x, y)| Circle::new((x + 10, y), 5, colour(i).stroke_width(2)));
            }
        }
        legend(&mut c, SeriesLabelPosition::UpperRight)?;
    }

    // Panel 3: iterations (integers) and time; the top is left for the legend.
    let imax = s
        .rows
        .iter()
        .map(|r| r.iterations)
        .max()
        .unwrap_or(1)
        .max(1) as f64;
    let tmax = s
        .rows
        .iter()
        .map(|r| r.solve_time_us)
        .fold(0.0, f64::max)
        .max(1e-3);
    let mut c = ChartBuilder::on(&panels[2])
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .right_y_label_area_size(80)
        .caption(
            format!(
                "iterations (solid, left) and median solve time of {} solves (dashed, right)",
                s.repeats
            ),
            ("sans-serif", 16),
        )
        .build_cartesian_2d(xs(), 0.0..imax * 1.8)?
        .set_secondary_coord(xs(), 0.0..tmax * 1.8);
    c.configure_mesh()
        .x_desc("N (sides)")
        .y_desc("iterations")
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| {
            if v.fract() == 0.0 {
                format!("{v:.0}")
            } else {
                String::new()
            }
        })
        .draw()?;
    c.configure_secondary_axes()
        .y_desc("time (µs)")
        .y_label_formatter(&|v| g(*v, 3))
        .draw()?;
    for (i, &k) in ks.iter().enumerate() {
        c.draw_series(LineSeries::new(
            series(k, &|r| Some(r.iterations as f64)),
            colour(i).stroke_width(2),
        ))?
        .label(format!("iterations{}", name(k)))
        .legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 20, y)], colour(i).stroke_width(2))
        });
        c.draw_secondary_series(DashedLineSeries::new(
            series(k, &|r| Some(r.solve_time_us)),
            6,
            4,
            colour(i).stroke_width(2),
        ))?
        .label(format!("time µs{}", name(k)))
        .legend(move |(x, y)| {
            DashedPathElement::new(vec![(x, y), (x + 20, y)], 5, 3, colour(i).stroke_width(2))
        });
    }
    legend(&mut c, SeriesLabelPosition::UpperLeft)?;
    root.present()?;
    Ok(())
}
