//! Tables and the scaling figure of docs/benchmarks.md, from the criterion results of
//! `cargo bench -p grasp-torque --bench backends --features osqp` (read from target/criterion).
//!
//! Run: `cargo run --release -p grasp-torque --example bench_report > /tmp/tables.md`
//! (also writes docs/figures/scaling.svg).

use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

#[path = "../benches/common/fixtures.rs"]
mod fixtures;

/// Median in ns of `target/criterion/grasp/<function>/<fixture>`.
fn median(root: &Path, function: &str, fixture: &str) -> Option<f64> {
    let p = root.join(function).join(fixture).join("new/estimates.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()?;
    v["median"]["point_estimate"].as_f64()
}

fn us(ns: Option<f64>) -> String {
    match ns {
        Some(v) if v < 10_000.0 => format!("{:.2}", v / 1e3),
        Some(v) => format!("{:.1}", v / 1e3),
        None => "—".into(),
    }
}

fn ratio(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => format!("{:.0}×", a / b),
        _ => "—".into(),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root =
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join("target/criterion/grasp");
    let fx = fixtures::all();
    println!("| fixture | joints | rows | build: new grasp µs | build: new wrench µs | native cold µs | native warm µs | cold/warm | Clarabel linear µs | Clarabel/native | OSQP µs | OSQP/native | Clarabel exact µs |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut scaling: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for f in &fx {
        let qp = grasp_torque::TorqueQp::from_problem(&f.problem, &Default::default())?;
        let n = f.name.as_str();
        let cold = median(&root, "native-cold", n);
        let warm = median(&root, "native-warm-1pct", n);
        let clar = median(&root, "clarabel-linear", n);
        let osqp = median(&root, "osqp-linear", n);
        let exact_name = match n.rfind("-N") {
            Some(i) => format!("{}-N4", &n[..i]),
            None => n.to_string(),
        };
        let exact = median(&root, "clarabel-exact", &exact_name);
        println!(
            "| {n} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            qp.joints(),
            qp.inequality_rows(),
            us(median(&root, "build-new-grasp", n)),
            us(median(&root, "build-new-wrench", n)),
            us(cold),
            us(warm),
            match (cold, warm) {
                (Some(c), Some(w)) => format!("{:.1}×", c / w),
                _ => "—".into(),
            },
            us(clar),
            ratio(clar, cold),
            us(osqp),
            ratio(osqp, cold),
            us(exact),
        );
        if let (Some(i), Some(c)) = (n.rfind("-N"), cold) {
            scaling
                .entry(format!("{} ({} joints)", &n[..i], qp.joints()))
                .or_default()
                .push((qp.inequality_rows() as f64, c / 1e3));
        }
    }
    let path =
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join("docs/figures/scaling.svg");
    let area = SVGBackend::new(&path, (900, 600)).into_drawing_area();
    area.fill(&WHITE)?;
    let xmax = scaling.values().flatten().map(|p| p.0).fold(1.0, f64::max);
    let ymax = scaling.values().flatten().map(|p| p.1).fold(1.0, f64::max);
    let mut c = ChartBuilder::on(&area)
        .margin(15)
        .caption(
            "Native solve time (cold, median) against inequality rows",
            ("sans-serif", 20),
        )
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (10.0..xmax * 1.2).log_scale(),
            (0.5..ymax * 1.5).log_scale(),
        )?;
    // Log axes get a label at every minor tick: keep decades and their 2× and 5×.
    let sparse = |v: &f64| {
        let lead = v / 10f64.powf(v.log10().floor());
        if [1.0, 2.0, 5.0].iter().any(|d| (lead - d).abs() < 1e-6) {
            format!("{v:.0}")
        } else {
            String::new()
        }
    };
    c.configure_mesh()
        .x_desc("inequality rows (N × contacts, SFCe: 2NK+1 per contact)")
        .y_desc("µs")
        .x_label_formatter(&sparse)
        .y_label_formatter(&sparse)
        .light_line_style(RGBColor(242, 242, 242))
        .draw()?;
    for (i, (label, pts)) in scaling.iter().enumerate() {
        let col = Palette99::pick(i).to_rgba();
        c.draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
        c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, col.filled())))?;
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    area.present()?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
