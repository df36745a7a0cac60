//! `grasp-torque batch`: one problem per input line, solved in parallel; one result per
//! output line, in input order.

use super::{ModelArgs, OutputError};
use anyhow::{Context, Result};
use grasp_torque::{
    solve_batch, BatchGrasp, BatchOptions, GraspProblem, ProblemParser, Solution, SolverConfig,
    Status,
};
use rayon::prelude::*;
use serde_json::{json, Map, Value};
use std::io::{BufRead, BufReader, IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(clap::Args, Debug)]
pub(crate) struct BatchArgs {
    /// JSON lines: one problem per line, in any of the three forms, optionally with
    /// `"wrenches": [[Fx, Fy, Fz, Mx, My, Mz], …]` to solve it for each (sharing one
    /// model build; a hand-form line's `object` weighs on each). `-` reads standard
    /// input. Relative robot paths of hand-form lines are relative to the file's folder
    /// (the working directory for `-`).
    input: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Output: one JSON object per line, or CSV with a header.
    #[arg(long, value_enum, default_value = "jsonl")]
    format: BatchFormat,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum BatchFormat {
    Jsonl,
    Csv,
}

/// Lines read and solved together: enough to keep every core busy, few enough that
/// memory stays flat on inputs of any length.
const CHUNK_LINES: usize = 4096;

/// The CSV columns. `torque` and `joint_names` hold one value per joint, separated by
/// spaces; `message` says why a line is not optimal.
const CSV_HEADER: &str = "line,wrench,status,objective,wrench_residual,torque_residual,consistency_residual,iterations,solve_time_us,torque,joint_names,message";

/// What a batch's lines came to, for the exit code.
#[derive(Default)]
struct Tally {
    lines: usize,
    records: usize,
    invalid: usize,
    infeasible: usize,
    failed: usize,
}

impl Tally {
    /// 2 when a line was invalid, else 4 when a solve failed numerically or hit its
    /// iteration limit, else 3 when a grasp was infeasible, else 0 (as `solve`).
    fn exit_code(&self) -> u8 {
        if self.invalid > 0 {
            2
        } else if self.failed > 0 {
            4
        } else if self.infeasible > 0 {
            3
        } else {
            0
        }
    }
}

pub(crate) fn run(args: &BatchArgs) -> Result<u8> {
    if let Some(n) = args.threads {
        if n == 0 || n > grasp_torque::batch::MAX_THREADS {
            anyhow::bail!(
                "--threads: expected 1 to {}, got {n}",
                grasp_torque::batch::MAX_THREADS
            );
        }
        // Parsing, solving and formatting all run on this pool.
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .context("--threads: could not start the worker threads")?;
    }
    let (reader, size, base): (Box<dyn Read>, Option<u64>, PathBuf) =
        if args.input.as_os_str() == "-" {
            (Box::new(std::io::stdin()), None, PathBuf::from("."))
        } else {
            let f = std::fs::File::open(&args.input)
                .with_context(|| format!("{}", args.input.display()))?;
            let size = f.metadata().ok().map(|m| m.len());
            let base = args
                .input
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_else(|| PathBuf::from("."));
            (Box::new(f), size, base)
        };
    let mut reader = BufReader::with_capacity(1 << 20, reader);
    let parser = ProblemParser::new();
    let progress = Progress::new(size);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if args.format == BatchFormat::Csv {
        writeln!(out, "{CSV_HEADER}").map_err(OutputError)?;
    }
    let mut tally = Tally::default();
    let mut line_no = 0;
    let mut read = 0u64;
    let mut ended = false;
    while !ended {
        let mut chunk = Vec::with_capacity(CHUNK_LINES);
        while chunk.len() < CHUNK_LINES {
            let Some(line) = next_line(&mut reader, &args.input)? else {
                ended = true;
                break;
            };
            line_no += 1;
            read += line.bytes;
            ended = line.last;
            // Blank lines are skipped, but still counted for line numbers.
            if !matches!(&line.text, Ok(t) if t.trim().is_empty()) {
                chunk.push((line_no, line.text));
            }
            if ended {
                break;
            }
        }
        if chunk.is_empty() {
            break;
        }
        let records = solve_chunk(&chunk, &parser, &base, &args.model, args.format, &mut tally);
        for r in records {
            out.write_all(r.as_bytes()).map_err(OutputError)?;
        }
        progress.update(read, tally.lines);
    }
    out.flush().map_err(OutputError)?;
    progress.finish();
    eprintln!(
        "batch: {} lines, {} results: {} invalid, {} infeasible, {} failed",
        tally.lines, tally.records, tally.invalid, tally.infeasible, tally.failed
    );
    Ok(tally.exit_code())
}

/// The longest line read: a problem file's limit.
const MAX_LINE_BYTES: u64 = grasp_torque::file::MAX_FILE_BYTES;

/// The most of one over-long line skipped in search of its end (1 GiB): past it the
/// input is taken as endless (`/dev/zero`) and read no further.
const MAX_SKIP_BYTES: u64 = 16 * MAX_LINE_BYTES;

/// One line read: its text (without its end) or why it is not one, the bytes
/// consumed, and whether reading stops after it.
struct Line {
    text: Result<String, String>,
    bytes: u64,
    last: bool,
}

/// The next line; `None` at the end of input. A line longer than the limit is
/// skipped unread, up to [`MAX_SKIP_BYTES`].
fn next_line(r: &mut impl BufRead, path: &Path) -> Result<Option<Line>> {
    let mut buf = Vec::new();
    let n = r
        .by_ref()
        .take(MAX_LINE_BYTES + 1)
        .read_until(b'\n', &mut buf)
        .with_context(|| format!("{}", path.display()))?;
    if n == 0 {
        return Ok(None);
    }
    let mut consumed = n as u64;
    if buf.last() != Some(&b'\n') && n as u64 > MAX_LINE_BYTES {
        // Skip the rest of the line, a mebibyte at a time.
        let mut ended = false;
        while !ended && consumed <= MAX_SKIP_BYTES {
            buf.clear();
            let n = r
                .by_ref()
                .take(1 << 20)
                .read_until(b'\n', &mut buf)
                .with_context(|| format!("{}", path.display()))?;
            consumed += n as u64;
            ended = n == 0 || buf.last() == Some(&b'\n');
        }
        let text = if ended {
            format!("(input): expected a line of at most {MAX_LINE_BYTES} bytes, got a longer one")
        } else {
            format!(
                "(input): expected a line of at most {MAX_LINE_BYTES} bytes, got one with no end within {MAX_SKIP_BYTES} bytes (an endless input?): the input is read no further"
            )
        };
        return Ok(Some(Line {
            text: Err(text),
            bytes: consumed,
            last: !ended,
        }));
    }
    while matches!(buf.last(), Some(b'\n' | b'\r')) {
        buf.pop();
    }
    let text = String::from_utf8(buf).map_err(|e| {
        format!(
            "(input): expected UTF-8 text (JSON), got invalid UTF-8 at byte {}",
            e.utf8_error().valid_up_to()
        )
    });
    Ok(Some(Line {
        text,
        bytes: consumed,
        last: false,
    }))
}

/// A parsed line: its grasp and valid wrenches, why each listed wrench that is not
/// valid is not (one entry per listed wrench, in order; empty without `wrenches`), and
/// the solver configuration of the flags.
struct Parsed {
    grasp: BatchGrasp,
    slots: Vec<Option<String>>,
    config: SolverConfig,
}

fn parse_line(
    text: &str,
    parser: &ProblemParser,
    base: &Path,
    model: &ModelArgs,
) -> Result<Parsed, String> {
    let mut value: Value = grasp_torque::file::from_json_str(text).map_err(|e| e.to_string())?;
    let (listed, wrenches) = match value.as_object_mut().and_then(|o| o.remove("wrenches")) {
        None => (false, Vec::new()),
        Some(w) => (true, wrench_list(&w)?),
    };
    let text = if !listed {
        std::borrow::Cow::Borrowed(text)
    } else {
        std::borrow::Cow::Owned(value.to_string())
    };
    let loaded = parser.parse_at(&text, base).map_err(|e| e.to_string())?;
    // A hand-form line's `object` weighs on every wrench, as on its `wrench`.
    let weight = loaded.hand.as_ref().and_then(|h| h.object_weight);
    let mut slots = Vec::with_capacity(wrenches.len());
    let mut valid = Vec::with_capacity(wrenches.len());
    for (k, w) in wrenches.into_iter().enumerate() {
        let w = w.and_then(|mut w| {
            let Some(weight) = weight else { return Ok(w) };
            for (x, v) in w.iter_mut().zip(weight) {
                *x = grasp_torque::problem::flush_subnormal(*x + v);
            }
            if w.iter().all(|&x| grasp_torque::problem::in_domain(x)) {
                Ok(w)
            } else {
                Err(format!(
                    "wrenches[{k}] plus the object's weight: expected each component {}, got {w:?}",
                    grasp_torque::problem::DOMAIN
                ))
            }
        });
        match w {
            Ok(w) => {
                valid.push(w);
                slots.push(None);
            }
            Err(e) => slots.push(Some(e)),
        }
    }
    let mut problem: GraspProblem = loaded.problem;
    let config = model
        .configure(&mut problem)
        .map_err(|e| format!("{e:#}"))?;
    Ok(Parsed {
        grasp: BatchGrasp {
            problem,
            wrenches: valid,
        },
        slots,
        config,
    })
}

/// The listed wrenches, each parsed or why it is not a wrench: a bad wrench is a record
/// of its own, and the line's other wrenches are solved. A `wrenches` that is not a
/// non-empty list makes the whole line invalid.
#[allow(clippy::type_complexity)]
fn wrench_list(v: &Value) -> Result<Vec<Result<[f64; 6], String>>, String> {
    let list = v.as_array().filter(|l| !l.is_empty()).ok_or_else(|| {
        format!(
            "wrenches: expected a non-empty list of wrenches [Fx, Fy, Fz, Mx, My, Mz], got {}",
            if v.as_array().is_some() {
                "an empty list".into()
            } else {
                v.to_string()
            }
        )
    })?;
    Ok(list
        .iter()
        .enumerate()
        .map(|(k, w)| {
            let nums: Option<Vec<f64>> = w
                .as_array()
                .map(|a| a.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
                .unwrap_or(None);
            match nums {
                Some(n)
                    if n.len() == 6 && n.iter().all(|&x| grasp_torque::problem::in_domain(x)) =>
                {
                    let mut a = [0.0; 6];
                    a.copy_from_slice(&n);
                    Ok(a)
                }
                _ => Err(format!(
                    "wrenches[{k}]: expected [Fx, Fy, Fz, Mx, My, Mz], each {}, got {w}",
                    grasp_torque::problem::DOMAIN
                )),
            }
        })
        .collect())
}

/// Parses, solves and formats one chunk of lines, in parallel; records in input order.
fn solve_chunk(
    chunk: &[(usize, Result<String, String>)],
    parser: &ProblemParser,
    base: &Path,
    model: &ModelArgs,
    format: BatchFormat,
    tally: &mut Tally,
) -> Vec<String> {
    let parsed: Vec<Result<Parsed, String>> = chunk
        .par_iter()
        .map(|(_, text)| {
            text.as_ref()
                .map_err(Clone::clone)
                .and_then(|t| parse_line(t, parser, base, model))
        })
        .collect();
    let n = chunk.len();
    let mut errors: Vec<Option<String>> = vec![None; n];
    let mut slots: Vec<Vec<Option<String>>> = vec![Vec::new(); n];
    let mut grasps = Vec::with_capacity(n);
    let mut line_of = Vec::with_capacity(n);
    // Every line's configuration comes from the same flags (the problem's own options
    // travel with the problem): the first good line's serves all.
    let mut config = None;
    for (i, p) in parsed.into_iter().enumerate() {
        match p {
            Ok(p) => {
                config.get_or_insert(p.config);
                slots[i] = p.slots;
                if !slots[i].is_empty() && p.grasp.wrenches.is_empty() {
                    // Nothing to solve, but the problem is still checked, as a solved
                    // line's is.
                    if let Err(e) = p.grasp.problem.validate() {
                        errors[i] = Some(e.to_string());
                    }
                    continue;
                }
                grasps.push(p.grasp);
                line_of.push(i);
            }
            Err(e) => errors[i] = Some(e),
        }
    }
    let mut results: Vec<Vec<Solution>> = vec![Vec::new(); n];
    if let Some(config) = &config {
        match solve_batch(&grasps, config, &BatchOptions::default()) {
            Ok(out) => {
                for r in out {
                    let i = line_of[r.grasp];
                    match r.outcome {
                        Ok(s) => results[i].push(s),
                        Err(e) => {
                            errors[i].get_or_insert_with(|| e.to_string());
                        }
                    }
                }
            }
            Err(e) => line_of
                .iter()
                .for_each(|&i| errors[i] = Some(e.to_string())),
        }
    }
    let mut problem_of: Vec<Option<&GraspProblem>> = vec![None; n];
    for (g, &i) in line_of.iter().enumerate() {
        problem_of[i] = Some(&grasps[g].problem);
    }
    // Each line's records, and each record's status (`None`: invalid).
    let records: Vec<(String, Vec<Option<Status>>)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let line = chunk[i].0;
            match (&errors[i], problem_of[i]) {
                (None, Some(p)) if slots[i].is_empty() => {
                    let sols = &results[i];
                    let text: String = sols
                        .iter()
                        .enumerate()
                        .map(|(k, s)| record(line, k, p, s, format))
                        .collect();
                    (text, sols.iter().map(|s| Some(s.status)).collect())
                }
                // Listed wrenches: the solutions of the valid ones in order, a record
                // of its own for each invalid one (a line with no valid one was not
                // solved).
                (None, p) if !slots[i].is_empty() => {
                    let mut sols = results[i].iter();
                    let (mut text, mut statuses) = (String::new(), Vec::new());
                    for (k, slot) in slots[i].iter().enumerate() {
                        let solved = slot.is_none().then(|| sols.next()).flatten();
                        match (slot, p.zip(solved)) {
                            (None, Some((p, s))) => {
                                text.push_str(&record(line, k, p, s, format));
                                statuses.push(Some(s.status));
                            }
                            (e, _) => {
                                let e = e.as_deref().unwrap_or("not solved");
                                text.push_str(&error_record(line, Some(k), e, format));
                                statuses.push(None);
                            }
                        }
                    }
                    (text, statuses)
                }
                (e, _) => (
                    error_record(line, None, e.as_deref().unwrap_or("not solved"), format),
                    vec![None],
                ),
            }
        })
        .collect();
    let mut texts = Vec::with_capacity(records.len());
    for (text, statuses) in records {
        tally.lines += 1;
        for s in statuses {
            tally.records += 1;
            match s {
                None => tally.invalid += 1,
                Some(Status::Infeasible) => tally.infeasible += 1,
                Some(s) if !s.has_answer() => tally.failed += 1,
                Some(_) => {}
            }
        }
        texts.push(text);
    }
    texts
}

