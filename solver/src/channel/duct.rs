//! Pressure-driven flow in a straight duct of rectangular cross-section: the Boussinesq series (sharp corners) and a finite-difference flux of the rounded-corner section.
//!
//! For `|y| <= a`, `|z| <= b` and a pressure gradient `-dp/dx = G` (Pa/um), viscosity `mu` (Pa s),
//! the axial velocity is (Boussinesq 1868; White, "Viscous fluid flow", 3rd ed., eq. 3-48)
//!
//! ```text
//! u(y, z) = 16 a^2 G / (mu pi^3) sum_{n odd} (-1)^((n-1)/2) n^-3 [1 - cosh(n pi z/2a) / cosh(n pi b/2a)] cos(n pi y/2a)
//! Q       = 4 a^3 b G / (3 mu) [1 - 192 a / (pi^5 b) sum_{n odd} tanh(n pi b/2a) / n^5]
//! ```
//!
//! The `1` of the bracket sums in closed form to the plane Poiseuille profile
//! `G (a^2 - y^2) / (2 mu)` (the Fourier series of the parabola), so the code sums only the
//! exponentially convergent remainder. Units: lengths um, `G` Pa/um, velocity um/s.
//!
//! The paper's 12 x 10 um section: `u_mean / u_max = 0.47878` (sharp corners; the square gives
//! 0.4770, the slit 2/3). With corners rounded by 1.5 um ([`RoundedDuct`]) the flux at equal
//! gradient is 0.99476 and the centre velocity 0.99858 of the sharp duct's.

/// Odd terms summed: `cosh(n pi z/2a)/cosh(n pi b/2a) <= exp(-n pi (b - |z|)/2a)` decays
/// exponentially except near the walls `z = +-b` (where `u -> 0`); 2001 terms make the
/// `n^-3` tail below 1e-8 there too.
const TERMS: usize = 2001;

/// Rectangular duct `|y| <= a`, `|z| <= b` (half-sides in um) with viscosity `mu` (Pa s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RectangularDuct {
    pub a: f64,
    pub b: f64,
    pub mu: f64,
}

/// `cosh(x) / cosh(big)` for `|x| <= big` without overflow.
fn cosh_ratio(x: f64, big: f64) -> f64 {
    let x = x.abs();
    (x - big).exp() * (1.0 + (-2.0 * x).exp()) / (1.0 + (-2.0 * big).exp())
}

impl RectangularDuct {
    /// The duct of width `width_y` and height `height_z` (um).
    pub fn new(width_y: f64, height_z: f64, mu: f64) -> Self {
        Self {
            a: 0.5 * width_y,
            b: 0.5 * height_z,
            mu,
        }
    }

    /// Axial velocity (um/s) at `(y, z)` for the pressure gradient `g = -dp/dx` (Pa/um); 0 outside.
    pub fn velocity(&self, g: f64, y: f64, z: f64) -> f64 {
        let (a, b) = (self.a, self.b);
        if y.abs() >= a || z.abs() >= b {
            return 0.0;
        }
        let pi = std::f64::consts::PI;
        let mut sum = 0.0;
        for k in 0..TERMS {
            let n = (2 * k + 1) as f64;
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            let w = n * pi / (2.0 * a);
            sum += sign * n.powi(-3) * cosh_ratio(w * z, w * b) * (w * y).cos();
        }
        g / self.mu * (0.5 * (a * a - y * y) - 16.0 * a * a / pi.powi(3) * sum)
    }

    /// Volumetric flux (um^3/s) for `g = -dp/dx` (Pa/um).
    pub fn flux(&self, g: f64) -> f64 {
        let (a, b) = (self.a, self.b);
        let pi = std::f64::consts::PI;
        let s: f64 = (0..TERMS)
            .map(|k| (2 * k + 1) as f64)
            .map(|n| (n * pi * b / (2.0 * a)).tanh() / n.powi(5))
            .sum();
        4.0 * a.powi(3) * b * g / (3.0 * self.mu) * (1.0 - 192.0 * a / (pi.powi(5) * b) * s)
    }

