//! Skalak strain energy on flat linear triangles (Krueger 2011 formulation), in two explicitly named conventions.
//!
//! Each triangle is a linear finite element: the deformation gradient
//! `F = X D^{-1}` (3 x 2) maps the reference edge vectors `D = [E1 E2]`
//! (2 x 2, in the reference triangle's own plane) to the current ones
//! `X = [x1 - x0, x2 - x0]` (3 x 2, um). With `C = F^T F` (right Cauchy-Green),
//! `I1 = tr C - 2 = l1^2 + l2^2 - 2`, `I2 = det C - 1 = l1^2 l2^2 - 1` and the
//! energy per reference area (N/m)
//!
//! `w = a (I1^2 + 2 I1 - 2 I2) + b I2^2`,
//!
//! the energy is `E = sum_t A0_t w_t` and the nodal forces are exactly
//! `F_i = -dE/dx_i`: `dE/dX = A0 2 F S D^{-T}` with
//! `S = dw/dC = w_1 I + w_2 adj(C)` (`w_k = dw/dI_k`, `adj(C) = det(C) C^{-1}`).
//! This is the same force as Krueger's explicit formula (Krueger, Varnik &
//! Raabe, Comput. Math. Appl. 61, 3485 (2011), appendix), written through `F`;
//! it is invariant under rigid motions, so total force and torque vanish.
//!
//! Conventions ([`SkalakConvention`]):
//! - `Krueger`: `w = kS/12 (I1^2 + 2 I1 - 2 I2) + kA/12 I2^2` (`a = kS/12`,
//!   `b = kA/12`), used by Krueger and by the paper's group. Small-strain shear
//!   modulus `kS/3`, area (dilatation) modulus `(kS + 2 kA)/3`.
//! - `BarthesBiesel`: `w = Gs/4 (I1^2 + 2 I1 - 2 I2 + C I2^2)` (Barthes-Biesel,
//!   Diaz & Dhenin, JFM 460, 211 (2002)); shear modulus `Gs`, area modulus
//!   `Gs (1 + 2 C)`.
//!
//! - `NeoHookean` (not a Skalak form; for the validation against Ramanujan &
//!   Pozrikidis 1998): `w = Gs/2 (I1 + 1/(I2 + 1) - 1)` (the neo-Hookean
//!   membrane of Barthes-Biesel, Diaz & Dhenin 2002), shear modulus
//!   `Gs`, area modulus `3 Gs` (the same small-strain moduli as Skalak with
//!   `C = 1`; it softens under strain where Skalak hardens).
//!
//! In general the small-strain moduli of `w` are `mu = 2 w_1` (shear) and
//! `K = 2 (w_2 + 2 w_11 + 2 w_22)` at `I1 = I2 = 0` (area: `w = K/2 (dA/A)^2`
//! for an isotropic stretch); for the Skalak forms `mu = 4 a`, `K = 4 a + 8 b`.

use nalgebra::{Matrix2, Matrix3x2, SMatrix, Vector3};

use super::error::{check_modulus, MembraneError};
use super::linear::LinearisedLaw;
use super::{MembraneLaw, UM};
use crate::mesh::Mesh;

/// Which of the two published forms of the Skalak law the parameters refer to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkalakConvention {
    /// `w = kS/12 (I1^2 + 2 I1 - 2 I2) + kA/12 I2^2` (Krueger 2011; the paper's group).
    Krueger,
    /// `w = Gs/4 (I1^2 + 2 I1 - 2 I2 + C I2^2)` (Barthes-Biesel).
    BarthesBiesel,
    /// Neo-Hookean membrane `w = Gs/2 (I1 + 1/(I2 + 1) - 1)` (area modulus `3 Gs`).
    NeoHookean,
}

impl std::str::FromStr for SkalakConvention {
    type Err = MembraneError;
    /// `krueger` or `barthes-biesel`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "krueger" => Ok(SkalakConvention::Krueger),
            "barthes-biesel" => Ok(SkalakConvention::BarthesBiesel),
            "neo-hookean" => Ok(SkalakConvention::NeoHookean),
            _ => Err(MembraneError::UnknownName {
                what: "Skalak convention",
                name: s.to_string(),
                expected: "krueger, barthes-biesel, neo-hookean",
            }),
        }
    }
}

/// Reference geometry of one triangle.
#[derive(Debug, Clone, Copy)]
struct ReferenceTriangle {
    /// `D^{-1}` (1/um).
    d_inv: Matrix2<f64>,
    /// Reference area `A0` (um^2).
    area: f64,
}

