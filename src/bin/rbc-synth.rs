//! `rbc-synth`: render synthetic bright-field recordings (frames + recording.toml + truth.csv) from a spec, at random, or the shipped examples.
//!
//! ```text
//! rbc-synth SPEC.toml --out DIR [--seed N]
//! rbc-synth --random --out DIR [--seed N] [--um-per-px 0.2] [--noise 0.01] [--velocity 1.0]
//!           [--vary] [--defocus UM] [--na NA] [--exposure-us US] [--gradient G] [--flicker F] [--bits 8|16]
//!           [--wall-brightness B] [--debris N] [--spacing UM] [--renderer synth|wave]
//! rbc-synth --examples examples/frames
//! rbc-synth --from-results results.h5 --run RUN_ID --out DIR [--snapshot K] [--um-per-px 0.2] [--noise 0.01]
//!           [--velocity MM_S] [--focal-z UM] [--dof-sigma 0.5] [--seed N]
//! rbc-synth --closed-loop results.h5 --out DIR [--um-per-px 0.2] [--noise 0.01] [--dof-sigma 0.5] [--seed N]
//!           [--renderer wave [--defocus UM] [--na NA]]
//! ```
//!
//! With any imaging condition (`--defocus` ... `--spacing`) or `--vary`, `--random` renders three
//! cells under those conditions (`rbc_analysis::simulated::synth::condition_spec`: the bright-field
//! edge of a cell `--defocus` um from focus through an objective of `--na`, below focus the rim
//! bright); `--vary` draws every condition not given from the ranges a lab meets
//! (`random_conditions(--seed)`), the others keep the nominal values of `Conditions::default`.
//! `--renderer wave` draws the same recording with the wave-optics renderer
//! (`rbc_analysis::simulated::wave`: the cells as thin phase-and-amplitude objects imaged through
//! the objective's pupil, which shares no image formation with the synthesiser's edge profiles);
//! a SPEC.toml selects it with a `[wave]` table.
//!
//! `--from-results` renders a simulated cell (snapshot `K`, default the last, of run
//! `RUN_ID`) in bright field with `rbc_analysis::simulated::render3d` and moves it along +x at the
//! run's mean velocity (or `--velocity`); `truth.csv` carries the solver's label.
//!
//! `--closed-loop` does this for every finished run of the file (its last snapshot, the
//! run's label; recordings in `DIR/<run_id>/`), analyses each recording like `rbc-analyze`,
//! writes `DIR/closed_loop.csv` (solver, pipeline and classifier-alone labels with the
//! shape measures, [`rbc_analysis::simulated::closedloop`]) and prints the agreement tables;
//! with `--renderer wave` the cells are drawn by the wave-optics renderer
//! (`rbc_analysis::simulated::wave::write_recording_mesh`: the mesh's thickness as a thin object,
//! `--defocus` default +1 um, `--na` default 0.8) instead of `render3d`.

