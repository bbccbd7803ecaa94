//! Partially coherent bright-field image of a thin phase-and-amplitude object: angular-spectrum propagation to the focal plane and a pupil of the objective's NA, summed over the condenser's illumination directions.
//!
//! Model (Goodman, *Introduction to Fourier Optics*, 3rd ed., sec. 3.10 (angular spectrum) and
//! 6.2-6.4 (coherent transfer function); Köhler illumination as an incoherent sum of tilted plane
//! waves, Born & Wolf sec. 10.6):
//!
//! - the object is its complex transmission `t(x, y) = exp(-mu T / 2 + i k0 (n_cell - n_medium) T)`
//!   (`T` the thickness, `mu` the intensity absorption coefficient of the cell's haemoglobin,
//!   `k0 = 2 pi / lambda`), a thin object in the mid-plane of the cell;
//! - a plane wave of transverse spatial frequency `f_c` (inside the condenser's disc
//!   `|f_c| <= NA_c / lambda`) is transmitted, propagated over `dz` to the plane the objective is
//!   focused on and cut by the pupil:
//!   `U_c(f) = t^(f - f_c) H(f)`, `H(f) = P(f) exp(i 2 pi dz (sqrt((n / lambda)^2 - |f|^2) - n / lambda))`,
//!   `P(f) = 1` for `|f| <= NA / lambda`, else 0;
//! - the image is the mean intensity over the illumination directions,
//!   `I(x) = mean_c |IFFT[t^(g) H(g + f_c)](x)|^2` (the tilt's linear phase drops out of the
//!   intensity), normalised so that `t = 1` gives `I = 1` (every `f_c` lies inside the pupil).
//!
//! The grid is periodic: the caller pads the object with enough empty border (transmission 1) that
//! the defocused image of one copy does not reach the next ([`margin_um`]).

use super::optics::WaveOptics;
use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;

/// Empty border an object needs around it, um: the lateral reach of a defocused edge,
/// `|dz| tan(asin(NA / n))` (the marginal ray), plus four resolution lengths `lambda / NA`.
pub fn margin_um(o: &WaveOptics) -> f64 {
    let sin = (o.na / o.n_medium).min(0.99);
    o.defocus_um.abs() * sin / (1.0 - sin * sin).sqrt() + 4.0 * o.wavelength_um / o.na
}

/// Transverse frequencies `(f_x, f_y)` (1/um) of the condenser's illumination directions: the disc
/// `|f_c| <= NA_c / lambda` sampled on rings `r_j = j / R NA_c / lambda`, `j = 0..=R`, with `6 j`
/// directions on ring `j` (equal area per direction to within a few per cent), `R = 2` (19 directions).
pub fn condenser_directions(o: &WaveOptics) -> Vec<[f64; 2]> {
    const RINGS: usize = 2;
    let r_max = o.condenser_na / o.wavelength_um;
    let mut out = vec![[0.0, 0.0]];
    if r_max > 0.0 {
        for j in 1..=RINGS {
            let r = r_max * j as f64 / RINGS as f64;
            for k in 0..6 * j {
                let a = std::f64::consts::TAU * (k as f64 + 0.5 * (j % 2) as f64) / (6 * j) as f64;
                out.push([r * a.cos(), r * a.sin()]);
            }
        }
    }
    out
}

/// The coherent transfer function `H(f)` of the module documentation at frequency `(fx, fy)` 1/um.
pub fn transfer(o: &WaveOptics, fx: f64, fy: f64) -> Complex64 {
    let f2 = fx * fx + fy * fy;
    let cut = o.na / o.wavelength_um;
    if f2 > cut * cut {
        return Complex64::new(0.0, 0.0);
    }
    let n = o.n_medium / o.wavelength_um;
    let phase = std::f64::consts::TAU * o.propagation_um() * ((n * n - f2).sqrt() - n);
    Complex64::from_polar(1.0, phase)
}

/// Spatial frequency (1/um) of FFT bin `k` of `n` samples at spacing `s` um.
fn freq(k: usize, n: usize, s: f64) -> f64 {
    let k = if k <= n / 2 { k as f64 } else { k as f64 - n as f64 };
    k / (n as f64 * s)
}

/// In-place 2D FFT of a row-major `nx` x `ny` grid (forward or inverse, unnormalised).
fn fft2(data: &mut [Complex64], nx: usize, ny: usize, planner: &mut FftPlanner<f64>, inverse: bool) {
    let (rows, cols) = if inverse { (planner.plan_fft_inverse(nx), planner.plan_fft_inverse(ny)) } else { (planner.plan_fft_forward(nx), planner.plan_fft_forward(ny)) };
    rows.process(data);
    let mut col = vec![Complex64::new(0.0, 0.0); ny];
    for i in 0..nx {
        for j in 0..ny {
            col[j] = data[j * nx + i];
        }
        cols.process(&mut col);
        for j in 0..ny {
            data[j * nx + i] = col[j];
        }
    }
}