/// A line, or one of its listed wrenches, that could not be solved: its line number
/// (and wrench) and the same message `solve` gives for the file.
fn error_record(line: usize, wrench: Option<usize>, message: &str, format: BatchFormat) -> String {
    match (format, wrench) {
        (BatchFormat::Jsonl, None) => format!(
            "{{\"line\":{line},\"status\":\"invalid\",\"error\":{}}}\n",
            json!(message)
        ),
        (BatchFormat::Jsonl, Some(k)) => format!(
            "{{\"line\":{line},\"wrench\":{k},\"status\":\"invalid\",\"error\":{}}}\n",
            json!(message)
        ),
        (BatchFormat::Csv, k) => format!(
            "{line},{},invalid,,,,,,,,,{}\n",
            k.map(|k| k.to_string()).unwrap_or_default(),
            csv_field(message)
        ),
    }
}

fn record(line: usize, k: usize, p: &GraspProblem, s: &Solution, format: BatchFormat) -> String {
    let ok = !s.torque.is_empty();
    let d = &s.diagnostics;
    // Names of the torques solved for: actuators with a transmission, else joints.
    let actuated = p.transmission.is_some();
    let names: Vec<String> = if actuated {
        (0..p.actuated()).map(|j| p.actuator_name(j)).collect()
    } else if p.joint_names.is_empty() {
        Vec::new()
    } else {
        (0..p.joints()).map(|j| p.joint_name(j)).collect()
    };
    let message = s.reason.as_ref().map(ToString::to_string);
    match format {
        BatchFormat::Jsonl => {
            let mut o = Map::new();
            o.insert("status".into(), json!(s.status));
            if let Some(r) = &s.reason {
                let mut v = serde_json::to_value(r).unwrap_or(Value::Null);
                if let Some(m) = v.as_object_mut() {
                    m.insert("message".into(), json!(message));
                }
                o.insert("reason".into(), v);
            }
            if ok {
                o.insert("objective".into(), json!(s.objective));
                o.insert("torque".into(), json!(s.torque));
                let mut off = 0;
                let forces: Vec<&[f64]> = p
                    .contacts
                    .iter()
                    .map(|c| {
                        let f = &s.contact_forces[off..off + c.dim()];
                        off += c.dim();
                        f
                    })
                    .collect();
                o.insert("contact_forces".into(), json!(forces));
                o.insert(
                    "object_forces".into(),
                    json!(grasp_torque::model::object_forces(
                        &p.grasp_matrix,
                        &p.contacts,
                        &s.contact_forces
                    )),
                );
                o.insert(
                    "residuals".into(),
                    json!({"wrench": d.wrench_residual, "torque": d.torque_residual, "consistency": d.consistency_residual}),
                );
            }
            if actuated {
                // `torque` holds u per actuator; `joint_torque` τ = T u per joint.
                if ok && !s.joint_torque.is_empty() {
                    o.insert("joint_torque".into(), json!(s.joint_torque));
                }
                o.insert("actuator_names".into(), json!(names));
                if !p.joint_names.is_empty() {
                    o.insert("joint_names".into(), json!(p.joint_names));
                }
            } else if !names.is_empty() {
                o.insert("joint_names".into(), json!(names));
            }
            o.insert("iterations".into(), json!(s.iterations));
            o.insert(
                "solve_time_us".into(),
                json!(s.solve_time.as_secs_f64() * 1e6),
            );
            // The line and wrench first, so that a reader sees at once what it is.
            let rest = Value::Object(o).to_string();
            format!("{{\"line\":{line},\"wrench\":{k},{}\n", &rest[1..])
        }
        BatchFormat::Csv => {
            let num = |x: f64| if ok { format!("{x:e}") } else { String::new() };
            let torque: Vec<String> = s.torque.iter().map(|t| format!("{t:e}")).collect();
            format!(
                "{line},{k},{},{},{},{},{},{},{:.3},{},{},{}\n",
                s.status,
                num(s.objective),
                num(d.wrench_residual),
                num(d.torque_residual),
                num(d.consistency_residual),
                s.iterations,
                s.solve_time.as_secs_f64() * 1e6,
                torque.join(" "),
                csv_field(&names.join(" ")),
                csv_field(message.as_deref().unwrap_or("")),
            )
        }
    }
}