use anyhow::bail;
use clap::Parser;
use rbc_analysis::simulated::synth;
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(name = "rbc-synth", about = "Render synthetic bright-field recordings of red blood cells with ground truth")]
struct Args {
    /// Spec file (TOML, see `rbc_analysis::simulated::synth::SynthSpec`).
    spec: Option<PathBuf>,
    /// Output recording folder (must not hold frames yet).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Noise seed (and, with --random, the seed of the spec).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Render a random plausible recording instead of a spec file.
    #[arg(long)]
    random: bool,
    /// Pixel size in the object plane, um [default: 0.2].
    #[arg(long)]
    um_per_px: Option<f64>,
    /// Read noise, fraction of full scale [default: 0.01].
    #[arg(long)]
    noise: Option<f64>,
    /// Cell velocity, mm/s (default 1 with --random; the run's mean velocity with --from-results).
    #[arg(long)]
    velocity: Option<f64>,
    /// (Re)generate the shipped example recordings into this folder.
    #[arg(long, value_name = "DIR")]
    examples: Option<PathBuf>,
    /// Render a simulated cell from this results.h5 (with --run).
    #[arg(long, value_name = "RESULTS_H5")]
    from_results: Option<PathBuf>,
    /// Run id inside the results file.
    #[arg(long, value_name = "RUN_ID")]
    run: Option<String>,
    /// Snapshot index of the run (default: the last).
    #[arg(long)]
    snapshot: Option<usize>,
    /// Focal plane height, um (default: the cell's volume centroid).
    #[arg(long)]
    focal_z: Option<f64>,
    /// Closed loop: render every finished run of this results.h5, analyse it, compare labels.
    #[arg(long, value_name = "RESULTS_H5")]
    closed_loop: Option<PathBuf>,
    /// Depth-of-field Gaussian sigma, um.
    #[arg(long, default_value_t = 0.5)]
    dof_sigma: f64,
    /// With --random: draw every imaging condition not given from the ranges a lab meets (seeded by --seed).
    #[arg(long)]
    vary: bool,
    /// With --random: focal plane above (+) or below (-) the cells' mid-plane, um (below focus the rim is bright).
    #[arg(long, allow_hyphen_values = true)]
    defocus: Option<f64>,
    /// With --random: numerical aperture of the objective (sets the edge and halo width).
    #[arg(long)]
    na: Option<f64>,
    /// With --random: exposure time, us (motion blur).
    #[arg(long)]
    exposure_us: Option<f64>,
    /// With --random: relative illumination change across the image.
    #[arg(long)]
    gradient: Option<f64>,
    /// With --random: relative frame-to-frame brightness fluctuation.
    #[arg(long)]
    flicker: Option<f64>,
    /// With --random: bit depth of the frames, 8 or 16.
    #[arg(long)]
    bits: Option<u8>,
    /// With --random: PDMS brightness beyond the walls relative to the channel.
    #[arg(long)]
    wall_brightness: Option<f64>,
    /// With --random: debris particles flowing through the field.
    #[arg(long)]
    debris: Option<usize>,
    /// With --random: centre-to-centre distance of consecutive cells, um.
    #[arg(long)]
    spacing: Option<f64>,
    /// With --random or --closed-loop: the synthesiser's edge profiles (synth; render3d for the
    /// closed loop) or the wave-optics renderer (wave).
    #[arg(long, default_value = "synth", value_parser = ["synth", "wave"])]
    renderer: String,
}

impl Args {
    fn um_per_px(&self) -> f64 {
        self.um_per_px.unwrap_or(0.2)
    }
    /// `--um-per-px` checked where it is given (the range of the imaging conditions), so that a
    /// bad value is not blamed on the `spec.toml` written from it.
    fn checked_um_per_px(&self) -> anyhow::Result<f64> {
        let v = self.um_per_px();
        if !(v.is_finite() && (0.01..=10.0).contains(&v)) {
            bail!("--um-per-px must be in [0.01, 10], got {v}");
        }
        Ok(v)
    }
    fn noise(&self) -> f64 {
        self.noise.unwrap_or(0.01)
    }
    /// Imaging conditions for --random, when any is given or --vary; `None` for the plain random recording.
    fn conditions(&self) -> anyhow::Result<Option<synth::Conditions>> {
        let given = self.defocus.is_some()
            || self.na.is_some()
            || self.exposure_us.is_some()
            || self.gradient.is_some()
            || self.flicker.is_some()
            || self.bits.is_some()
            || self.wall_brightness.is_some()
            || self.debris.is_some()
            || self.spacing.is_some();
        if !(given || self.vary) {
            return Ok(None);
        }
        let mut c = if self.vary { synth::random_conditions(self.seed) } else { synth::Conditions::default() };
        let check = |name: &str, v: f64, lo: f64, hi: f64| -> anyhow::Result<f64> {
            if !(v.is_finite() && v >= lo && v <= hi) {
                bail!("--{name} must be in [{lo}, {hi}], got {v}");
            }
            Ok(v)
        };
        if let Some(v) = self.defocus {
            c.defocus_um = check("defocus", v, -10.0, 10.0)?;
        }
        if let Some(v) = self.na {
            c.na = check("na", v, 0.05, 1.5)?;
        }
        if let Some(v) = self.exposure_us {
            // a frame is exposed within its frame interval (1/fps, 2500 us at 400 fps)
            c.exposure_s = 1e-6 * check("exposure-us", v, 0.0, 1e6 / synth::random::FPS)?;
        }
        if let Some(v) = self.gradient {
            c.gradient = check("gradient", v, 0.0, 1.0)?;
        }
        if let Some(v) = self.flicker {
            c.flicker = check("flicker", v, 0.0, 0.5)?;
        }
        if let Some(b) = self.bits {
            c.sixteen_bit = match b {
                8 => false,
                16 => true,
                _ => bail!("--bits must be 8 or 16, got {b}"),
            };
        }
        if let Some(v) = self.wall_brightness {
            c.wall_brightness = check("wall-brightness", v, 0.01, 10.0)?;
        }
        if let Some(n) = self.debris {
            c.debris = n.min(10_000);
        }
        if let Some(v) = self.spacing {
            c.spacing_um = check("spacing", v, 8.0, 1000.0)?;
        }
        if let Some(v) = self.um_per_px {
            c.um_per_px = check("um-per-px", v, 0.01, 10.0)?;
        }
        if let Some(v) = self.noise {
            c.noise_sigma = check("noise", v, 0.0, 1.0)?;
        }
        if let Some(v) = self.velocity {
            c.velocity_mm_s = check("velocity", v, 1e-3, 1000.0)?;
        }
        Ok(Some(c))
    }
}