/// Skalak membrane with a stress-free reference mesh (same connectivity as
/// the meshes it is evaluated on; the paper's reference is the discocyte).
#[derive(Debug, Clone)]
pub struct Skalak {
    convention: SkalakConvention,
    /// Coefficient `a` of `I1^2 + 2 I1 - 2 I2` (N/m).
    a: f64,
    /// Coefficient `b` of `I2^2` (N/m).
    b: f64,
    reference: Vec<ReferenceTriangle>,
}

/// `adj(C)` of a 2 x 2 matrix: `[[c11, -c01], [-c10, c00]]` (= det(C) C^{-1}).
#[inline]
fn adj(c: &Matrix2<f64>) -> Matrix2<f64> {
    Matrix2::new(c[(1, 1)], -c[(0, 1)], -c[(1, 0)], c[(0, 0)])
}

impl Skalak {
    /// A Skalak law with reference state `reference` (positions in um).
    ///
    /// Parameters by convention (N/m):
    /// - `Krueger`: `shear_modulus_n_m = kS`, `area_modulus_n_m = kA` as in the
    ///   formula (so the paper's `kappa_S = 5e-6`, `kappa_A = 100 kappa_S` go in
    ///   unchanged); true small-strain moduli are `kS/3` and `(kS + 2 kA)/3`.
    /// - `BarthesBiesel`: `shear_modulus_n_m = Gs`, `area_modulus_n_m = Gs (1 + 2 C)`
    ///   (the true area modulus), i.e. `C = (area / Gs - 1) / 2`; use
    ///   [`Skalak::barthes_biesel`] to give `C` directly.
    /// - `NeoHookean`: `shear_modulus_n_m = Gs`; the area modulus is fixed at
    ///   `3 Gs` and must be given as such (else a parameter error); or use
    ///   [`Skalak::neo_hookean`].
    pub fn new(
        reference: &Mesh,
        convention: SkalakConvention,
        shear_modulus_n_m: f64,
        area_modulus_n_m: f64,
    ) -> Result<Skalak, MembraneError> {
        let shear = check_modulus("Skalak", "shear modulus", shear_modulus_n_m, true)?;
        let area = check_modulus("Skalak", "area modulus", area_modulus_n_m, false)?;
        let (a, b) = match convention {
            SkalakConvention::Krueger => (shear / 12.0, area / 12.0),
            SkalakConvention::BarthesBiesel => {
                let c = (area / shear - 1.0) / 2.0;
                if c < 0.0 {
                    return Err(MembraneError::Parameter {
                        law: "Skalak (Barthes-Biesel)",
                        name: "area modulus",
                        value: area,
                        requirement: ">= the shear modulus (C >= 0)",
                    });
                }
                (shear / 4.0, shear * c / 4.0)
            }
            SkalakConvention::NeoHookean => {
                if (area - 3.0 * shear).abs() > 1e-12 * area {
                    return Err(MembraneError::Parameter {
                        law: "neo-Hookean",
                        name: "area modulus",
                        value: area,
                        requirement: "= 3 x the shear modulus (fixed by the neo-Hookean law)",
                    });
                }
                (shear / 4.0, 0.0)
            }
        };
        Self::from_coefficients(reference, convention, a, b)
    }

    /// Barthes-Biesel form with its own parameters: `Gs` (N/m) and the
    /// dimensionless `C >= 0`.
    pub fn barthes_biesel(reference: &Mesh, gs_n_m: f64, c: f64) -> Result<Skalak, MembraneError> {
        let gs = check_modulus("Skalak (Barthes-Biesel)", "Gs", gs_n_m, true)?;
        let c = check_modulus("Skalak (Barthes-Biesel)", "C", c, false)?;
        Self::from_coefficients(
            reference,
            SkalakConvention::BarthesBiesel,
            gs / 4.0,
            gs * c / 4.0,
        )
    }

    /// Neo-Hookean membrane with shear modulus `Gs` (N/m): `w = Gs/2 (I1 + 1/(I2 + 1) - 1)`.
    pub fn neo_hookean(reference: &Mesh, gs_n_m: f64) -> Result<Skalak, MembraneError> {
        let gs = check_modulus("neo-Hookean", "Gs", gs_n_m, true)?;
        Self::from_coefficients(reference, SkalakConvention::NeoHookean, gs / 4.0, 0.0)
    }