/// The bright-field image (relative intensity, 1 = empty field) of a transmission `t` sampled on a
/// periodic `nx` x `ny` grid of spacing `s` um (row-major).
pub fn bright_field(t: &[Complex64], nx: usize, ny: usize, s: f64, o: &WaveOptics) -> Vec<f64> {
    assert_eq!(t.len(), nx * ny, "transmission of {nx} x {ny} samples");
    let mut planner = FftPlanner::new();
    let mut spectrum = t.to_vec();
    fft2(&mut spectrum, nx, ny, &mut planner, false);
    let dirs = condenser_directions(o);
    let norm = 1.0 / (nx * ny) as f64;
    let mut image = vec![0.0; nx * ny];
    let mut u = vec![Complex64::new(0.0, 0.0); nx * ny];
    for fc in &dirs {
        for j in 0..ny {
            let fy = freq(j, ny, s) + fc[1];
            for i in 0..nx {
                let fx = freq(i, nx, s) + fc[0];
                u[j * nx + i] = spectrum[j * nx + i] * transfer(o, fx, fy);
            }
        }
        fft2(&mut u, nx, ny, &mut planner, true);
        for (p, v) in image.iter_mut().zip(&u) {
            *p += (v * norm).norm_sqr();
        }
    }
    let w = 1.0 / dirs.len() as f64;
    image.iter_mut().for_each(|p| *p *= w);
    image
}

