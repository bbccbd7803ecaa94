//! A sweep file read and validated into a [`Sweep`]: its axes (lists or ranges), counts, start
//! shapes, grids, overrides and settings, every error one line naming the file and the field.

use super::raw::{RawAxis, RawSweep};
use super::{field, ClassifySettings, Grid, SlurmSettings, SteadySettings, Sweep, MAX_RUNS};
use crate::error::{Result, SchemaError};
use crate::recording::positive;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn axis(p: &Path, name: &str, raw: RawAxis) -> Result<Vec<f64>> {
    // range values are rounded to 6 significant digits so that run ids stay readable
    // (`u10.4`, not `u10.399999999999995`)
    let round6 = |x: f64| {
        if x == 0.0 {
            0.0
        } else {
            format!("{x:.5e}").parse::<f64>().unwrap_or(x)
        }
    };
    let v = match raw {
        RawAxis::List(v) => v,
        RawAxis::Range {
            from,
            to,
            n,
            spacing,
        } => {
            if !(from.is_finite() && to.is_finite()) {
                return Err(field(p, name, "from and to must be finite numbers"));
            }
            if !(1..=10_000).contains(&n) {
                return Err(field(
                    p,
                    &format!("{name}.n"),
                    format!("must be an integer in 1..=10000, got {n}"),
                ));
            }
            let n = n as usize;
            let t = |k: usize| {
                if n == 1 {
                    0.0
                } else {
                    k as f64 / (n - 1) as f64
                }
            };
            match spacing.as_deref().unwrap_or("linear") {
                "linear" => (0..n).map(|k| round6(from + (to - from) * t(k))).collect(),
                "log" => {
                    if !(from > 0.0 && to > 0.0) {
                        return Err(field(
                            p,
                            &format!("{name}.spacing"),
                            "log spacing needs from > 0 and to > 0",
                        ));
                    }
                    (0..n)
                        .map(|k| round6((from.ln() + (to.ln() - from.ln()) * t(k)).exp()))
                        .collect()
                }
                other => {
                    return Err(field(
                        p,
                        &format!("{name}.spacing"),
                        format!("unknown spacing \"{other}\" (expected linear or log)"),
                    ))
                }
            }
        }
    };
    if v.is_empty() {
        return Err(field(p, name, "must not be empty"));
    }
    let mut sorted = v.clone();
    sorted.sort_by(f64::total_cmp);
    if sorted.windows(2).any(|w| w[0] == w[1]) {
        return Err(field(p, name, "contains a value twice"));
    }
    Ok(v)
}

/// A velocity axis (mm/s): every value positive.
fn velocities(p: &Path, name: &str, raw: RawAxis) -> Result<Vec<f64>> {
    let v = axis(p, name, raw)?;
    for x in &v {
        positive(p, name, *x)?;
    }
    Ok(v)
}

/// An offset axis (um): every value finite and >= 0.
fn offsets(p: &Path, name: &str, raw: RawAxis) -> Result<Vec<f64>> {
    let v = axis(p, name, raw)?;
    if let Some(r) = v.iter().find(|r| !(r.is_finite() && **r >= 0.0)) {
        return Err(field(p, name, format!("offsets must be finite and >= 0, got {r}")));
    }
    Ok(v)
}

fn count(p: &Path, f: &str, v: Option<i64>, default: usize, min: i64) -> Result<usize> {
    match v {
        None => Ok(default),
        Some(x) if x >= min => Ok(x as usize),
        Some(x) => Err(field(p, f, format!("must be an integer >= {min}, got {x}"))),
    }
}

fn opt_positive(p: &Path, f: &str, v: Option<f64>) -> Result<Option<f64>> {
    if let Some(x) = v {
        positive(p, f, x)?;
    }
    Ok(v)
}

/// A Slurm time limit in seconds: `MM`, `MM:SS`, `HH:MM:SS`, `D-HH`, `D-HH:MM`, `D-HH:MM:SS`
/// (sbatch `--time`); `Some(None)` for `UNLIMITED` / `INFINITE`, `None` when malformed.
pub fn slurm_time_s(text: &str) -> Option<Option<u64>> {
    if text.eq_ignore_ascii_case("unlimited") || text.eq_ignore_ascii_case("infinite") {
        return Some(None);
    }
    let num = |s: &str| -> Option<u64> {
        (!s.is_empty() && s.len() <= 9 && s.bytes().all(|b| b.is_ascii_digit())).then(|| s.parse().ok()).flatten()
    };
    let (days, rest) = match text.split_once('-') {
        Some((d, r)) => (Some(num(d)?), r),
        None => (None, text),
    };
    let parts = rest.split(':').map(num).collect::<Option<Vec<u64>>>()?;
    let s = match (days, parts.as_slice()) {
        (None, [m]) => m * 60,
        (None, [m, s]) => m * 60 + s,
        (None, [h, m, s]) => h * 3600 + m * 60 + s,
        (Some(d), [h]) => d * 86400 + h * 3600,
        (Some(d), [h, m]) => d * 86400 + h * 3600 + m * 60,
        (Some(d), [h, m, s]) => d * 86400 + h * 3600 + m * 60 + s,
        _ => return None,
    };
    Some(Some(s))
}

