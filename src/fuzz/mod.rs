//! The input fuzzer of `rbc-bench fuzz`: mutated recording.toml, scene and sweep TOML, the CSV tables of
//! `rbc-predict`, PNG/TIFF frames, results.h5 and checkpoints, fed to the library entry points the binaries call.
//!
//! Every case starts from a valid seed (the shipped examples, or files made from them) and applies
//! byte, token, line and structured mutations ([`mutate`], [`toml_mutate`], [`images`]); a case is
//! reproducible from (format, seed, case index) alone. Cases run in a child process
//! (`rbc-bench fuzz-worker`, [`worker`]) that catches panics with `catch_unwind` and reports
//! each outcome on a pipe; the parent ([`run_format`]) kills the child on a hang (no answer
//! within the timeout) and restarts it, and a child that dies (an abort in the HDF5 C library, a
//! stack overflow, a failed allocation) is reported as a crash. The input of every panic, hang
//! and crash is kept with `--save DIR` (and of a case replayed with `--case`, whatever its
//! outcome: "reproducible from the index alone" holds only while the shipped examples the
//! mutations start from stay as they were, so a fixed finding's input is kept as a file).

pub mod images;
pub mod mutate;
pub mod targets;
pub mod toml_mutate;
pub mod worker;

use anyhow::{bail, Context, Result};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::process::ExitStatus;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

/// The input formats the fuzzer covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Recording,
    Scene,
    Sweep,
    Csv,
    Frames,
    Results,
    Checkpoint,
}

impl Format {
    pub const ALL: [Format; 7] = [Format::Recording, Format::Scene, Format::Sweep, Format::Csv, Format::Frames, Format::Results, Format::Checkpoint];

    pub fn name(self) -> &'static str {
        match self {
            Format::Recording => "recording",
            Format::Scene => "scene",
            Format::Sweep => "sweep",
            Format::Csv => "csv",
            Format::Frames => "frames",
            Format::Results => "results",
            Format::Checkpoint => "checkpoint",
        }
    }

    pub fn parse(s: &str) -> Option<Format> {
        Format::ALL.into_iter().find(|f| f.name() == s)
    }
}

/// Settings of a fuzzing run.
#[derive(Debug, Clone)]
pub struct Options {
    pub formats: Vec<Format>,
    /// Cases per format.
    pub cases: usize,
    pub seed: u64,
    /// A case without an answer after this long is a hang (the worker is killed and restarted).
    pub timeout: Duration,
    /// Run only this case index (reproduce a finding).
    pub only_case: Option<usize>,
    /// Keep the input of every panic, hang and crash here (`<format>-<case>/`).
    pub save: Option<PathBuf>,
    /// Distinct error lines printed per format.
    pub top_errors: usize,
}

/// How one case ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Accepted (parsed, validated and processed).
    Ok,
    /// Refused with an error; `named` is false when the message names no file of the case or spans several lines.
    Error { message: String, named: bool },
    Panic(String),
    Hang,
    /// A hang inside a watched libhdf5 call that the watchdog ended (`rbc_schema::hdf5_watch`): the
    /// commands print this line and exit 2 where the call would never return. Counted as a hang.
    HangCaught(String),
    /// The worker died (signal or abort); the last line it wrote to stderr.
    Crash(String),
    /// A crash during a read of a file that the HDF5 watchdog's signal handler turned into its one-line
    /// error and exit 2 (`rbc_schema::hdf5_watch`): what the commands print there. Counted as a crash.
    CrashCaught(String),
}

/// Tally of one format.
#[derive(Debug, Clone, Default)]
pub struct FormatReport {
    pub cases: usize,
    pub ok: usize,
    pub errors: usize,
    /// Errors that name no input file or are not one line.
    pub unnamed: usize,
    pub panics: usize,
    pub hangs: usize,
    /// Of the hangs, those the HDF5 watchdog ended with its one-line error.
    pub hangs_caught: usize,
    pub crashes: usize,
    /// Of the crashes, those the watchdog's signal handler ended with its one-line error.
    pub crashes_caught: usize,
    pub seconds: f64,
    /// Distinct error lines (paths of the case and digits folded) and their counts.
    pub error_lines: BTreeMap<String, usize>,
    /// Example of an unnamed error line, with its case.
    pub unnamed_examples: Vec<(usize, String)>,
    /// (case, what) of every panic, hang and crash.
    pub findings: Vec<(usize, String)>,
}

