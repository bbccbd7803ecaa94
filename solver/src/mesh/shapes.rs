//! Analytic axisymmetric surfaces (sphere, spheroid, Evans-Fung discocyte): mapping from the unit sphere, their meshes, and exact curvatures.
//!
//! Each surface is a profile `(r(t), z(t))`, `t` in `[0, pi]` the polar angle of
//! the unit-sphere point it comes from, rotated about the z axis. Curvatures
//! follow from the profile by exact differentiation: `r(t)` and `z(t)` are
//! evaluated as truncated Taylor series (`Jet`, forward-mode automatic
//! differentiation to 6th order, written here because none of the workspace
//! crates provides higher-order derivatives), so the reference values of `H`,
//! `K` and `Lap_s H` used by the convergence tests are exact to rounding.
//!
//! Sign convention (used by the whole `membrane` module): `n` is the outward
//! normal, `H = (kappa_1 + kappa_2) / 2 = div_s(n) / 2` is positive on a sphere
//! (`H = 1/R`), `K = kappa_1 kappa_2`.

use std::f64::consts::PI;

use nalgebra::Vector3;

use super::generate::octahedron_sphere;
use super::Mesh;

/// Evans-Fung parameters (Evans & Fung 1972, as used in the paper): `R0` in um.
pub const EVANS_FUNG_R0_UM: f64 = 3.91;
/// Evans-Fung `C0` (um).
pub const EVANS_FUNG_C0_UM: f64 = 0.81;
/// Evans-Fung `C2` (um).
pub const EVANS_FUNG_C2_UM: f64 = 7.83;
/// Evans-Fung `C4` (um).
pub const EVANS_FUNG_C4_UM: f64 = -4.39;
/// Large radius of the paper's cell, `R_RBC = 4 um`.
pub const R_RBC_UM: f64 = 4.0;

/// An axisymmetric closed surface (axis along z, centred at the origin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AxisymmetricShape {
    /// Sphere of radius `radius` (um).
    Sphere { radius: f64 },
    /// Spheroid with equatorial semi-axis `a` and polar semi-axis `c` (um).
    Spheroid { a: f64, c: f64 },
    /// Evans-Fung discocyte `z = +-1/2 sqrt(1 - r^2/R0^2) (C0 + C2 r^2/R0^2 + C4 r^4/R0^4)`
    /// with all lengths multiplied by `scale` (`scale = 4 / 3.91` for `R_RBC = 4 um`).
    /// Profile: `r = scale R0 sin t`, `z = scale cos t (C0 + C2 sin^2 t + C4 sin^4 t) / 2`
    /// (the substitution `r / R0 = sin t` turns the square root into `|cos t|`
    /// and makes the profile analytic across the rim `t = pi/2`).
    EvansFung { scale: f64 },
}

/// Exact local geometry of an axisymmetric surface at one profile parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curvatures {
    /// Mean curvature `H = (k1 + k2) / 2` (1/um), positive on a sphere.
    pub mean: f64,
    /// Gaussian curvature `K = k1 k2` (1/um^2).
    pub gaussian: f64,
    /// Surface Laplacian of the mean curvature `Lap_s H` (1/um^3).
    pub laplacian_mean: f64,
    /// Outward unit normal in the meridian plane: `(n_r, n_z)`.
    pub normal_rz: [f64; 2],
}

impl AxisymmetricShape {
    /// The paper's discocyte: Evans-Fung scaled by `4 / 3.91` (`R_RBC = 4 um`).
    pub fn evans_fung_rbc() -> Self {
        AxisymmetricShape::EvansFung {
            scale: R_RBC_UM / EVANS_FUNG_R0_UM,
        }
    }

    /// Profile as Taylor jets in `t` at `t0`.
    fn profile(&self, t0: f64) -> (Jet, Jet) {
        let s = Jet::sin(t0);
        let c = Jet::cos(t0);
        match *self {
            AxisymmetricShape::Sphere { radius } => (s.scale(radius), c.scale(radius)),
            AxisymmetricShape::Spheroid { a, c: cz } => (s.scale(a), c.scale(cz)),
            AxisymmetricShape::EvansFung { scale } => {
                let s2 = s.mul(&s);
                let poly = s2
                    .scale(EVANS_FUNG_C2_UM)
                    .add(&s2.mul(&s2).scale(EVANS_FUNG_C4_UM))
                    .add_scalar(EVANS_FUNG_C0_UM);
                (
                    s.scale(scale * EVANS_FUNG_R0_UM),
                    c.mul(&poly).scale(0.5 * scale),
                )
            }
        }
    }