/// A CSV field, quoted when it holds a separator, a quote or a line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A progress bar on standard error, shown only when standard error is a terminal and
/// standard output is not (results go to a file or a pipe), and only once the batch
/// has run for a second: short batches and scripts see nothing.
struct Progress {
    bar: Option<indicatif::ProgressBar>,
    start: Instant,
    shown: std::cell::Cell<bool>,
}

impl Progress {
    fn new(size: Option<u64>) -> Self {
        let wanted = std::io::stderr().is_terminal() && !std::io::stdout().is_terminal();
        let bar = wanted.then(|| {
            let bar = indicatif::ProgressBar::with_draw_target(
                size,
                indicatif::ProgressDrawTarget::hidden(),
            );
            let template = if size.is_some() {
                "batch [{bar:30}] {percent}% {msg}, {elapsed} (eta {eta})"
            } else {
                "batch {spinner} {msg}, {elapsed}"
            };
            bar.set_style(
                indicatif::ProgressStyle::with_template(template)
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            bar
        });
        Self {
            bar,
            start: Instant::now(),
            shown: std::cell::Cell::new(false),
        }
    }

    fn update(&self, bytes: u64, lines: usize) {
        let Some(bar) = &self.bar else { return };
        if !self.shown.get() && self.start.elapsed() > Duration::from_secs(1) {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            self.shown.set(true);
        }
        bar.set_position(bytes);
        bar.set_message(format!("{lines} lines"));
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