/// Resolve `path` against `dir` when relative.
fn resolve(dir: &Path, path: &Path) -> PathBuf {
    if path.is_relative() {
        dir.join(path)
    } else {
        path.to_path_buf()
    }
}

/// Flatten nested override tables into dotted keys (`[overrides] time = { end_s = 1 }` is `time.end_s`).
fn flatten(prefix: &str, t: &toml::Table, out: &mut Vec<(String, toml::Value)>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(inner) => flatten(&key, inner, out),
            other => out.push((key, other.clone())),
        }
    }
}

impl Sweep {
    /// Read and validate a sweep file (and read its base scene).
    pub fn read(path: &Path) -> Result<Sweep> {
        let text = std::fs::read_to_string(path).map_err(|e| SchemaError::io(path, e))?;
        Self::parse(&text, path)
    }

    /// Parse and validate sweep text; `path` names the file and anchors relative paths.
    pub fn parse(text: &str, path: &Path) -> Result<Sweep> {
        let p = path;
        let raw: RawSweep = toml::from_str(text).map_err(|e| {
            let mut message = e.message().replace('\n', " ").trim().to_string();
            if let Some(span) = e.span() {
                message = format!(
                    "{message} (line {})",
                    crate::recording::line_at(text, span.start)
                );
            }
            SchemaError::Toml {
                path: p.into(),
                message,
            }
        })?;
        let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
        let base_scene = resolve(&dir, &raw.base_scene);
        let base_text = std::fs::read_to_string(&base_scene).map_err(|e| {
            field(
                p,
                "base_scene",
                format!("cannot read {}: {e}", base_scene.display()),
            )
        })?;
        base_text.parse::<toml::Table>().map_err(|e| {
            field(
                p,
                "base_scene",
                format!(
                    "{} is not valid TOML: {}",
                    base_scene.display(),
                    e.message().replace('\n', " ")
                ),
            )
        })?;

        let velocities_mm_s = velocities(p, "mean_velocity_mm_s", raw.mean_velocity_mm_s)?;
        let r_init_um = offsets(p, "r_init_um", raw.r_init_um)?;
        if raw.start_shapes.is_empty() {
            return Err(field(
                p,
                "start_shapes",
                "must name at least one start shape",
            ));
        }
        // The [cell] table of start shape `s`, named by the field `f` that uses it.
        let cell_of = |s: &str, f: &str| -> Result<toml::Table> {
            if s.is_empty() || !s.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
                return Err(field(p, f, format!("\"{s}\" must be a non-empty name of letters, digits and '-'")));
            }
            let mut cell = match raw.start_shape.get(s) {
                Some(t) => t.clone(),
                None if s == "discocyte" => {
                    let mut t = toml::Table::new();
                    t.insert("shape".into(), "discocyte".into());
                    t.insert("axis".into(), toml::Value::Array(vec![1.0.into(), 0.0.into(), 0.0.into()]));
                    t
                }
                None if f.starts_with("also") => return Err(field(p, f, format!("\"{s}\" has no [start_shape.{s}] table (its [cell] table, e.g. shape = \"mesh-from-results\", results, run)"))),
                None => return Err(field(p, &format!("start_shape.{s}"), "missing: the [cell] table of this start shape (e.g. shape = \"mesh-from-results\", results, run)")),
            };
            for k in ["level", "position_um"] {
                if cell.contains_key(k) {
                    return Err(field(p, &format!("start_shape.{s}.{k}"), "not allowed (taken from the base scene / the sweep grid)"));
                }
            }
            if let Some(toml::Value::String(r)) = cell.get("results") {
                // absolute: the run's scene resolves a relative path against the base scene's
                // folder again (a sweep given as a relative path would double its folder)
                let resolved = resolve(&dir, Path::new(r));
                let abs = std::path::absolute(&resolved).unwrap_or(resolved);
                cell.insert("results".into(), toml::Value::String(abs.to_string_lossy().into_owned()));
            }
            Ok(cell)
        };
        let mut cells = BTreeMap::new();
        for (i, s) in raw.start_shapes.iter().enumerate() {
            let f = format!("start_shapes[{i}]");
            if cells.contains_key(s) {
                return Err(field(p, &f, format!("\"{s}\" is listed twice")));
            }
            cells.insert(s.clone(), cell_of(s, &f)?);
        }
        let velocity_key = raw
            .velocity_key
            .unwrap_or_else(|| "walls.mean_velocity_um_s".into());
        // scene overrides, `[overrides]` and an [[also]] grid's: never the fields the grid sets
        let overrides_of = |at: &str, table: &toml::Table| -> Result<Vec<(String, toml::Value)>> {
            let mut list = Vec::new();
            flatten("", table, &mut list);
            for (k, _) in &list {
                if k == "cell.position_um" || k == "cell.level" || *k == velocity_key {
                    return Err(field(p, &format!("{at}.{k}"), "is set by the sweep grid"));
                }
            }
            Ok(list)
        };
        // an [[also]] grid may use a start shape of its own (a [start_shape.X] table the main grid
        // does not list): a study adds start shapes without adding runs to its earlier grids
        let mut also = Vec::with_capacity(raw.also.len());
        for (i, g) in raw.also.into_iter().enumerate() {
            let f = |k: &str| format!("also[{i}].{k}");
            let start_shapes = g.start_shapes.unwrap_or_else(|| raw.start_shapes.clone());
            if start_shapes.is_empty() {
                return Err(field(p, &f("start_shapes"), "must name at least one start shape"));
            }
            for (j, s) in start_shapes.iter().enumerate() {
                if start_shapes[..j].contains(s) {
                    return Err(field(p, &f("start_shapes"), format!("\"{s}\" is listed twice")));
                }
                if !cells.contains_key(s) {
                    cells.insert(s.clone(), cell_of(s, &f("start_shapes"))?);
                }
            }
            also.push(Grid {
                velocities_mm_s: velocities(p, &f("mean_velocity_mm_s"), g.mean_velocity_mm_s)?,
                r_init_um: offsets(p, &f("r_init_um"), g.r_init_um)?,
                start_shapes,
                overrides: overrides_of(&f("overrides"), &g.overrides)?,
            });
        }
        let more: usize = also.iter().map(Grid::len).sum();
        let runs = raw.start_shapes.len() * velocities_mm_s.len() * r_init_um.len() + more;
        if runs > MAX_RUNS {
            let axis = if r_init_um.len() >= velocities_mm_s.len() { "r_init_um" } else { "mean_velocity_mm_s" };
            return Err(field(
                p,
                axis,
                format!(
                    "the grid has {} x {} x {}{} = {runs} runs (start_shapes x mean_velocity_mm_s x r_init_um{}), more than the {MAX_RUNS} a sweep may hold",
                    raw.start_shapes.len(),
                    velocities_mm_s.len(),
                    r_init_um.len(),
                    if more > 0 { format!(" + {more}") } else { String::new() },
                    if more > 0 { " + the [[also]] grids" } else { "" },
                ),
            ));
        }
        if let Some(k) = raw.start_shape.keys().find(|k| !cells.contains_key(*k)) {
            return Err(field(p, &format!("start_shape.{k}"), "is used by no grid (start_shapes, or an [[also]] grid's start_shapes)"));
        }
        let overrides = overrides_of("overrides", &raw.overrides)?;
        let threads_per_run = count(p, "threads_per_run", raw.threads_per_run, 1, 1)?;
        let snapshot_every = count(p, "snapshot_every", raw.snapshot_every, 50, 1)?;
        let checkpoint_interval_s = opt_positive(p, "checkpoint_interval_s", raw.checkpoint_interval_s)?.unwrap_or(60.0);