    fn from_coefficients(
        reference: &Mesh,
        convention: SkalakConvention,
        a: f64,
        b: f64,
    ) -> Result<Skalak, MembraneError> {
        let mut tris = Vec::with_capacity(reference.triangles.len());
        for t in 0..reference.triangles.len() {
            let [x0, x1, x2] = reference.corners(t);
            let (e1, e2) = (x1 - x0, x2 - x0);
            let l1 = e1.norm();
            let n = e1.cross(&e2);
            let area = 0.5 * n.norm();
            if area.is_nan() || area <= 0.0 || !area.is_finite() {
                return Err(MembraneError::DegenerateReference {
                    law: "Skalak",
                    triangle: t,
                    area,
                });
            }
            let u = e1 / l1;
            let v = n.normalize().cross(&u);
            let d = Matrix2::new(l1, e2.dot(&u), 0.0, e2.dot(&v));
            let d_inv = d.try_inverse().ok_or(MembraneError::DegenerateReference {
                law: "Skalak",
                triangle: t,
                area,
            })?;
            tris.push(ReferenceTriangle { d_inv, area });
        }
        Ok(Skalak {
            convention,
            a,
            b,
            reference: tris,
        })
    }

    /// The convention the parameters were given in.
    pub fn convention(&self) -> SkalakConvention {
        self.convention
    }

    /// Small-strain (shear, area) moduli (N/m): `(4 a, 4 a + 8 b)` for the
    /// Skalak forms, `(Gs, 3 Gs)` for the neo-Hookean law (`Gs = 4 a`).
    pub fn small_strain_moduli(&self) -> (f64, f64) {
        match self.convention {
            SkalakConvention::NeoHookean => (4.0 * self.a, 12.0 * self.a),
            _ => (4.0 * self.a, 4.0 * self.a + 8.0 * self.b),
        }
    }

    /// `w, w_1, w_2, w_11, w_22` at `(I1, I2)` (N/m; `w_12 = 0` for every form).
    /// Neo-Hookean with `Gs = 4 a`: `w = 2 a (I1 + 1/(I2 + 1) - 1)`.
    #[inline]
    fn w(&self, i1: f64, i2: f64) -> (f64, f64, f64, f64, f64) {
        if self.convention == SkalakConvention::NeoHookean {
            let j = 1.0 / (i2 + 1.0);
            let g2 = 2.0 * self.a; // Gs / 2
            return (g2 * (i1 + j - 1.0), g2, -g2 * j * j, 0.0, 2.0 * g2 * j * j * j);
        }
        let w = self.a * (i1 * i1 + 2.0 * i1 - 2.0 * i2) + self.b * i2 * i2;
        (
            w,
            2.0 * self.a * (i1 + 1.0),
            -2.0 * self.a + 2.0 * self.b * i2,
            2.0 * self.a,
            2.0 * self.b,
        )
    }

    /// Edge matrix `X = [x1 - x0, x2 - x0]` of triangle `t` (um).
    #[inline]
    fn edges(mesh: &Mesh, t: usize) -> Matrix3x2<f64> {
        let [x0, x1, x2] = mesh.corners(t);
        Matrix3x2::from_columns(&[x1 - x0, x2 - x0])
    }

    /// `dE_t/dX` (3 x 2, N/m um) of triangle `t`.
    #[inline]
    fn triangle_gradient(&self, x: &Matrix3x2<f64>, r: &ReferenceTriangle) -> Matrix3x2<f64> {
        let f = x * r.d_inv;
        let c = f.transpose() * f;
        let (_, w1, w2, _, _) = self.w(c.trace() - 2.0, c.determinant() - 1.0);
        let s = Matrix2::identity() * w1 + adj(&c) * w2;
        f * s * r.d_inv.transpose() * (2.0 * r.area)
    }

    /// Directional derivative of `dE_t/dX` along the edge change `dX` (N/m, for `dX` in um).
    #[inline]
    fn triangle_gradient_jvp(
        &self,
        x: &Matrix3x2<f64>,
        dx: &Matrix3x2<f64>,
        r: &ReferenceTriangle,
    ) -> Matrix3x2<f64> {
        let f = x * r.d_inv;
        let df = dx * r.d_inv;
        let c = f.transpose() * f;
        let dc = df.transpose() * f + f.transpose() * df;
        let (_, w1, w2, w11, w22) = self.w(c.trace() - 2.0, c.determinant() - 1.0);
        let ac = adj(&c);
        let di1 = dc.trace();
        let di2 = (ac * dc).trace();
        let s = Matrix2::identity() * w1 + ac * w2;
        let ds = Matrix2::identity() * (w11 * di1) + ac * (w22 * di2) + adj(&dc) * w2;
        (df * s + f * ds) * r.d_inv.transpose() * (2.0 * r.area)
    }