fn from_results(args: &Args, path: &std::path::Path, out: &std::path::Path) -> anyhow::Result<()> {
    use rbc_analysis::simulated::render3d;
    let Some(run) = &args.run else { bail!("--from-results needs --run RUN_ID") };
    args.checked_um_per_px()?;
    let cell = render3d::cell_from_results(path, run, args.snapshot)?;
    let velocity = args.velocity.unwrap_or(cell.velocity_mm_s);
    if !(velocity.is_finite() && velocity > 0.0) {
        bail!("{}: run {run}: velocity {velocity} mm/s is not > 0; give --velocity", path.display());
    }
    let params = render3d::Render3dParams { focal_z_um: args.focal_z, dof_sigma_um: args.dof_sigma, ..Default::default() };
    let img = render3d::cell_image(&cell.mesh, &synth::OpticsSpec::default(), &params)?;
    let (spec, x0) = render3d::single_cell_spec(args.um_per_px(), args.noise(), velocity, img.bbox_um[1] - img.bbox_um[0]);
    let motion = render3d::CellMotion { x0_um: x0, velocity_mm_s: velocity };
    let truth = render3d::write_recording_3d(out, &spec, &img, &motion, &cell.label, args.seed)?;
    println!(
        "{}: run {run} snapshot at t = {:.4} s ({}), {} frames at {velocity:.3} mm/s; in-focus area {:.1} um^2, y {:+.2} um",
        out.display(),
        cell.t_s,
        cell.label,
        truth.rows.len(),
        img.area_um2,
        img.centroid_um[1]
    );
    Ok(())
}