    /// Mean velocity `Q / (4 a b)` (um/s).
    pub fn mean_velocity(&self, g: f64) -> f64 {
        self.flux(g) / (4.0 * self.a * self.b)
    }

    /// Centre-line (maximum) velocity `u(0, 0)` (um/s).
    pub fn max_velocity(&self, g: f64) -> f64 {
        self.velocity(g, 0.0, 0.0)
    }

    /// `u_mean / u_max`, independent of `G` and `mu` (0.4770 for a square, 2/3 for a slit).
    pub fn mean_to_max(&self) -> f64 {
        self.mean_velocity(1.0) / self.max_velocity(1.0)
    }
}

/// Solution of `lap w = -1` (um^2), `w = 0` outside a cross-section, on a vertex grid: the duct
/// velocity is `u = (G / mu) w`.
#[derive(Debug, Clone, PartialEq)]
pub struct PoissonGrid {
    half_y: f64,
    half_z: f64,
    hy: f64,
    hz: f64,
    ny: usize,
    nz: usize,
    /// `w` at node `(i, j)` (y index i, z index j), row-major with `nz + 1` per row.
    w: Vec<f64>,
}

impl PoissonGrid {
    /// Solve on the box `|y| <= half_y`, `|z| <= half_z` restricted to `inside(y, z)`, grid spacing
    /// ~`h` (um), by the 5-point finite-difference Laplacian and conjugate gradients (matrix-free:
    /// the operator is a stencil; no sparse solver is needed for a few 1e5 unknowns). Nodes outside
    /// `inside` are set to zero (staircase): O(h^2) where the walls lie on grid lines, O(h) along
    /// curved parts.
    pub fn solve(half_y: f64, half_z: f64, h: f64, inside: impl Fn(f64, f64) -> bool) -> Self {
        let ny = (2.0 * half_y / h).round() as usize;
        let nz = (2.0 * half_z / h).round() as usize;
        let (hy, hz) = (2.0 * half_y / ny as f64, 2.0 * half_z / nz as f64);
        let (sy, sz) = (ny + 1, nz + 1);
        let mask: Vec<bool> = (0..sy * sz)
            .map(|p| {
                let (i, j) = (p / sz, p % sz);
                i > 0
                    && j > 0
                    && i < ny
                    && j < nz
                    && inside(-half_y + i as f64 * hy, -half_z + j as f64 * hz)
            })
            .collect();
        let apply = |x: &[f64], out: &mut [f64]| {
            for p in 0..sy * sz {
                if !mask[p] {
                    out[p] = 0.0;
                    continue;
                }
                let v = |q: usize| if mask[q] { x[q] } else { 0.0 };
                out[p] = (2.0 * x[p] - v(p - sz) - v(p + sz)) / (hy * hy)
                    + (2.0 * x[p] - v(p - 1) - v(p + 1)) / (hz * hz);
            }
        };
        let b: Vec<f64> = mask.iter().map(|&m| if m { 1.0 } else { 0.0 }).collect();
        let mut x = vec![0.0; sy * sz];
        let mut r = b.clone();
        let mut p = r.clone();
        let mut ap = vec![0.0; sy * sz];
        let mut rr: f64 = r.iter().map(|v| v * v).sum();
        let rr0 = rr;
        for _ in 0..20 * (sy + sz) {
            apply(&p, &mut ap);
            let alpha = rr / p.iter().zip(&ap).map(|(a, b)| a * b).sum::<f64>();
            x.iter_mut().zip(&p).for_each(|(x, p)| *x += alpha * p);
            r.iter_mut().zip(&ap).for_each(|(r, a)| *r -= alpha * a);
            let rr_new: f64 = r.iter().map(|v| v * v).sum();
            if rr_new < 1e-26 * rr0 {
                break;
            }
            let beta = rr_new / rr;
            p.iter_mut().zip(&r).for_each(|(p, r)| *p = r + beta * *p);
            rr = rr_new;
        }
        Self {
            half_y,
            half_z,
            hy,
            hz,
            ny,
            nz,
            w: x,
        }
    }