/// The same for an object that varies along one axis only (`n` samples at spacing `s` um along it,
/// periodic; e.g. the channel walls, uniform along the flow): the illumination direction's
/// component along the uniform axis stays in the pupil (`H(f_c,x, g + f_c,y)`).
pub fn bright_field_1d(t: &[Complex64], s: f64, o: &WaveOptics) -> Vec<f64> {
    let n = t.len();
    let mut planner = FftPlanner::new();
    let (fwd, inv) = (planner.plan_fft_forward(n), planner.plan_fft_inverse(n));
    let mut spectrum = t.to_vec();
    fwd.process(&mut spectrum);
    let dirs = condenser_directions(o);
    let mut image = vec![0.0; n];
    let mut u = vec![Complex64::new(0.0, 0.0); n];
    for fc in &dirs {
        for j in 0..n {
            u[j] = spectrum[j] * transfer(o, fc[0], freq(j, n, s) + fc[1]);
        }
        inv.process(&mut u);
        for (p, v) in image.iter_mut().zip(&u) {
            *p += (v / n as f64).norm_sqr();
        }
    }
    let w = 1.0 / dirs.len() as f64;
    image.iter_mut().for_each(|p| *p *= w);
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    fn optics(defocus_um: f64) -> WaveOptics {
        WaveOptics { defocus_um, ..WaveOptics::default() }
    }

    /// A disc-shaped phase object (thickness of a lens) on an n x n grid.
    fn phase_disc(n: usize, s: f64, r: f64, phase: f64, amplitude: f64) -> Vec<Complex64> {
        let mut t = vec![Complex64::new(1.0, 0.0); n * n];
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f64 - n as f64 / 2.0) * s, (j as f64 - n as f64 / 2.0) * s);
                let q = 1.0 - (x * x + y * y) / (r * r);
                if q > 0.0 {
                    t[j * n + i] = Complex64::from_polar(amplitude.powf(q.sqrt()), phase * q.sqrt());
                }
            }
        }
        t
    }

    /// An empty field images to 1 everywhere, at any focus.
    #[test]
    fn an_empty_field_is_uniform() {
        for dz in [-2.0, 0.0, 1.5] {
            let im = bright_field(&vec![Complex64::new(1.0, 0.0); 64 * 48], 64, 48, 0.1, &optics(dz));
            assert!(im.iter().all(|v| (v - 1.0).abs() < 1e-12));
        }
    }

    /// Energy: with a pupil that passes every frequency of the grid (NA at the grid's Nyquist
    /// limit is not reachable, so a coarse grid, s = 1 um, and in focus), the mean image intensity
    /// equals the mean of |t|^2 (Parseval), for a phase-and-amplitude object.
    #[test]
    fn a_pupil_wider_than_the_grid_keeps_the_energy() {
        let o = WaveOptics { na: 1.3, condenser_na: 0.0, wavelength_um: 0.2, defocus_um: 0.0, ..WaveOptics::default() };
        let t = phase_disc(32, 1.0, 8.0, 2.0, 0.7);
        let im = bright_field(&t, 32, 32, 1.0, &o);
        let mean_in: f64 = t.iter().map(|v| v.norm_sqr()).sum::<f64>() / t.len() as f64;
        let mean_out: f64 = im.iter().sum::<f64>() / im.len() as f64;
        assert!((mean_in - mean_out).abs() < 1e-12, "{mean_in} vs {mean_out}");
        // and it is the object's own |t|^2 point by point (the pupil passes everything)
        assert!(im.iter().zip(&t).all(|(a, b)| (a - b.norm_sqr()).abs() < 1e-12));
    }

    /// A weak pure-phase object is invisible in focus and seen by defocus with a contrast that
    /// changes sign with it (transport of intensity: `I = 1 - dz / k Laplacian(phi)`): the centre of a
    /// smooth phase bump is bright at one focus and dark at the other, equally much to first order,
    /// as much as the TIE says.
    #[test]
    fn a_phase_object_shows_only_out_of_focus_with_the_sign_of_the_defocus() {
        let (n, s, a, sigma) = (128, 0.1, 0.2, 1.5);
        let mut t = vec![Complex64::new(1.0, 0.0); n * n];
        for j in 0..n {
            for i in 0..n {
                let (x, y) = ((i as f64 - 64.0) * s, (j as f64 - 64.0) * s);
                t[j * n + i] = Complex64::from_polar(1.0, a * (-(x * x + y * y) / (2.0 * sigma * sigma)).exp());
            }
        }
        let centre = 64 * n + 64;
        let focus = bright_field(&t, n, n, s, &optics(0.0));
        let plus = bright_field(&t, n, n, s, &optics(1.0));
        let minus = bright_field(&t, n, n, s, &optics(-1.0));
        let c = |im: &[f64]| im[centre] - 1.0;
        assert!(focus.iter().all(|v| (v - 1.0).abs() < 1e-6), "in focus {}", c(&focus));
        assert!(c(&plus) * c(&minus) < 0.0, "{} {}", c(&plus), c(&minus));
        assert!((c(&plus) + c(&minus)).abs() < 0.05 * c(&plus).abs(), "{} {}", c(&plus), c(&minus));
        // the TIE at the centre: Laplacian(phi) = -2 a / sigma^2, so I - 1 = dz 2 a / (k sigma^2),
        // k = 2 pi n / lambda, dz the propagation distance
        let o = optics(1.0);
        let k = std::f64::consts::TAU * o.n_medium / o.wavelength_um;
        let tie = o.propagation_um() * 2.0 * a / (k * sigma * sigma);
        assert!((c(&plus) / tie - 1.0).abs() < 0.1, "{} vs TIE {tie}", c(&plus));
    }

    /// An absorbing object is dark in focus by its transmission (a large disc: the interior far from
    /// the edge has `I = |t|^2`).
    #[test]
    fn an_absorber_is_dark_by_its_transmission_in_focus() {
        let (n, s) = (128, 0.1);
        let mut t = vec![Complex64::new(1.0, 0.0); n * n];
        for j in 0..n {
            for i in 0..n {
                if ((i as f64 - 64.0) * s).hypot((j as f64 - 64.0) * s) < 4.0 {
                    t[j * n + i] = Complex64::new(0.9, 0.0);
                }
            }
        }
        let im = bright_field(&t, n, n, s, &optics(0.0));
        assert!((im[64 * n + 64] - 0.81).abs() < 0.01, "{}", im[64 * n + 64]);
    }

    /// The one-dimensional image equals the two-dimensional one of an object uniform along x.
    #[test]
    fn the_1d_image_is_the_2d_image_of_a_uniform_object() {
        let (nx, ny, s) = (32, 96, 0.1);
        let line: Vec<Complex64> = (0..ny).map(|j| if (30..60).contains(&j) { Complex64::from_polar(0.95, 1.1) } else { Complex64::new(1.0, 0.0) }).collect();
        let mut t = vec![Complex64::new(1.0, 0.0); nx * ny];
        for j in 0..ny {
            for i in 0..nx {
                t[j * nx + i] = line[j];
            }
        }
        let o = optics(1.2);
        let im2 = bright_field(&t, nx, ny, s, &o);
        let im1 = bright_field_1d(&line, s, &o);
        for j in 0..ny {
            assert!((im2[j * nx + 5] - im1[j]).abs() < 1e-10, "row {j}: {} vs {}", im2[j * nx + 5], im1[j]);
        }
    }
}
