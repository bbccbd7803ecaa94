//! `rbc-bench`: speed measurements printed as tables (never asserted in tests).
//!
//! `rbc-bench solver` times the boundary-integral kernels and operators;
//! `rbc-bench analyze` times the frame pipeline (and trackpy beside it when installed);
//! `rbc-bench frame-stages` times frame detection alone and each of its stages per frame;
//! `rbc-bench classifier-features` prints the shape classifier's calibration table (features against truth, CSV);
//! `rbc-bench shape-calibration` fits the shape score's calibrated probability on synthetic tracks and prints its held-out reliability diagram, ECE and Brier score.
//! `rbc-bench precision` prints the work-precision table of the time integrators;
//! `rbc-bench periodic` times membrane forces, spectral Ewald sums and the channel wall operator;
//! `rbc-bench channel` prints core-seconds per simulated ms of the paper's channel scene (no-slip and penalty walls).
//! `rbc-bench channel-tol` measures steps, error-estimate anatomy and accuracy versus cost per scheme and tolerance in the channel.
//! `rbc-bench controller` compares the integral and the PI step-size controller on the free-space work-precision cases.
//! `rbc-bench channel-cost` splits one channel Stokes solve into its parts at 512, 2048 and 8192 cell triangles.
//! `rbc-bench near-field` measures the near-singular quadrature against one channel solve (on and off side by side).
//! `rbc-bench channel-profile` splits one viscosity-contrast channel solve into its Ewald sums (real / Fourier parts, pair counts).
//! `rbc-bench robustness` prints `rbc-analyze`'s accuracy per imaging condition (defocus, NA, blur, noise, pixel size, walls, debris, neighbours) against the synthesiser's truth.
//! `rbc-bench fuzz` feeds mutated inputs of every format to the library's readers and reports panics, hangs and the errors seen (`rbc::fuzz`).
//! `rbc-bench bending-relaxation` measures the relaxation rate of a bending shape mode against linear theory per bending method, mode, lambda and mesh.
//! `rbc-bench centroid-bias` prints the signed centroid error of frame detection per truth shape and pixel size.
//! `rbc-bench steady-detector` prints what the steady-state detector costs a run per 10 ms of sample time as its kept samples pile up.
//! `rbc-bench compare` puts runs of one scene (other binaries, other settings) beside a reference run: cost and observables (`scripts/bench_speed.sh`).

fn main() -> std::process::ExitCode {
    if !rbc::build_cpu::check("rbc-bench") {
        return std::process::ExitCode::from(2);
    }
    rbc::alloc::keep_freed_memory();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let which = args.first().map(String::as_str).unwrap_or("");
    let result = match which {
        "solver" => rbc::bench::solver::run(&args[1..]),
        "analyze" => rbc::bench::analyze::run(&args[1..]),
        "frame-stages" => rbc::bench::frame_stages::run(&args[1..]),
        "classifier-features" => rbc::bench::classifier_features::run(&args[1..]),
        "shape-calibration" => rbc::bench::shape_calibration::run(&args[1..]),
        "precision" => rbc::bench::precision::run(&args[1..]),
        "periodic" => rbc::bench::periodic::run(&args[1..]),
        "channel-cost" => rbc::bench::channel_cost::run(&args[1..]),
        "channel" => rbc::bench::channel::run(&args[1..]),
        "channel-profile" => rbc::bench::channel_profile::run(&args[1..]),
        "channel-tol" => rbc::bench::channel_tol::run(&args[1..]),
        "controller" => rbc::bench::controller::run(&args[1..]),
        "near-field" => rbc::bench::near_field::run(&args[1..]),
        "robustness" => rbc::bench::robustness::run(&args[1..]),
        "compare" => rbc::bench::compare::run(&args[1..]),
        "steady-detector" => rbc::bench::steady_detector::run(&args[1..]),
        "centroid-bias" => rbc::bench::centroid_bias::run(&args[1..]),
        "bending-relaxation" => rbc::bench::bending_relaxation::run(&args[1..]),
        "fuzz" => rbc::fuzz::run(&args[1..]),
        "fuzz-worker" => rbc::fuzz::worker::main(&args[1..]),
        _ => {
            eprintln!("usage: rbc-bench (solver|analyze|frame-stages|classifier-features|shape-calibration|precision|periodic|channel|channel-cost|channel-profile|channel-tol|controller|near-field|robustness|centroid-bias|compare|steady-detector|bending-relaxation|fuzz) [options]");
            return std::process::ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rbc-bench: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