    /// `Int w dA` (um^4): the flux per unit `G / mu`.
    pub fn integral(&self) -> f64 {
        self.w.iter().sum::<f64>() * self.hy * self.hz
    }

    /// `w` at `(y, z)` by bilinear interpolation (0 outside the box).
    pub fn value(&self, y: f64, z: f64) -> f64 {
        let (fy, fz) = ((y + self.half_y) / self.hy, (z + self.half_z) / self.hz);
        if !(fy >= 0.0 && fz >= 0.0 && fy <= self.ny as f64 && fz <= self.nz as f64) {
            return 0.0;
        }
        let (i, j) = (
            (fy.floor() as usize).min(self.ny - 1),
            (fz.floor() as usize).min(self.nz - 1),
        );
        let (ty, tz) = (fy - i as f64, fz - j as f64);
        let sz = self.nz + 1;
        let at = |a: usize, b: usize| self.w[a * sz + b];
        (1.0 - ty) * ((1.0 - tz) * at(i, j) + tz * at(i, j + 1))
            + ty * ((1.0 - tz) * at(i + 1, j) + tz * at(i + 1, j + 1))
    }
}

/// Flux per unit `G / mu` (um^4) of a cross-section `inside(y, z)` within `|y| <= half_y`,
/// `|z| <= half_z` ([`PoissonGrid::solve`] with spacing `h`).
pub fn poisson_flux(half_y: f64, half_z: f64, h: f64, inside: impl Fn(f64, f64) -> bool) -> f64 {
    PoissonGrid::solve(half_y, half_z, h, inside).integral()
}

/// The rounded-corner duct flow per unit `G / mu` (um^2): the Boussinesq solution of the sharp
/// rectangle plus the finite-difference difference rounded - sharp on the same grid (the grid
/// errors of the straight walls cancel in the difference). `u = (G / mu) w`.
#[derive(Debug, Clone, PartialEq)]
pub struct RoundedDuct {
    sharp: RectangularDuct,
    fd_sharp: PoissonGrid,
    fd_rounded: PoissonGrid,
}

impl RoundedDuct {
    /// Grid spacing `h` (um) of the finite-difference correction (0.05 um: 1e5 nodes, ~1 s).
    pub fn new(geometry: &super::mesh::ChannelGeometry, h: f64) -> Self {
        let (hy, hz) = (0.5 * geometry.width_y, 0.5 * geometry.height_z);
        Self {
            sharp: RectangularDuct::new(geometry.width_y, geometry.height_z, 1.0),
            fd_sharp: PoissonGrid::solve(hy, hz, h, |_, _| true),
            fd_rounded: PoissonGrid::solve(hy, hz, h, |y, z| geometry.contains(y, z)),
        }
    }

    /// Axial velocity (um/s) at `(y, z)` for `g = -dp/dx` (Pa/um) and viscosity `mu` (Pa s).
    pub fn velocity(&self, mu: f64, g: f64, y: f64, z: f64) -> f64 {
        let w = self.sharp.velocity(1.0, y, z) + self.fd_rounded.value(y, z)
            - self.fd_sharp.value(y, z);
        g / mu * w
    }

    /// Flux (um^3/s) for `g` (Pa/um) and `mu` (Pa s).
    pub fn flux(&self, mu: f64, g: f64) -> f64 {
        g / mu * (self.sharp.flux(1.0) + self.fd_rounded.integral() - self.fd_sharp.integral())
    }
}

/// Flux (um^3/s) of the rounded-corner channel for `g = -dp/dx` (Pa/um), see [`RoundedDuct`].
pub fn rounded_flux(geometry: &super::mesh::ChannelGeometry, mu: f64, g: f64, h: f64) -> f64 {
    RoundedDuct::new(geometry, h).flux(mu, g)
}

