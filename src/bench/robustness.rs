//! `rbc-bench robustness`: `rbc-analyze`'s accuracy per imaging condition against the synthesiser's truth (a Markdown table).
//!
//! Usage: `rbc-bench robustness [--seeds N] [--random N] [--only TEXT] [--renderer synth|wave|both]`
//! (default 6 recordings of 3 cells per condition of `rbc_analysis::simulated::synth::condition_grid`;
//! `--random N` adds N recordings each under its own `random_conditions`, as one row; `--only`
//! keeps the conditions whose name contains TEXT; `--renderer` draws them with the synthesiser
//! (default), the wave-optics renderer (`rbc_analysis::simulated::wave`) or both, one row each).
//!
//! Each row: croissant/slipper correct over tracked croissants and slippers (`other` counts as
//! wrong), how many of them were called `other`, median centroid and |y| error per detection,
//! recall (cells seen whole in >= 3 frames that one pure track covers in >= 80 % of them), false
//! tracks (mostly near no cell) and mixed tracks ([`rbc_analysis::simulated::robustness`]).

use anyhow::{bail, Context};
use rbc_analysis::simulated::robustness::{run_condition_with, Renderer, Score};
use rbc_analysis::simulated::synth::{condition_grid, random_conditions};

struct Options {
    seeds: u64,
    random: u64,
    only: Option<String>,
    renderers: Vec<Renderer>,
}

fn parse(args: &[String]) -> anyhow::Result<Options> {
    let mut o = Options { seeds: 6, random: 0, only: None, renderers: vec![Renderer::Synth] };
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a}: missing value"));
        match a.as_str() {
            "--seeds" => o.seeds = val()?.parse().context("--seeds")?,
            "--random" => o.random = val()?.parse().context("--random")?,
            "--only" => o.only = Some(val()?.clone()),
            "--renderer" => {
                o.renderers = match val()?.as_str() {
                    "synth" => vec![Renderer::Synth],
                    "wave" => vec![Renderer::Wave],
                    "both" => vec![Renderer::Synth, Renderer::Wave],
                    other => bail!("--renderer {other}: expected synth, wave or both"),
                }
            }
            other => bail!("unknown option {other} (options: --seeds N --random N --only TEXT --renderer synth|wave|both)"),
        }
    }
    if o.seeds == 0 && o.random == 0 {
        bail!("--seeds and --random are both 0: nothing to measure");
    }
    Ok(o)
}

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let o = parse(args)?;
    let tmp = std::env::temp_dir().join(format!("rbc-bench-robustness-{}", std::process::id()));
    let result = table(&o, &tmp);
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

fn table(o: &Options, tmp: &std::path::Path) -> anyhow::Result<()> {
    println!("rbc-bench robustness: {} recordings of 3 cells per condition and renderer", o.seeds);
    println!("{}", Score::header());
    let mut all: Vec<Score> = o.renderers.iter().map(|_| Score::default()).collect();
    let name_of = |name: &str, r: Renderer| if o.renderers.len() > 1 { format!("{name} ({})", r.as_str()) } else { name.to_string() };
    let grid = condition_grid();
    for (k, (name, c)) in grid.iter().enumerate() {
        if o.only.as_ref().is_some_and(|t| !name.contains(t.as_str())) || o.seeds == 0 {
            continue;
        }
        for (r, total) in o.renderers.iter().zip(all.iter_mut()) {
            let s = run_condition_with(tmp, &format!("c{k:02}"), c, 1..1 + o.seeds, *r)?;
            println!("{}", s.row(&name_of(name, *r)));
            total.merge(s);
        }
    }
    if o.random > 0 {
        for (r, total) in o.renderers.iter().zip(all.iter_mut()) {
            let mut sum = Score::default();
            for seed in 0..o.random {
                sum.merge(run_condition_with(tmp, &format!("random{seed:03}"), &random_conditions(seed), seed..seed + 1, *r)?);
            }
            println!("{}", sum.row(&name_of(&format!("random conditions ({} recordings)", o.random), *r)));
            total.merge(sum);
        }
    }
    for (r, total) in o.renderers.iter().zip(all) {
        println!("{}", total.row(&name_of("all", *r)));
    }
    Ok(())
}