    /// `(r(t), z(t))` in um.
    pub fn profile_point(&self, t: f64) -> [f64; 2] {
        let (r, z) = self.profile(t);
        [r.0[0], z.0[0]]
    }

    /// Maps points of the unit sphere onto the surface, keeping the azimuth
    /// and sending the polar angle `theta` to the profile parameter `t` by
    /// `placement` (see [`Placement`] for the trade-off).
    pub fn meridian_map(&self, placement: Placement) -> MeridianMap {
        let cumulative = match placement {
            Placement::Polar => Vec::new(),
            Placement::ArcLength => {
                // cumulative arc length on a fine midpoint grid (relative error ~1e-9)
                let n = 20_000;
                let dt = PI / n as f64;
                let mut cumulative = Vec::with_capacity(n + 1);
                cumulative.push(0.0);
                let mut s = 0.0;
                for k in 0..n {
                    s += self.speed((k as f64 + 0.5) * dt) * dt;
                    cumulative.push(s);
                }
                cumulative
            }
        };
        MeridianMap {
            shape: *self,
            cumulative,
        }
    }

    /// Octahedron-subdivision mesh of this surface (`8 * 4^level` triangles)
    /// with the default [`Placement::Polar`].
    pub fn mesh(&self, level: usize) -> Mesh {
        self.mesh_with(level, Placement::Polar)
    }

    /// Octahedron-subdivision mesh of this surface with the given vertex placement.
    pub fn mesh_with(&self, level: usize, placement: Placement) -> Mesh {
        let map = self.meridian_map(placement);
        let mut mesh = octahedron_sphere(level);
        for v in &mut mesh.vertices {
            *v = map.map(v);
        }
        mesh
    }

    /// Profile parameter `t` of a surface point (inverse of the map for points
    /// on this surface): `t = atan2(sin t, cos t)` with `sin t = r / r_eq` and
    /// `cos t = z / g(sin^2 t)`, where `z(t) = g(sin^2 t) cos t` for all three
    /// shapes (`g > 0`), which stays well conditioned at the rim.
    pub fn parameter_of(&self, x: &Vector3<f64>) -> f64 {
        let [r_eq, _] = self.profile_point(PI / 2.0);
        let sin_t = ((x.x * x.x + x.y * x.y).sqrt() / r_eq).min(1.0);
        let g = match *self {
            AxisymmetricShape::Sphere { radius } => radius,
            AxisymmetricShape::Spheroid { c, .. } => c,
            AxisymmetricShape::EvansFung { scale } => {
                let s2 = sin_t * sin_t;
                0.5 * scale
                    * (EVANS_FUNG_C0_UM + EVANS_FUNG_C2_UM * s2 + EVANS_FUNG_C4_UM * s2 * s2)
            }
        };
        sin_t.atan2(x.z / g)
    }

    /// Exact curvatures at profile parameter `t`. Principal curvatures of the
    /// surface of revolution (do Carmo, "Differential geometry of curves and
    /// surfaces", 3-3): meridian `k1 = (z' r'' - r' z'') / s'^3`, parallel
    /// `k2 = -z' / (r s')`, `s' = sqrt(r'^2 + z'^2)`; for an axisymmetric
    /// function `Lap_s H = (1 / (r s')) d/dt (r H' / s')`.
    /// At the poles (`r = 0`, `t = 0` or `pi`) the 0/0 quotients are resolved
    /// exactly by cancelling the common factor `(t - t_pole)` of the Taylor
    /// series (l'Hopital), so the values are exact there too.
    pub fn curvatures(&self, t: f64) -> Curvatures {
        let pole = if t.abs() < 1e-12 {
            Some(0.0)
        } else if (t - PI).abs() < 1e-12 {
            Some(PI)
        } else {
            None
        };
        let t0 = pole.unwrap_or(t);
        // a / b, cancelling a common root at the pole
        let quotient = |a: &Jet, b: &Jet| {
            if pole.is_some() {
                a.shift().div(&b.shift())
            } else {
                a.div(b)
            }
        };
        let (r, z) = self.profile(t0);
        let (r1, z1) = (r.derivative(), z.derivative());
        let (r2, z2) = (r1.derivative(), z1.derivative());
        let speed = r1.mul(&r1).add(&z1.mul(&z1)).sqrt();
        let k1 = z1
            .mul(&r2)
            .sub(&r1.mul(&z2))
            .div(&speed.mul(&speed).mul(&speed));
        let k2 = quotient(&z1.scale(-1.0), &r).div(&speed);
        let h = k1.add(&k2).scale(0.5);
        let q = r.mul(&h.derivative()).div(&speed);
        let lap = quotient(&q.derivative(), &r).div(&speed).0[0];
        Curvatures {
            mean: h.0[0],
            gaussian: k1.0[0] * k2.0[0],
            laplacian_mean: lap,
            normal_rz: [-z1.0[0] / speed.0[0], r1.0[0] / speed.0[0]],
        }
    }