/// How well the empty channel `ch` reproduces the duct flow (its accuracy check, used by the
/// tests and `rbc-bench periodic`): the max error of the axial velocity against the rounded-corner duct flow ([`RoundedDuct`]:
/// Boussinesq's series plus the finite-difference corner correction) at the solve's own pressure
/// gradient, relative to the centre velocity, over a 7 x 7 grid of the cross-section at least
/// `margin_um` from the walls, in two cross-sections (x = 0.37 L_x and 0.81 L_x); also the
/// largest transverse velocity (same scale) and the gradient `-dp/dx` (Pa/um).
pub fn duct_profile_error(
    ch: &super::ChannelStokes,
    margin_um: f64,
    mean_mm_s: f64,
) -> Result<(f64, f64, f64), super::ChannelError> {
    let g = ch.geometry;
    let (hy, hz) = (0.5 * g.width_y - margin_um, 0.5 * g.height_z - margin_um);
    let mut pts = Vec::new();
    for x in [0.37 * g.length_x, 0.81 * g.length_x] {
        for i in 0..=6 {
            for j in 0..=6 {
                pts.push(nalgebra::Vector3::new(
                    x,
                    -hy + 2.0 * hy * i as f64 / 6.0,
                    -hz + 2.0 * hz * j as f64 / 6.0,
                ));
            }
        }
    }
    let (u, grad) = ch.empty_channel_flow(&pts, mean_mm_s)?;
    let mu = ch.viscosity();
    let umax = ch.duct.velocity(mu, grad, 0.0, 0.0);
    let (mut err, mut transverse) = (0.0f64, 0.0f64);
    for (p, v) in pts.iter().zip(&u) {
        err = err.max((v.x - ch.duct.velocity(mu, grad, p.y, p.z)).abs() / umax);
        transverse = transverse.max(v.y.abs().max(v.z.abs()) / umax);
    }
    Ok((err, transverse, grad))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Square duct: `Q = 0.5623 G a^4 / mu` (White, "Viscous fluid flow", section 3-3.3) and
    /// centre velocity `0.2947 G a^2 / mu` (Shah & London 1978), hence `u_mean/u_max = 0.4770`.
    #[test]
    fn square_duct_published_numbers() {
        let d = RectangularDuct {
            a: 1.0,
            b: 1.0,
            mu: 1.0,
        };
        assert!((d.flux(1.0) - 0.5623).abs() < 1e-4, "{}", d.flux(1.0));
        assert!(
            (d.mean_to_max() - 0.5623 / 4.0 / 0.2947).abs() < 3e-4,
            "{}",
            d.mean_to_max()
        );
        // Centre velocity 0.2947 G a^2 / mu (Shah & London).
        assert!(
            (d.max_velocity(1.0) - 0.29468).abs() < 1e-4,
            "{}",
            d.max_velocity(1.0)
        );
    }

    /// Wide slit (b >> a): plane Poiseuille `G (a^2 - y^2) / (2 mu)` and mean/max = 2/3.
    #[test]
    fn slit_limit() {
        let d = RectangularDuct {
            a: 1.0,
            b: 200.0,
            mu: 2.0,
        };
        for y in [0.0, 0.3, -0.7] {
            let exact = 3.0 * (1.0 - y * y) / (2.0 * 2.0);
            assert!((d.velocity(3.0, y, 0.0) - exact).abs() < 1e-12, "{y}");
        }
        // Flux per unit depth -> 2 a^3 G/(3 mu) times 2b, minus the end effects O(a/b).
        let ratio = d.mean_to_max();
        assert!(
            (ratio - 2.0 / 3.0).abs() < 0.01 && ratio < 2.0 / 3.0,
            "{ratio}"
        );
    }

    /// The series in y (cosines of y) must agree with the same duct turned by 90 degrees,
    /// where the series runs in the other direction; zero on the walls; flux = integral of u.
    #[test]
    fn series_is_consistent() {
        let d = RectangularDuct {
            a: 6.0,
            b: 5.0,
            mu: 1.2e-3,
        };
        let t = RectangularDuct {
            a: 5.0,
            b: 6.0,
            mu: 1.2e-3,
        };
        for (y, z) in [(0.0, 0.0), (2.0, 1.0), (-5.0, 4.5), (5.9, -0.3)] {
            let (u, v) = (d.velocity(1e-3, y, z), t.velocity(1e-3, z, y));
            assert!(
                (u - v).abs() < 1e-9 * d.max_velocity(1e-3),
                "{y},{z}: {u} vs {v}"
            );
        }
        assert!(d.velocity(1.0, 6.0, 1.0) == 0.0 && d.velocity(1.0, 2.0, 5.0 - 1e-13).abs() < 1e-6);
        // Gauss-Legendre (20 x 20 per cell of a 6 x 5 grid... here a plain midpoint rule, O(h^2)).
        let n = 600;
        let (hy, hz) = (12.0 / n as f64, 10.0 / n as f64);
        let mut q = 0.0;
        for i in 0..n {
            for j in 0..n {
                q += d.velocity(
                    1e-3,
                    -6.0 + (i as f64 + 0.5) * hy,
                    -5.0 + (j as f64 + 0.5) * hz,
                ) * hy
                    * hz;
            }
        }
        assert!(
            (q - d.flux(1e-3)).abs() < 1e-4 * d.flux(1e-3),
            "{q} vs {}",
            d.flux(1e-3)
        );
    }

    /// The 12 x 10 um channel of the paper: mean/max ratio (printed), and the finite-difference
    /// flux of the sharp section converges to the series at second order.
    #[test]
    fn paper_channel_ratio_and_fd_flux() {
        let d = RectangularDuct::new(12.0, 10.0, 1.2e-3);
        let ratio = d.mean_to_max();
        eprintln!("12 x 10 um duct: mean/max = {ratio:.6}");
        // Between the square (0.4770) and the slit (2/3), close to the square.
        assert!(ratio > 0.4770 && ratio < 0.5);
        let exact = d.flux(1.0) * d.mu;
        let e1 = (poisson_flux(6.0, 5.0, 0.2, |_, _| true) - exact).abs() / exact;
        let e2 = (poisson_flux(6.0, 5.0, 0.1, |_, _| true) - exact).abs() / exact;
        eprintln!("FD flux error h = 0.2: {e1:.3e}, h = 0.1: {e2:.3e}");
        assert!(e2 < 1e-3 && e1 / e2 > 3.5, "{e1} {e2}");
        // Rounding the corners (r_c = 1.5 um) removes a little flux.
        let g = crate::channel::mesh::ChannelGeometry::default();
        let qr = rounded_flux(&g, 1.2e-3, 1.0, 0.05);
        let rel = qr / d.flux(1.0);
        eprintln!("rounded/sharp flux ratio (r_c = 1.5 um): {rel:.6}");
        assert!(rel < 1.0 && rel > 0.99);
        // The rounded-duct profile: zero in the cut corners, equal to the series far from them,
        // and its centre velocity lower than the sharp one.
        let rd = RoundedDuct::new(&g, 0.05);
        assert!(rd.velocity(1.2e-3, 1.0, 5.9, 4.9).abs() < 1e-3 * d.max_velocity(1.0));
        let centre = rd.velocity(1.2e-3, 1.0, 0.0, 0.0) / d.max_velocity(1.0);
        eprintln!("rounded/sharp centre velocity: {centre:.6}");
        assert!(centre < 1.0 && centre > 0.99);
        let side = (rd.velocity(1.2e-3, 1.0, 0.0, 4.0) - d.velocity(1.0, 0.0, 4.0)).abs()
            / d.max_velocity(1.0);
        assert!(side < 1e-2, "{side}");
    }
}
