//! Speed of the periodic Stokeslet and stresslet sums (real-space and spectral parts separately), for [`super::periodic`] (`rbc-bench periodic`).

use nalgebra::Vector3;

use super::clock::{min_wall_s, pool};
use rbc_solver::ewald::{EwaldError, EwaldParams, PeriodicStokes};

/// One row of the Ewald timing table (seconds per application).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EwaldTiming {
    pub points: usize,
    pub threads: usize,
    pub tol: f64,
    pub params: EwaldParams,
    pub stokeslet_real_s: f64,
    pub stokeslet_fourier_s: f64,
    pub stresslet_real_s: f64,
    pub stresslet_fourier_s: f64,
}

/// Quasi-random points (a Kronecker sequence: deterministic and well spread) in the box.
pub fn kronecker_points(n: usize, box_len: [f64; 3]) -> Vec<Vector3<f64>> {
    (1..=n)
        .map(|k| {
            let k = k as f64;
            Vector3::new(
                (k * 0.754_877_666_246_692_7).fract() * box_len[0],
                (k * 0.569_840_290_998_053_2).fract() * box_len[1],
                (k * 0.430_159_709_001_946_8).fract() * box_len[2],
            )
        })
        .collect()
}

/// `points` targets = sources in `box_len` (um), parameters from [`EwaldParams::for_tolerance`] at `tol`,
/// on `threads` threads, best of `repeats`.
pub fn ewald_timing(points: usize, box_len: [f64; 3], tol: f64, threads: usize, repeats: usize) -> Result<EwaldTiming, EwaldError> {
    let params = EwaldParams::for_tolerance(box_len, points, tol)?;
    let ps = PeriodicStokes::new(box_len, params)?;
    let x = kronecker_points(points, box_len);
    let f: Vec<Vector3<f64>> = x.iter().map(|p| Vector3::new(p.y.sin(), p.z.cos(), 0.3)).collect();
    let n: Vec<Vector3<f64>> = x.iter().map(|p| Vector3::new(p.z.cos(), 0.2, p.x.sin()) * 0.01).collect();
    let pool = pool(threads);
    let mut out = vec![Vector3::zeros(); points];
    let (a, b, c, d) = pool.install(|| {
        (
            min_wall_s(repeats, || ps.stokeslet_real(&x, &x, &f, &mut out)),
            min_wall_s(repeats, || ps.stokeslet_fourier_add(&x, &x, &f, &mut out)),
            min_wall_s(repeats, || ps.stresslet_real(&x, &x, &f, &n, &mut out)),
            min_wall_s(repeats, || ps.stresslet_fourier_add(&x, &x, &f, &n, &mut out)),
        )
    });
    std::hint::black_box(&out);
    Ok(EwaldTiming {
        points,
        threads,
        tol,
        params,
        stokeslet_real_s: a,
        stokeslet_fourier_s: b,
        stresslet_real_s: c,
        stresslet_fourier_s: d,
    })
}

/// The unit cell of the paper's channel as a periodic box (um): `L_x = 42.7`, the 12 x 10 um
/// cross-section with 1 um of margin on each side.
pub const CHANNEL_BOX: [f64; 3] = [42.7, 14.0, 12.0];

/// The timing table for `rbc-bench`: at each point count (e.g. 1026, 3000, 10000, 30000) and tolerance,
/// targets = sources (Kronecker points in [`CHANNEL_BOX`]). The last column, the stresslet's Fourier
/// part divided by `N log2 N` (ns), stays roughly constant when the smooth part scales like `N log N`
/// (`xi` grows like `N^(1/3)` at fixed tolerance, so the grid grows like `N`).
pub fn ewald_table(points: &[usize], tols: &[f64], threads: usize, repeats: usize) -> Result<String, EwaldError> {
    let mut s = String::from(
        "points  tol      xi(1/um) r_cut(um) grid          P   G_real(s)  G_fourier(s) T_real(s)  T_fourier(s) T_fourier/(N log2 N) (ns)\n",
    );
    for &n in points {
        for &tol in tols {
            let t = ewald_timing(n, CHANNEL_BOX, tol, threads, repeats)?;
            let p = t.params;
            s += &format!(
                "{:<7} {:<8.0e} {:<8.3} {:<9.3} {:<13} {:<3} {:<10.4} {:<12.4} {:<10.4} {:<12.4} {:.1}\n",
                n,
                tol,
                p.xi,
                p.r_cut,
                format!("{}x{}x{}", p.grid[0], p.grid[1], p.grid[2]),
                p.support,
                t.stokeslet_real_s,
                t.stokeslet_fourier_s,
                t.stresslet_real_s,
                t.stresslet_fourier_s,
                t.stresslet_fourier_s / (n as f64 * (n as f64).log2()) * 1e9
            );
        }
    }
    Ok(s)
}