    /// Exact curvatures at a surface point (through [`Self::parameter_of`]), with
    /// the outward normal as a 3D vector.
    pub fn curvatures_at(&self, x: &Vector3<f64>) -> (Curvatures, Vector3<f64>) {
        let c = self.curvatures(self.parameter_of(x));
        let rxy = (x.x * x.x + x.y * x.y).sqrt();
        let (cp, sp) = if rxy > 0.0 {
            (x.x / rxy, x.y / rxy)
        } else {
            (1.0, 0.0)
        };
        let n = Vector3::new(c.normal_rz[0] * cp, c.normal_rz[0] * sp, c.normal_rz[1]);
        (c, n)
    }

    /// Arc-length element of the profile `s'(t) = sqrt(r'^2 + z'^2)` (um per
    /// radian); the surface element is `dA = r s' dt dphi`.
    pub fn speed(&self, t: f64) -> f64 {
        let (r, z) = self.profile(t);
        let (r1, z1) = (r.derivative(), z.derivative());
        (r1.0[0].powi(2) + z1.0[0].powi(2)).sqrt()
    }

    /// Exact area (um^2) `int_0^pi 2 pi r s' dt`, by composite Gauss-Legendre
    /// (the integrand is analytic; 400 panels of 4 points give ~1e-14).
    pub fn area(&self) -> f64 {
        integrate(0.0, PI, |t| {
            let (r, z) = self.profile(t);
            let (r1, z1) = (r.derivative(), z.derivative());
            2.0 * PI * r.0[0] * (r1.0[0].powi(2) + z1.0[0].powi(2)).sqrt()
        })
    }

    /// Exact enclosed volume (um^3) `int_0^pi pi r^2 (-z') dt`.
    pub fn volume(&self) -> f64 {
        integrate(0.0, PI, |t| {
            let (r, z) = self.profile(t);
            -PI * r.0[0].powi(2) * z.derivative().0[0]
        })
    }
}

/// Sphere of radius `radius_um` (um), `8 * 4^level` triangles.
pub fn sphere(level: usize, radius_um: f64) -> Mesh {
    AxisymmetricShape::Sphere { radius: radius_um }.mesh(level)
}

/// Spheroid `(x^2 + y^2) / a^2 + z^2 / c^2 = 1` (semi-axes in um; axis along z),
/// `8 * 4^level` triangles: the unit-sphere vertex `p` maps to
/// `(a p_x, a p_y, c p_z)` ([`Placement::Polar`]).
pub fn spheroid(level: usize, a_um: f64, c_um: f64) -> Mesh {
    AxisymmetricShape::Spheroid { a: a_um, c: c_um }.mesh(level)
}

/// Evans-Fung discocyte (Evans & Fung 1972) scaled to `R_RBC = 4 um`
/// (area 140.3 um^2, volume 100.7 um^3), symmetry axis along z, centroid at
/// the origin, `8 * 4^level` triangles (level 4: the paper's 2048).
/// See [`AxisymmetricShape::EvansFung`] for the surface and
/// [`Placement`] for the placement of the vertices
/// (default `Polar`; `AxisymmetricShape::evans_fung_rbc().mesh_with(level,
/// Placement::ArcLength)` gives better-shaped triangles).
/// Place it in the channel with [`Mesh::transformed`].
pub fn discocyte(level: usize) -> Mesh {
    AxisymmetricShape::evans_fung_rbc().mesh(level)
}

/// Where the vertices of the subdivided octahedron go along the meridian.
///
/// Measured on the discocyte at 2048 triangles (tests `mesh_generate`,
/// `membrane_bending`): `Polar` has smallest angle 28.7 deg, longest/shortest
/// edge 2.85, and bending-force errors (quartic fit, max/L2) 0.19/0.14;
/// `ArcLength` has 38.2 deg, 1.95, and 0.35/0.21. `Polar` crowds vertices at
/// the rim, where the curvature is highest, which helps the curvature
/// estimates more than the better triangles of `ArcLength` do.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Placement {
    /// `t = theta`: the unit-sphere point `p` goes to `(r_eq p_x, r_eq p_y, z(acos p_z))`
    /// (for the Evans-Fung surface: its formula evaluated at `r = R p_rho`).
    #[default]
    Polar,
    /// Equal fractions of meridian arc length: `s(t) / s(pi) = theta / pi`.
    ArcLength,
}

