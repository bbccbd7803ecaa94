//! The fuzzer's child process (`rbc-bench fuzz-worker FORMAT SEED WORKDIR`): reads case indices on stdin,
//! writes each case's input into `WORKDIR/case/`, runs it under `catch_unwind` and answers one tagged line per case.
//!
//! Protocol (stdout lines starting with [`TAG`]; other output of the library is ignored):
//! `ready` once the seeds are prepared, then per case `ok`, `err<TAB>named<TAB>message` or
//! `panic<TAB>message` (newlines replaced by ` | `).

use super::targets::{self, Target};
use super::{Format, Outcome};
use anyhow::{bail, Context, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::io::{BufRead, Write};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Prefix of the worker's protocol lines.
pub const TAG: &str = "@@rbc-fuzz ";
/// Sub-folder of the work folder that holds the current case's files.
pub const CASE_DIR: &str = "case";

static LAST_PANIC: Mutex<String> = Mutex::new(String::new());

/// The random generator of case `case` of `format` under `seed`: independent streams, reproducible alone.
pub fn case_rng(format: Format, seed: u64, case: usize) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (Format::ALL.iter().position(|f| *f == format).unwrap_or(0) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    rng.set_stream(case as u64);
    rng
}

fn one_line(s: &str) -> String {
    s.trim().replace('\t', " ").replace('\n', " | ")
}

/// True when `message` is one line and names a file or folder of the case (its path, or a file name in it).
fn names_the_input(message: &str, case_dir: &Path) -> bool {
    if message.trim().contains('\n') {
        return false;
    }
    if message.contains(&case_dir.display().to_string()) {
        return true;
    }
    std::fs::read_dir(case_dir).map(|d| d.flatten().any(|e| message.contains(&*e.file_name().to_string_lossy()))).unwrap_or(false)
}

/// Run one case: write its input, call the target, classify the outcome.
pub fn run_case(target: &dyn Target, format: Format, seed: u64, case: usize, case_dir: &Path) -> Outcome {
    let _ = std::fs::remove_dir_all(case_dir);
    if let Err(e) = std::fs::create_dir_all(case_dir) {
        return Outcome::Crash(format!("cannot create {}: {e}", case_dir.display()));
    }
    let mut rng = case_rng(format, seed, case);
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| {
        target.write_case(&mut rng, case_dir)?;
        target.exercise(case_dir)
    }));
    match result {
        Ok(Ok(())) => Outcome::Ok,
        Ok(Err(message)) => {
            let named = names_the_input(&message, case_dir);
            Outcome::Error { message, named }
        }
        Err(_) => Outcome::Panic(LAST_PANIC.lock().map(|m| m.clone()).unwrap_or_default()),
    }
}

/// Parse one answer line of the worker (without the tag).
pub fn parse_answer(line: &str) -> Result<Outcome> {
    let mut parts = line.splitn(3, '\t');
    Ok(match (parts.next(), parts.next(), parts.next()) {
        (Some("ok"), None, None) => Outcome::Ok,
        (Some("err"), Some(named), Some(m)) => Outcome::Error { message: m.to_string(), named: named == "named" },
        (Some("panic"), Some(m), None) => Outcome::Panic(m.to_string()),
        _ => bail!("malformed answer"),
    })
}

fn answer(o: &Outcome) -> String {
    match o {
        Outcome::Ok => "ok".into(),
        Outcome::Error { message, named } => format!("err\t{}\t{}", if *named { "named" } else { "unnamed" }, one_line(message)),
        Outcome::Panic(m) => format!("panic\t{}", one_line(m)),
        Outcome::Hang | Outcome::HangCaught(_) => "panic\thang reported by the worker".into(),
        Outcome::Crash(m) | Outcome::CrashCaught(m) => format!("panic\tcrash: {}", one_line(m)),
    }
}

/// `rbc-bench fuzz-worker FORMAT SEED WORKDIR`.
pub fn main(args: &[String]) -> Result<()> {
    let [format, seed, work] = args else { bail!("usage: rbc-bench fuzz-worker FORMAT SEED WORKDIR") };
    let format = Format::parse(format).with_context(|| format!("unknown format {format}"))?;
    let seed: u64 = seed.parse().context("SEED")?;
    let work = PathBuf::from(work);
    std::panic::set_hook(Box::new(|info| {
        if let Ok(mut m) = LAST_PANIC.lock() {
            *m = one_line(&info.to_string());
        }
    }));
    // the commands' HDF5 watchdog (the parent sets its limit below the case timeout)
    rbc_schema::hdf5_watch::enable_from_env("rbc-bench fuzz-worker");
    let target = targets::prepare(format, &work.join("seeds"))?;
    let case_dir = work.join(CASE_DIR);
    let mut out = std::io::stdout();
    writeln!(out, "{TAG}ready")?;
    out.flush()?;
    for line in std::io::stdin().lock().lines() {
        let case: usize = line?.trim().parse().context("case index")?;
        let o = run_case(target.as_ref(), format, seed, case, &case_dir);
        writeln!(out, "{TAG}{}", answer(&o))?;
        out.flush()?;
    }
    Ok(())
}