impl FormatReport {
    fn add(&mut self, case: usize, o: Outcome, work: &Path) {
        self.cases += 1;
        match o {
            Outcome::Ok => self.ok += 1,
            Outcome::Error { message, named } => {
                self.errors += 1;
                let line = fold(&message, work);
                if !named {
                    self.unnamed += 1;
                    if self.unnamed_examples.len() < 5 {
                        self.unnamed_examples.push((case, line.clone()));
                    }
                }
                *self.error_lines.entry(line).or_default() += 1;
            }
            Outcome::Panic(m) => {
                self.panics += 1;
                self.findings.push((case, format!("panic: {}", m.replace(&work.display().to_string(), ""))));
            }
            Outcome::Hang => {
                self.hangs += 1;
                self.findings.push((case, "hang (no answer within the timeout, outside any watched libhdf5 call)".into()));
            }
            Outcome::HangCaught(line) => {
                self.hangs += 1;
                self.hangs_caught += 1;
                self.findings.push((case, format!("hang in libhdf5, ended by the watchdog: {}", line.replace(&work.display().to_string(), ""))));
            }
            Outcome::Crash(m) => {
                self.crashes += 1;
                self.findings.push((case, format!("crash: {m}")));
            }
            Outcome::CrashCaught(line) => {
                self.crashes += 1;
                self.crashes_caught += 1;
                self.findings.push((case, format!("crash in a read, one line and exit 2: {}", line.replace(&work.display().to_string(), ""))));
            }
        }
    }

    /// Panics, hangs and crashes.
    pub fn failures(&self) -> usize {
        self.panics + self.hangs + self.crashes
    }
}

/// An error line with the case's paths removed and digit runs folded to `#`, truncated to 160 characters.
fn fold(message: &str, work: &Path) -> String {
    let m = message.replace(&format!("{}/", work.display()), "").replace(&work.display().to_string(), "");
    let mut out = String::new();
    let mut prev_digit = false;
    for c in m.chars() {
        if c.is_ascii_digit() {
            if !prev_digit {
                out.push('#');
            }
            prev_digit = true;
        } else {
            out.push(c);
            prev_digit = false;
        }
        if out.chars().count() >= 160 {
            out.push_str("...");
            break;
        }
    }
    out
}

/// Waiting for a child with a time limit (std has none).
trait WaitTimeout {
    /// The exit status when the child ends within `d`; otherwise it is killed and `None` returned.
    fn wait_timeout_or_kill(&mut self, d: Duration) -> Option<ExitStatus>;
}

impl WaitTimeout for Child {
    fn wait_timeout_or_kill(&mut self, d: Duration) -> Option<ExitStatus> {
        let t0 = Instant::now();
        while t0.elapsed() < d {
            if let Ok(Some(s)) = self.try_wait() {
                return Some(s);
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        let _ = self.kill();
        let _ = self.wait();
        None
    }
}

/// A running worker process and the lines of its stdout.
struct Worker {
    child: Child,
    stdin: ChildStdin,
    lines: Receiver<String>,
    stderr: PathBuf,
}

impl Worker {
    fn spawn(format: Format, seed: u64, work: &Path, timeout: Duration) -> Result<Worker> {
        let exe = std::env::current_exe().context("locating rbc-bench")?;
        std::fs::create_dir_all(work).with_context(|| format!("creating {}", work.display()))?;
        let stderr = work.join("worker-stderr.log");
        let err_file = std::fs::File::create(&stderr).with_context(|| format!("creating {}", stderr.display()))?;
        let mut child = Command::new(exe)
            .args(["fuzz-worker", format.name(), &seed.to_string(), &work.display().to_string()])
            // the HDF5 watchdog of the commands, at half the case timeout: a hang in a watched
            // libhdf5 call ends the worker with the watchdog's line (reported as a caught hang)
            .env(rbc_schema::hdf5_watch::LIMIT_ENV, format!("{}", timeout.as_secs_f64() / 2.0))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(err_file)
            .spawn()
            .context("starting the fuzz worker")?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = child.stdout.take().expect("piped stdout");
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            // byte lines: a library may print anything (not UTF-8) to stdout; only tagged lines count
            let mut reader = BufReader::new(stdout);
            let mut buf = Vec::new();
            while reader.read_until(b'\n', &mut buf).is_ok_and(|n| n > 0) {
                let line = String::from_utf8_lossy(&buf);
                if let Some(msg) = line.trim_end_matches(['\n', '\r']).strip_prefix(worker::TAG) {
                    if tx.send(msg.to_string()).is_err() {
                        break;
                    }
                }
                buf.clear();
            }
        });
        let w = Worker { child, stdin, lines, stderr };
        match w.lines.recv_timeout(Duration::from_secs(600)) {
            Ok(l) if l == "ready" => Ok(w),
            Ok(l) => bail!("fuzz worker for {}: {l}", format.name()),
            Err(_) => bail!("fuzz worker for {} did not start: {}", format.name(), last_line(&w.stderr)),
        }
    }