        let steady = match raw.steady {
            None => SteadySettings::default(),
            Some(s) => SteadySettings {
                window_s: opt_positive(p, "steady.window_s", s.window_s)?,
                max_time_s: opt_positive(p, "steady.max_time_s", s.max_time_s)?,
                position_tol_um: opt_positive(p, "steady.position_tol_um", s.position_tol_um)?,
                asphericity_tol: opt_positive(p, "steady.asphericity_tol", s.asphericity_tol)?,
                min_cycles: s
                    .min_cycles
                    .map(|c| count(p, "steady.min_cycles", Some(c), 0, 1))
                    .transpose()?,
            },
        };
        if let (Some(w), Some(m)) = (steady.window_s, steady.max_time_s) {
            if w > m {
                return Err(field(
                    p,
                    "steady.window_s",
                    format!("must not exceed steady.max_time_s = {m}"),
                ));
            }
        }
        let classify = match raw.classify {
            None => ClassifySettings::default(),
            Some(c) => ClassifySettings {
                centred_um: opt_positive(p, "classify.centred_um", c.centred_um)?,
                symmetric_rel: opt_positive(p, "classify.symmetric_rel", c.symmetric_rel)?,
                rigid_rel: opt_positive(p, "classify.rigid_rel", c.rigid_rel)?,
                frames: c
                    .frames
                    .map(|f| count(p, "classify.frames", Some(f), 0, 3))
                    .transpose()?,
                frame_interval_s: opt_positive(p, "classify.frame_interval_s", c.frame_interval_s)?,
                frame_travel_um: opt_positive(p, "classify.frame_travel_um", c.frame_travel_um)?,
            },
        };
        if classify.frame_interval_s.is_some() && classify.frame_travel_um.is_some() {
            return Err(field(p, "classify.frame_travel_um", "give frame_interval_s or frame_travel_um, not both"));
        }
        let slurm = match raw.slurm {
            None => SlurmSettings::default(),
            Some(s) => {
                for (i, line) in s.extra.iter().enumerate() {
                    if !line.starts_with("#SBATCH ") || line.contains('\n') {
                        return Err(field(
                            p,
                            &format!("slurm.extra[{i}]"),
                            "each line must start with \"#SBATCH \" and be a single line",
                        ));
                    }
                }
                let limit_s = match &s.time {
                    Some(t) => Some(slurm_time_s(t).ok_or_else(|| {
                        field(p, "slurm.time", format!("\"{t}\" is not a Slurm time (MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS or UNLIMITED)"))
                    })?),
                    None => None,
                };
                let stop_before_limit_s = s
                    .stop_before_limit_s
                    .map(|c| count(p, "slurm.stop_before_limit_s", Some(c), 0, 1).map(|c| c as u64))
                    .transpose()?;
                if let (Some(m), Some(Some(l))) = (stop_before_limit_s, limit_s) {
                    if 2 * m >= l {
                        return Err(field(p, "slurm.stop_before_limit_s", format!("{m} s must be less than half of slurm.time ({l} s): each attempt of a task must get somewhere before it stops")));
                    }
                }
                for (f, v) in [
                    ("slurm.partition", &s.partition),
                    ("slurm.time", &s.time),
                    ("slurm.mem", &s.mem),
                    ("slurm.account", &s.account),
                ] {
                    if let Some(v) = v {
                        if v.is_empty()
                            || v.chars()
                                .any(|c| c.is_whitespace() || c == '\'' || c == '"')
                        {
                            return Err(field(
                                p,
                                f,
                                format!("\"{v}\" must be non-empty without spaces or quotes"),
                            ));
                        }
                    }
                }
                SlurmSettings {
                    partition: s.partition,
                    time: s.time,
                    mem: s.mem,
                    account: s.account,
                    max_concurrent: s
                        .max_concurrent
                        .map(|c| count(p, "slurm.max_concurrent", Some(c), 0, 1))
                        .transpose()?,
                    stop_before_limit_s,
                    extra: s.extra,
                }
            }
        };
        let sweep = Sweep {
            path: p.to_path_buf(),
            base_scene,
            base_text,
            velocities_mm_s,
            r_init_um,
            start_shapes: raw.start_shapes,
            also,
            cells,
            velocity_key,
            overrides,
            threads_per_run,
            snapshot_every,
            checkpoint_interval_s,
            steady,
            classify,
            slurm,
        };
        sweep.refuse_repeated_runs()?;
        Ok(sweep)
    }

    /// A run id may occur once: an `[[also]]` grid must not repeat a run of an earlier grid
    /// (or itself), or two runs would write the same group of the results file.
    fn refuse_repeated_runs(&self) -> Result<()> {
        let mut seen = std::collections::HashSet::new();
        for (g, grid) in self.grids().enumerate() {
            for shape in &grid.start_shapes {
                for &u in &grid.velocities_mm_s {
                    for &r in &grid.r_init_um {
                        let id = Self::run_id(shape, u, r);
                        if !seen.insert(id.clone()) {
                            let f = if g == 0 { "start_shapes".to_string() } else { format!("also[{}]", g - 1) };
                            return Err(field(&self.path, &f, format!("run {id} occurs twice")));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
