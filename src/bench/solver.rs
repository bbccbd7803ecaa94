//! `rbc-bench solver`: speed of the boundary-integral kernels, operators and a full deflated GMRES solve, against this CPU's kernel limit.
//!
//! Usage: `rbc-bench solver [--quick]` (`--quick` skips 8192 triangles and uses fewer repeats).
//! Tables go to stdout. The "kernel limit" of an operator is the time the vectorised
//! Stokeslet + stresslet sums alone take for its `vertices x quadrature nodes` pairs at
//! the rate measured in the first table; the ratio shows the overhead of density
//! interpolation, Duffy corrections and scheduling on top of the raw sums.

use anyhow::{bail, Context};
use super::bim_timing::{kernel_throughput, operator_timing, solve_timing, KernelThroughput};

/// Run the benchmark with the remaining command-line arguments.
pub fn run(args: &[String]) -> anyhow::Result<()> {
    let mut quick = false;
    for a in args {
        match a.as_str() {
            "--quick" => quick = true,
            other => bail!("rbc-bench solver: unknown option {other:?} (expected --quick)"),
        }
    }
    let repeats = if quick { 3 } else { 10 };
    let max_threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1).min(2);
    let threads: Vec<usize> = (1..=max_threads).collect();

    // The paper's cell: 1026 vertices x 14336 quadrature nodes (2048 triangles, 7 nodes each).
    let (nt, ns) = (1026, 14336);
    println!("## Kernel throughput: {nt} targets x {ns} sources (tiled lane loops as used by the operators; naive array of structs)");
    println!("threads | AVX-512 | Stokeslet Gpairs/s | stresslet Gpairs/s | portable SL / DL Gpairs/s | naive SL+DL Gpairs/s | SL+DL time (ms) | portable SL+DL (ms) | naive SL+DL (ms)");
    println!("---|---|---|---|---|---|---|---|---");
    let mut kernels: Vec<KernelThroughput> = Vec::new();
    for &t in &threads {
        let k = kernel_throughput(nt, ns, t, repeats);
        let pairs = (nt * ns) as f64;
        println!(
            "{t} | {} | {:.3} | {:.3} | {:.3} / {:.3} | {:.3} | {:.2} | {:.2} | {:.2}",
            k.avx512,
            k.stokeslet_pairs_per_s / 1e9,
            k.stresslet_pairs_per_s / 1e9,
            k.portable_stokeslet_pairs_per_s / 1e9,
            k.portable_stresslet_pairs_per_s / 1e9,
            k.naive_pairs_per_s / 1e9,
            1e3 * k.single_plus_double_seconds(nt, ns),
            1e3 * (pairs / k.portable_stokeslet_pairs_per_s + pairs / k.portable_stresslet_pairs_per_s),
            1e3 * pairs / k.naive_pairs_per_s
        );
        kernels.push(k);
    }
    println!("(reference, dependencies.md: ~11 ms single + double layer on one core, ~6 ms on two)\n");

    println!("## One operator application on a sphere (octahedron subdivision)");
    println!("triangles | vertices | nodes | threads | single layer (ms) | double layer (ms) | SL+DL (ms) | kernel limit (ms) | ratio");
    println!("---|---|---|---|---|---|---|---|---");
    let levels: &[usize] = if quick { &[3, 4] } else { &[3, 4, 5] };
    for &level in levels {
        for (ti, &t) in threads.iter().enumerate() {
            let reps = if level >= 5 { repeats.min(3) } else { repeats };
            let o = operator_timing(level, t, reps).context("operator benchmark")?;
            let limit = kernels[ti].single_plus_double_seconds(o.vertices, o.quadrature_nodes);
            let total = o.single_layer_s + o.double_layer_s;
            println!(
                "{} | {} | {} | {t} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2}",
                o.triangles,
                o.vertices,
                o.quadrature_nodes,
                1e3 * o.single_layer_s,
                1e3 * o.double_layer_s,
                1e3 * total,
                1e3 * limit,
                total / limit
            );
        }
    }

    println!("\n## Full solve: discocyte in shear with a generic load, lambda = 5, GMRES to 1e-5 with Wielandt deflation");
    println!("triangles | threads | iterations | DL applications | residual | single layer (ms) | GMRES (ms) | GMRES per application (ms) | total (ms) | total / kernel limit (SL + applications x DL)");
    println!("---|---|---|---|---|---|---|---|---|---");
    for (ti, &t) in threads.iter().enumerate() {
        let level = 4;
        let (st, secs) = solve_timing(level, 5.0, t).context("solve benchmark")?;
        let o_nodes = 7 * 8 * 4usize.pow(level as u32);
        let o_vertices = 4 * 4usize.pow(level as u32) + 2;
        // Kernel limit of this solve: one single layer plus one double layer per application.
        let pairs = (o_vertices * o_nodes) as f64;
        let k = &kernels[ti];
        let limit = pairs / k.stokeslet_pairs_per_s + st.operator_applications as f64 * pairs / k.stresslet_pairs_per_s;
        println!(
            "{} | {t} | {} | {} | {:.1e} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2}",
            8 * 4usize.pow(level as u32),
            st.iterations,
            st.operator_applications,
            st.residual,
            1e3 * st.single_layer_seconds,
            1e3 * st.gmres_seconds,
            1e3 * st.gmres_seconds / st.operator_applications.max(1) as f64,
            1e3 * secs,
            secs / limit
        );
    }
    Ok(())
}