/// The map of [`AxisymmetricShape::meridian_map`] from the unit sphere to the surface.
#[derive(Debug, Clone)]
pub struct MeridianMap {
    shape: AxisymmetricShape,
    /// For [`Placement::ArcLength`]: arc length from the north pole at
    /// `t = k pi / n` (um); empty for [`Placement::Polar`].
    cumulative: Vec<f64>,
}

impl MeridianMap {
    /// Profile parameter `t` at polar angle `theta` (for arc-length
    /// placement by linear interpolation in the table; exactly symmetric:
    /// `t(pi - theta) = pi - t(theta)`).
    pub fn parameter(&self, theta: f64) -> f64 {
        if self.cumulative.is_empty() {
            return theta;
        }
        if theta > PI / 2.0 {
            return PI - self.parameter(PI - theta);
        }
        let n = self.cumulative.len() - 1;
        let target = theta / PI * self.cumulative[n];
        let k = self.cumulative.partition_point(|&c| c < target).clamp(1, n);
        let frac =
            (target - self.cumulative[k - 1]) / (self.cumulative[k] - self.cumulative[k - 1]);
        (k as f64 - 1.0 + frac) * PI / n as f64
    }

    /// Surface point of the unit-sphere point `p` (um).
    pub fn map(&self, p: &Vector3<f64>) -> Vector3<f64> {
        if self.cumulative.is_empty() {
            // r(t) = r_eq sin t for all shapes: no trigonometry needed in the plane
            let [r_eq, _] = self.shape.profile_point(PI / 2.0);
            let [_, z] = self.shape.profile_point(p.z.clamp(-1.0, 1.0).acos());
            return Vector3::new(r_eq * p.x, r_eq * p.y, z);
        }
        let t = self.parameter(p.z.clamp(-1.0, 1.0).acos());
        let [r, z] = self.shape.profile_point(t);
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        if rho > 0.0 {
            Vector3::new(r * p.x / rho, r * p.y / rho, z)
        } else {
            Vector3::new(0.0, 0.0, z)
        }
    }
}

/// Composite 4-point Gauss-Legendre rule on 400 panels.
fn integrate(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    const X: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    let n = 400;
    let h = (b - a) / n as f64;
    let mut sum = 0.0;
    for i in 0..n {
        let mid = a + (i as f64 + 0.5) * h;
        for k in 0..4 {
            sum += W[k] * f(mid + 0.5 * h * X[k]);
        }
    }
    sum * 0.5 * h
}

/// Order of the Taylor jets (derivatives up to 6 are carried: 4 are needed for `Lap_s H`).
const ORDER: usize = 7;

/// Truncated Taylor series `sum_k a_k h^k` of a function at a point
/// (`a_k = f^(k)(t0) / k!`): forward-mode automatic differentiation of any order.
#[derive(Debug, Clone, Copy)]
struct Jet([f64; ORDER]);