    /// Nodal forces `-dE/dx_i` in units of N/m um (= 1e-6 N).
    fn add_scaled_nodal_forces(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        debug_assert_eq!(
            mesh.triangles.len(),
            self.reference.len(),
            "mesh and reference connectivity differ"
        );
        for (t, (tri, r)) in mesh.triangles.iter().zip(&self.reference).enumerate() {
            let g = self.triangle_gradient(&Self::edges(mesh, t), r);
            let (g1, g2): (Vector3<f64>, Vector3<f64>) = (g.column(0).into(), g.column(1).into());
            out[tri[0]] += g1 + g2;
            out[tri[1]] -= g1;
            out[tri[2]] -= g2;
        }
    }
}

impl MembraneLaw for Skalak {
    fn assembled_stiffness(&self, mesh: &Mesh) -> Option<Vec<(usize, usize, f64)>> {
        Some(self.stiffness_triplets(mesh))
    }
    /// `Df_i = -dE/dx_i / A_i` (Pa): nodal force over the (mixed Voronoi)
    /// vertex area, then [`super::remove_net_force_and_torque`].
    fn add_force_density(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        let mut f = vec![Vector3::zeros(); mesh.vertices.len()];
        self.add_scaled_nodal_forces(mesh, &mut f);
        // (N/m um) / um^2 = N/m / um = 1e6 Pa
        for (fi, a) in f.iter_mut().zip(mesh.vertex_areas()) {
            *fi *= 1.0 / (a * UM);
        }
        super::remove_net_force_and_torque(mesh, &mut f);
        for (o, fi) in out.iter_mut().zip(&f) {
            *o += fi;
        }
    }

    /// `E = sum_t A0_t w(I1, I2)` (J).
    fn energy(&self, mesh: &Mesh) -> f64 {
        let mut e = 0.0;
        for (t, r) in self.reference.iter().enumerate() {
            let f = Self::edges(mesh, t) * r.d_inv;
            let c = f.transpose() * f;
            e += r.area * self.w(c.trace() - 2.0, c.determinant() - 1.0).0;
        }
        e * UM * UM
    }

    fn name(&self) -> &str {
        match self.convention {
            SkalakConvention::Krueger => "skalak-krueger",
            SkalakConvention::BarthesBiesel => "skalak-barthes-biesel",
            SkalakConvention::NeoHookean => "neo-hookean",
        }
    }
}

impl LinearisedLaw for Skalak {
    fn add_nodal_forces(&self, mesh: &Mesh, out: &mut [Vector3<f64>]) {
        let mut f = vec![Vector3::zeros(); mesh.vertices.len()];
        self.add_scaled_nodal_forces(mesh, &mut f);
        for (o, fi) in out.iter_mut().zip(&f) {
            *o += fi * UM;
        }
    }

    fn triangle_stiffness(&self, mesh: &Mesh, t: usize) -> SMatrix<f64, 9, 9> {
        let x = Self::edges(mesh, t);
        let r = &self.reference[t];
        let mut k = SMatrix::<f64, 9, 9>::zeros();
        for col in 0..9 {
            let (vertex, comp) = (col / 3, col % 3);
            // dX for a unit displacement of `vertex` along `comp`
            let mut dx = Matrix3x2::zeros();
            match vertex {
                0 => {
                    dx[(comp, 0)] = -1.0;
                    dx[(comp, 1)] = -1.0;
                }
                1 => dx[(comp, 0)] = 1.0,
                _ => dx[(comp, 1)] = 1.0,
            }
            let dg = self.triangle_gradient_jvp(&x, &dx, r);
            let (g1, g2): (Vector3<f64>, Vector3<f64>) = (dg.column(0).into(), dg.column(1).into());
            // dF = -dg, in N/um: (N/m um)/um * 1e-6
            let cols = [g1 + g2, -g1, -g2];
            for (a, v) in cols.iter().enumerate() {
                for i in 0..3 {
                    k[(3 * a + i, col)] = v[i] * UM;
                }
            }
        }
        k
    }

    fn add_nodal_force_jvp(&self, mesh: &Mesh, v: &[Vector3<f64>], out: &mut [Vector3<f64>]) {
        for (t, (tri, r)) in mesh.triangles.iter().zip(&self.reference).enumerate() {
            let dx = Matrix3x2::from_columns(&[v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]]]);
            let dg = self.triangle_gradient_jvp(&Self::edges(mesh, t), &dx, r);
            let (g1, g2): (Vector3<f64>, Vector3<f64>) = (dg.column(0).into(), dg.column(1).into());
            out[tri[0]] += (g1 + g2) * UM;
            out[tri[1]] -= g1 * UM;
            out[tri[2]] -= g2 * UM;
        }
    }
}