    fn stop(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn last_line(path: &Path) -> String {
    std::fs::read_to_string(path).ok().and_then(|t| t.lines().rev().find(|l| !l.trim().is_empty()).map(str::to_string)).unwrap_or_default()
}

/// Copy the case folder of the worker into `save/<format>-<case>/`.
fn save_case(save: &Path, format: Format, case: usize, work: &Path) -> Result<()> {
    let dst = save.join(format!("{}-{case}", format.name()));
    std::fs::create_dir_all(&dst).with_context(|| format!("creating {}", dst.display()))?;
    for e in std::fs::read_dir(work.join(worker::CASE_DIR)).with_context(|| format!("reading {}", work.display()))?.flatten() {
        if e.path().is_file() {
            std::fs::copy(e.path(), dst.join(e.file_name())).with_context(|| format!("copying {}", e.path().display()))?;
        }
    }
    Ok(())
}

/// Fuzz one format: `o.cases` cases (or the one `o.only_case`), in a worker process under `scratch`.
pub fn run_format(format: Format, o: &Options, scratch: &Path) -> Result<FormatReport> {
    let work = scratch.join(format.name());
    let started = Instant::now();
    let mut report = FormatReport::default();
    let mut worker = Some(Worker::spawn(format, o.seed, &work, o.timeout)?);
    let cases: Box<dyn Iterator<Item = usize>> = match o.only_case {
        Some(i) => Box::new(std::iter::once(i)),
        None => Box::new(0..o.cases),
    };
    for case in cases {
        let w = match worker.as_mut() {
            Some(w) => w,
            None => worker.insert(Worker::spawn(format, o.seed, &work, o.timeout)?),
        };
        let answer = writeln!(w.stdin, "{case}").and_then(|_| w.stdin.flush()).map_err(|_| RecvTimeoutError::Disconnected).and_then(|_| w.lines.recv_timeout(o.timeout));
        let outcome = match answer {
            Ok(line) => worker::parse_answer(&line).with_context(|| format!("fuzz worker answered `{line}`"))?,
            Err(RecvTimeoutError::Timeout) => Outcome::Hang,
            Err(RecvTimeoutError::Disconnected) => {
                let mut w = worker.take().expect("worker present");
                // the pipe closed: the worker died (or closed its stdout: then end it)
                let status = match w.child.wait_timeout_or_kill(Duration::from_secs(5)) {
                    Some(s) => s.to_string(),
                    None => "closed its output and was killed".into(),
                };
                let last = last_line(&w.stderr);
                if last.contains(rbc_schema::hdf5_watch::MESSAGE) {
                    Outcome::HangCaught(last)
                } else if last.contains(rbc_schema::hdf5_watch::CRASH_MESSAGE) {
                    Outcome::CrashCaught(last)
                } else {
                    Outcome::Crash(format!("worker {status}: {last}"))
                }
            }
        };
        let failed = matches!(outcome, Outcome::Panic(_) | Outcome::Hang | Outcome::HangCaught(_) | Outcome::Crash(_) | Outcome::CrashCaught(_));
        if matches!(outcome, Outcome::Hang) {
            if let Some(w) = worker.take() {
                w.stop();
            }
        }
        // a replayed case (`--case`) is kept whatever its outcome: the input of a fixed finding
        if failed || o.only_case.is_some() {
            if let Some(save) = &o.save {
                save_case(save, format, case, &work)?;
            }
        }
        report.add(case, outcome, &work.join(worker::CASE_DIR));
    }
    if let Some(w) = worker.take() {
        w.stop();
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Print the table of all formats, the distinct error lines of each and every finding.
pub fn print_reports(o: &Options, reports: &[(Format, FormatReport)]) {
    println!("seed {}, timeout {} ms", o.seed, o.timeout.as_millis());
    println!();
    println!("| format | cases | ok | error | unnamed error | panic | hang | crash | cases/s |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (f, r) in reports {
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {:.0} |",
            f.name(),
            r.cases,
            r.ok,
            r.errors,
            r.unnamed,
            r.panics,
            r.hangs,
            r.crashes,
            r.cases as f64 / r.seconds.max(1e-9)
        );
    }
    for (f, r) in reports.iter().filter(|(_, r)| r.hangs > 0) {
        println!();
        println!(
            "{}: {} of {} hangs were in a watched libhdf5 call and ended by the watchdog (here after half the timeout; the commands end such a call after RBC_HDF5_TIMEOUT_S, default {} s, with a one-line error and exit 2); the others would hang a command",
            f.name(),
            r.hangs_caught,
            r.hangs,
            rbc_schema::hdf5_watch::DEFAULT_LIMIT_S
        );
    }
    for (f, r) in reports.iter().filter(|(_, r)| r.crashes > 0) {
        println!();
        println!(
            "{}: {} of {} crashes were in a marked read of a file and ended with the watchdog's one-line error naming it and exit 2, as in the commands; the others would end a command with a bare signal",
            f.name(),
            r.crashes_caught,
            r.crashes
        );
    }
    for (f, r) in reports {
        println!();
        println!("{}: {} distinct error lines (paths of the case removed, digits as #); the most frequent:", f.name(), r.error_lines.len());
        let mut lines: Vec<(&String, &usize)> = r.error_lines.iter().collect();
        lines.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
        for (line, n) in lines.into_iter().take(o.top_errors) {
            println!("  {n:>7}  {line}");
        }
        for (case, line) in &r.unnamed_examples {
            println!("  unnamed (case {case}): {line}");
        }
        for (case, what) in r.findings.iter().take(20) {
            println!("  FINDING case {case}: {what}   (rbc-bench fuzz --format {} --seed {} --case {case} --save DIR)", f.name(), o.seed);
        }
    }
}

/// `rbc-bench fuzz [--format F[,G]] [--cases N] [--seed S] [--timeout-ms T] [--case I] [--save DIR] [--top K]`.
pub fn run(args: &[String]) -> Result<()> {
    let mut o = Options { formats: Format::ALL.to_vec(), cases: 1000, seed: 1, timeout: Duration::from_millis(10_000), only_case: None, save: None, top_errors: 10 };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--format" => {
                o.formats = value()?
                    .split(',')
                    .map(|s| Format::parse(s).with_context(|| format!("--format {s}: expected one of {}", Format::ALL.map(Format::name).join(", "))))
                    .collect::<Result<_>>()?
            }
            "--cases" => o.cases = value()?.parse::<f64>().ok().filter(|n| *n >= 1.0 && n.fract() == 0.0).context("--cases: a whole number >= 1 (1e5 works)")? as usize,
            "--seed" => o.seed = value()?.parse().context("--seed: an integer")?,
            "--timeout-ms" => o.timeout = Duration::from_millis(value()?.parse::<u64>().ok().filter(|t| *t > 0).context("--timeout-ms: milliseconds > 0")?),
            "--case" => o.only_case = Some(value()?.parse().context("--case: a case index")?),
            "--save" => o.save = Some(PathBuf::from(value()?)),
            "--top" => o.top_errors = value()?.parse().context("--top: a count")?,
            other => bail!("unknown option {other} (rbc-bench fuzz [--format F] [--cases N] [--seed S] [--timeout-ms T] [--case I] [--save DIR] [--top K])"),
        }
    }
    let scratch = std::env::temp_dir().join(format!("rbc-fuzz-{}", std::process::id()));
    let mut reports = Vec::new();
    let result = (|| -> Result<()> {
        for &f in &o.formats {
            let r = run_format(f, &o, &scratch)?;
            eprintln!("rbc-bench fuzz: {}: {} cases, {} panics, {} hangs, {} crashes in {:.1} s", f.name(), r.cases, r.panics, r.hangs, r.crashes, r.seconds);
            reports.push((f, r));
        }
        Ok(())
    })();
    let _ = std::fs::remove_dir_all(&scratch);
    result?;
    print_reports(&o, &reports);
    let failures: usize = reports.iter().map(|(_, r)| r.failures()).sum();
    if failures > 0 {
        bail!("{failures} panics, hangs or crashes");
    }
    Ok(())
}