impl Jet {
    fn sin(t0: f64) -> Jet {
        // sin(t0 + h) = sum_k sin(t0 + k pi / 2) h^k / k!
        let mut a = [0.0; ORDER];
        let mut fact = 1.0;
        for (k, ak) in a.iter_mut().enumerate() {
            if k > 0 {
                fact *= k as f64;
            }
            *ak = (t0 + k as f64 * PI / 2.0).sin() / fact;
        }
        Jet(a)
    }
    fn cos(t0: f64) -> Jet {
        Jet::sin(t0 + PI / 2.0)
    }
    fn scale(&self, s: f64) -> Jet {
        Jet(self.0.map(|a| a * s))
    }
    fn add_scalar(&self, s: f64) -> Jet {
        let mut a = self.0;
        a[0] += s;
        Jet(a)
    }
    fn add(&self, o: &Jet) -> Jet {
        Jet(std::array::from_fn(|k| self.0[k] + o.0[k]))
    }
    fn sub(&self, o: &Jet) -> Jet {
        Jet(std::array::from_fn(|k| self.0[k] - o.0[k]))
    }
    fn mul(&self, o: &Jet) -> Jet {
        Jet(std::array::from_fn(|k| {
            (0..=k).map(|j| self.0[j] * o.0[k - j]).sum()
        }))
    }
    fn div(&self, o: &Jet) -> Jet {
        let mut q = [0.0; ORDER];
        for k in 0..ORDER {
            let s: f64 = (1..=k).map(|j| o.0[j] * q[k - j]).sum();
            q[k] = (self.0[k] - s) / o.0[0];
        }
        Jet(q)
    }
    fn sqrt(&self) -> Jet {
        let mut s = [0.0; ORDER];
        s[0] = self.0[0].sqrt();
        for k in 1..ORDER {
            let c: f64 = (1..k).map(|j| s[j] * s[k - j]).sum();
            s[k] = (self.0[k] - c) / (2.0 * s[0]);
        }
        Jet(s)
    }
    /// Divides by `h` a series whose constant term vanishes (one order is lost).
    fn shift(&self) -> Jet {
        Jet(std::array::from_fn(|k| {
            if k + 1 < ORDER {
                self.0[k + 1]
            } else {
                0.0
            }
        }))
    }
    /// Derivative (the highest coefficient becomes unknown and is set to 0:
    /// each derivative costs one order of accuracy, tracked by the callers).
    fn derivative(&self) -> Jet {
        Jet(std::array::from_fn(|k| {
            if k + 1 < ORDER {
                (k + 1) as f64 * self.0[k + 1]
            } else {
                0.0
            }
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_curvatures_are_exact() {
        let s = AxisymmetricShape::Sphere { radius: 2.0 };
        for &t in &[0.0, 0.3, 1.2, PI / 2.0, 2.5, PI] {
            let c = s.curvatures(t);
            assert!((c.mean - 0.5).abs() < 1e-12, "{t} {c:?}");
            assert!((c.gaussian - 0.25).abs() < 1e-12);
            assert!(c.laplacian_mean.abs() < 1e-12, "{t} {c:?}");
        }
        assert!((s.area() - 16.0 * PI).abs() < 1e-10);
        assert!((s.volume() - 32.0 * PI / 3.0).abs() < 1e-10);
    }

    #[test]
    fn spheroid_curvatures_match_closed_form() {
        // Spheroid x = a sin t, z = c cos t: k1 = a c / D^3, k2 = c / (a D),
        // D = sqrt(a^2 cos^2 t + c^2 sin^2 t) (meridian ellipse and parallel).
        let (a, c) = (2.0, 1.0);
        let s = AxisymmetricShape::Spheroid { a, c };
        for &t in &[0.2f64, 0.7, 1.3, 2.0] {
            let d = (a * a * t.cos().powi(2) + c * c * t.sin().powi(2)).sqrt();
            let (k1, k2) = (a * c / d.powi(3), c / (a * d));
            let cv = s.curvatures(t);
            assert!((cv.mean - 0.5 * (k1 + k2)).abs() < 1e-12);
            assert!((cv.gaussian - k1 * k2).abs() < 1e-12);
            // Lap_s H = (1/(r s')) d/dt (r H_t / s') by central differences of
            // the closed-form H(t) (step 2.5e-4: truncation ~1e-6 relative, measured)
            let hcl = |t: f64| {
                let d = (a * a * t.cos().powi(2) + c * c * t.sin().powi(2)).sqrt();
                0.5 * (a * c / d.powi(3) + c / (a * d))
            };
            let sp = |t: f64| (a * a * t.cos().powi(2) + c * c * t.sin().powi(2)).sqrt();
            let e = 2.5e-4;
            let flux = |t: f64| a * t.sin() * (hcl(t + e / 2.0) - hcl(t - e / 2.0)) / e / sp(t);
            let lap = (flux(t + e / 2.0) - flux(t - e / 2.0)) / e / (a * t.sin() * sp(t));
            assert!(
                (cv.laplacian_mean - lap).abs() < 1e-5 * lap.abs().max(0.1),
                "{} {lap}",
                cv.laplacian_mean
            );
        }
        // poles: k1 = k2 = c / a^2; Lap_s H by a finite-difference cross-check
        // of the regular formula near the pole (continuity of the 0/0 limit)
        let p = s.curvatures(0.0);
        assert!(
            (p.mean - c / (a * a)).abs() < 1e-12
                && (p.gaussian - (c / (a * a)).powi(2)).abs() < 1e-12
        );
        let near = s.curvatures(1e-2);
        assert!(
            (near.laplacian_mean - p.laplacian_mean).abs() < 1e-3 * p.laplacian_mean.abs(),
            "{near:?} {p:?}"
        );
        let q = s.curvatures(PI);
        assert!((q.laplacian_mean - p.laplacian_mean).abs() < 1e-12);
    }
}