fn closed_loop(args: &Args, path: &std::path::Path, out: &std::path::Path) -> anyhow::Result<()> {
    use rbc_analysis::simulated::closedloop::{self, Agreement, LoopConfig, LOOP_COLUMNS};
    args.checked_um_per_px()?;
    if !(args.dof_sigma.is_finite() && args.dof_sigma > 0.0) {
        bail!("--dof-sigma must be > 0, got {}", args.dof_sigma);
    }
    let cfg = LoopConfig {
        um_per_px: args.um_per_px(),
        noise: args.noise(),
        render: rbc_analysis::simulated::render3d::Render3dParams { focal_z_um: args.focal_z, dof_sigma_um: args.dof_sigma, ..Default::default() },
        seed: args.seed,
        wave: (args.renderer == "wave").then(|| rbc_analysis::simulated::wave::WaveOptics {
            defocus_um: args.defocus.unwrap_or(1.0),
            na: args.na.unwrap_or(0.8),
            condenser_na: 0.5 * args.na.unwrap_or(0.8),
            ..Default::default()
        }),
        ..Default::default()
    };
    if let Some(o) = &cfg.wave {
        o.validate(std::path::Path::new("--defocus/--na"))?;
    }
    // the rendered recordings and closed_loop.csv replace those of an earlier run as one set
    let ids: Vec<String> = rbc_schema::results::read_runs(path)?.into_iter().map(|r| r.run_id).collect();
    let owns = |n: &str| n == "closed_loop.csv" || ids.iter().any(|id| id == n);
    let fill = |staging: &std::path::Path| -> anyhow::Result<_> {
        let (rows, skipped) = closedloop::closed_loop(path, staging, &cfg)?;
        if rows.is_empty() {
            bail!("{}: no finished run to render ({} unfinished)", path.display(), skipped.len());
        }
        rbc_schema::tables::write_table(&staging.join("closed_loop.csv"), &rows, &LOOP_COLUMNS)?;
        Ok((rows, skipped))
    };
    let ((rows, skipped), _) = rbc_schema::output_set::write_set_with(out, owns, fill, rbc::unstaged)?;
    for r in &rows {
        println!("{:28} solver {:9} pipeline {:9} classifier {:9} cluster {:5} y {:+.2} um asymmetry {:.3} solidity {:.3} notch {:.3}", r.run_id, r.solver, r.pipeline, r.classifier, r.cluster, r.y_um, r.asymmetry, r.solidity, r.notch);
    }
    if !skipped.is_empty() {
        println!("skipped (unfinished): {}", skipped.join(", "));
    }
    let csv = out.join("closed_loop.csv");
    print!("{}", Agreement::pipeline(&rows).render("rbc-analyze pipeline vs solver"));
    print!("{}", Agreement::classifier(&rows).render("shape classifier alone vs solver"));
    println!("{}", csv.display());
    Ok(())
}

fn run(args: Args) -> anyhow::Result<()> {
    if let Some(root) = &args.examples {
        // the example folders replace those of an earlier run as one set; other files (README) stay
        let examples = synth::examples::examples();
        let names: Vec<&str> = examples.iter().map(|ex| ex.name.as_str()).collect();
        let fill = |staging: &std::path::Path| -> anyhow::Result<()> {
            for ex in &examples {
                let truth = synth::write_recording(&staging.join(&ex.name), &ex.spec, ex.seed)?;
                println!("{}: {} frames, {} cells", root.join(&ex.name).display(), ex.spec.n_frames, truth.spec.cells.len());
            }
            Ok(())
        };
        rbc_schema::output_set::write_set_with(root, |n| names.contains(&n), fill, rbc::unstaged)?;
        return Ok(());
    }
    let Some(out) = &args.out else { bail!("--out DIR is required (or use --examples DIR)") };
    if let Some(path) = &args.from_results {
        return from_results(&args, path, out);
    }
    if let Some(path) = &args.closed_loop {
        return closed_loop(&args, path, out);
    }
    let spec = if args.random {
        args.checked_um_per_px()?;
        let c = args.conditions()?;
        match (c, args.renderer.as_str()) {
            (Some(c), "wave") => synth::condition_spec_wave(args.seed, &c),
            (None, "wave") => synth::condition_spec_wave(args.seed, &synth::Conditions { um_per_px: args.um_per_px(), noise_sigma: args.noise(), velocity_mm_s: args.velocity.unwrap_or(1.0), ..Default::default() }),
            (Some(c), _) => synth::condition_spec(args.seed, &c),
            (None, _) => synth::random_spec(args.seed, args.um_per_px(), args.noise(), args.velocity.unwrap_or(1.0)),
        }
    } else {
        let Some(path) = &args.spec else { bail!("give a SPEC.toml, --random or --examples DIR") };
        synth::read_spec(path)?
    };
    let truth = synth::write_recording(out, &spec, args.seed)?;
    println!("{}: {} frames, {} cells, {} truth rows", out.display(), spec.n_frames, spec.cells.len(), truth.rows.len());
    Ok(())
}

fn main() -> std::process::ExitCode {
    if !rbc::build_cpu::check("rbc-synth") {
        return std::process::ExitCode::from(2);
    }
    // a libhdf5 call that hangs on a damaged file ends the command with one line (exit 2)
    rbc_schema::hdf5_watch::enable_from_env("rbc-synth");
    match run(Args::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rbc-synth: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
