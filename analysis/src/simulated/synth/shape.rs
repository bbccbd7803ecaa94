//! Projected outlines of synthetic cells (croissant, slipper, irregular) as polygons in um, centroid at the origin.
//!
//! Local frame: `x` along the flow (+x downstream), `y` across the channel,
//! positive towards increasing image rows. Every polygon is shifted so that
//! its area centroid (shoelace formula) is exactly at the origin; the truth
//! of a synthetic recording is this centroid moved along `x` at the cell velocity.

use serde::{Deserialize, Serialize};

/// Kind of synthetic cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CellShape {
    /// Mirror-symmetric about its horizontal centre line: a bullet with a concave rear (or front).
    Croissant,
    /// Elongated teardrop, bent and tilted: no mirror symmetry.
    Slipper,
    /// Irregular blob (random Fourier modes of the radius).
    Other,
}

impl CellShape {
    pub fn as_str(self) -> &'static str {
        match self {
            CellShape::Croissant => "croissant",
            CellShape::Slipper => "slipper",
            CellShape::Other => "other",
        }
    }
}

/// A simple polygon (counter-clockwise or clockwise), vertices in um.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    pub pts: Vec<[f64; 2]>,
}

/// Vertices per half outline.
const N_HALF: usize = 64;

impl Polygon {
    /// Signed area (shoelace), um^2.
    pub fn signed_area(&self) -> f64 {
        let n = self.pts.len();
        (0..n).map(|i| {
            let (p, q) = (self.pts[i], self.pts[(i + 1) % n]);
            p[0] * q[1] - q[0] * p[1]
        }).sum::<f64>() * 0.5
    }

    /// Area, um^2.
    pub fn area(&self) -> f64 {
        self.signed_area().abs()
    }

    /// Area centroid, um: `C = 1/(6A) sum (p_i + p_{i+1}) (p_i x p_{i+1})`.
    pub fn centroid(&self) -> [f64; 2] {
        let n = self.pts.len();
        let a = self.signed_area();
        let (mut cx, mut cy) = (0.0, 0.0);
        for i in 0..n {
            let (p, q) = (self.pts[i], self.pts[(i + 1) % n]);
            let cr = p[0] * q[1] - q[0] * p[1];
            cx += (p[0] + q[0]) * cr;
            cy += (p[1] + q[1]) * cr;
        }
        [cx / (6.0 * a), cy / (6.0 * a)]
    }

    /// Second central area moments `(mu20, mu02, mu11)` per unit area, um^2 (polygon moment formulas, e.g. Steger 1996).
    pub fn central_moments(&self) -> (f64, f64, f64) {
        let n = self.pts.len();
        let a = self.signed_area();
        let c = self.centroid();
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let (p, q) = (self.pts[i], self.pts[(i + 1) % n]);
            let (x0, y0, x1, y1) = (p[0] - c[0], p[1] - c[1], q[0] - c[0], q[1] - c[1]);
            let cr = x0 * y1 - x1 * y0;
            sxx += (x0 * x0 + x0 * x1 + x1 * x1) * cr;
            syy += (y0 * y0 + y0 * y1 + y1 * y1) * cr;
            sxy += (x0 * y1 + 2.0 * x0 * y0 + 2.0 * x1 * y1 + x1 * y0) * cr;
        }
        (sxx / (12.0 * a), syy / (12.0 * a), sxy / (24.0 * a))
    }

    /// Extents along and across the principal axis, um: `(length, width)`.
    pub fn extents(&self) -> (f64, f64) {
        let (mu20, mu02, mu11) = self.central_moments();
        let th = crate::experiment::measure::principal_angle(mu20, mu02, mu11);
        let (ct, st) = (th.cos(), th.sin());
        let (mut a0, mut a1, mut b0, mut b1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in &self.pts {
            let a = p[0] * ct + p[1] * st;
            let b = -p[0] * st + p[1] * ct;
            a0 = a0.min(a);
            a1 = a1.max(a);
            b0 = b0.min(b);
            b1 = b1.max(b);
        }
        (a1 - a0, b1 - b0)
    }

    /// Bounding box `[xmin, xmax, ymin, ymax]`, um.
    pub fn bbox(&self) -> [f64; 4] {
        let mut b = [f64::MAX, f64::MIN, f64::MAX, f64::MIN];
        for p in &self.pts {
            b[0] = b[0].min(p[0]);
            b[1] = b[1].max(p[0]);
            b[2] = b[2].min(p[1]);
            b[3] = b[3].max(p[1]);
        }
        b
    }

    /// Signed distance of `(x, y)` to the outline, um: negative inside.
    pub fn signed_distance(&self, x: f64, y: f64) -> f64 {
        let n = self.pts.len();
        let mut d2 = f64::MAX;
        let mut inside = false;
        let mut j = n - 1;
        for i in 0..n {
            let (p, q) = (self.pts[j], self.pts[i]);
            let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
            let (wx, wy) = (x - p[0], y - p[1]);
            let l2 = ex * ex + ey * ey;
            let t = if l2 > 0.0 { ((wx * ex + wy * ey) / l2).clamp(0.0, 1.0) } else { 0.0 };
            let (dx, dy) = (wx - t * ex, wy - t * ey);
            d2 = d2.min(dx * dx + dy * dy);
            // even-odd crossing test on a horizontal ray towards +x
            if (p[1] > y) != (q[1] > y) && x < p[0] + (y - p[1]) / (q[1] - p[1]) * ex {
                inside = !inside;
            }
            j = i;
        }
        if inside { -d2.sqrt() } else { d2.sqrt() }
    }

    /// Polygon moved so that its centroid is at the origin.
    pub fn centred(mut self) -> Polygon {
        let c = self.centroid();
        for p in self.pts.iter_mut() {
            p[0] -= c[0];
            p[1] -= c[1];
        }
        self
    }
}

/// Parameters of one outline (um, degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutlineParams {
    pub length_um: f64,
    pub width_um: f64,
    pub orientation_deg: f64,
    /// Croissant: depth of the concave side as a fraction of the length; slipper: bend; other: roughness.
    pub deform: f64,
    /// Croissant: concave side upstream (`false`) or downstream (`true`); slipper: thick end downstream (`false`) or upstream.
    pub flip: bool,
    /// Slipper: teardrop asymmetry in [0, 0.6]; other: seed of the Fourier phases.
    pub asymmetry: f64,
    pub seed: u64,
}

/// Outline of a cell of kind `shape`, centroid at the origin.
pub fn outline(shape: CellShape, p: &OutlineParams) -> Polygon {
    let poly = match shape {
        CellShape::Croissant => croissant(p),
        CellShape::Slipper => slipper(p),
        CellShape::Other => irregular(p),
    };
    poly.centred()
}

/// Node `k` of `0..=n` on [-1, 1], denser at the ends (Chebyshev-Lobatto).
fn cheb(k: usize, n: usize) -> f64 {
    -(std::f64::consts::PI * k as f64 / n as f64).cos()
}

/// Croissant: `y = s W/2`, front `x_f = a sqrt(1-s^2)`, rear `x_b = -a sqrt(1-s^2) + notch (1-s^2)^3` (concave for `notch > a/6`):
/// symmetric under `y -> -y`; `flip` mirrors it along x.
fn croissant(p: &OutlineParams) -> Polygon {
    let a = 0.5 * p.length_um;
    let notch = p.deform.clamp(0.0, 0.9) * p.length_um;
    let hw = 0.5 * p.width_um;
    let sx = if p.flip { -1.0 } else { 1.0 };
    let mut pts = Vec::with_capacity(2 * N_HALF);
    for k in 0..N_HALF {
        let s = cheb(k, N_HALF);
        pts.push([sx * a * (1.0 - s * s).max(0.0).sqrt(), s * hw]);
    }
    for k in 0..N_HALF {
        let s = -cheb(k, N_HALF);
        let c = (1.0 - s * s).max(0.0);
        pts.push([sx * (-a * c.sqrt() + notch * c.powi(3)), s * hw]);
    }
    Polygon { pts }
}

/// Slipper: along the major axis `t in [-1, 1]`, `x = t L/2`, centre line `y_c = bend W (t^2 - 1/3)`,
/// half width `W/2 sqrt(1-t^2) (1 + asym t)`; then rotated by `orientation_deg`.
fn slipper(p: &OutlineParams) -> Polygon {
    let (a, hw) = (0.5 * p.length_um, 0.5 * p.width_um);
    let asym = p.asymmetry.clamp(0.0, 0.6) * if p.flip { -1.0 } else { 1.0 };
    let bend = p.deform;
    let (c, s) = (p.orientation_deg.to_radians().cos(), p.orientation_deg.to_radians().sin());
    let mut local = Vec::with_capacity(2 * N_HALF);
    for k in 0..N_HALF {
        let t = cheb(k, N_HALF);
        let h = hw * (1.0 - t * t).max(0.0).sqrt() * (1.0 + asym * t);
        local.push([t * a, bend * p.width_um * (t * t - 1.0 / 3.0) - h]);
    }
    for k in 0..N_HALF {
        let t = -cheb(k, N_HALF);
        let h = hw * (1.0 - t * t).max(0.0).sqrt() * (1.0 + asym * t);
        local.push([t * a, bend * p.width_um * (t * t - 1.0 / 3.0) + h]);
    }
    Polygon { pts: local.into_iter().map(|q| [c * q[0] - s * q[1], s * q[0] + c * q[1]]).collect() }
}

/// Irregular cell: ellipse of the given length and width with radius modulated by
/// Fourier modes 2..5 of amplitude up to `deform` and phases drawn from `seed`.
fn irregular(p: &OutlineParams) -> Polygon {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(p.seed);
    let modes: Vec<(f64, f64, f64)> = (2..=5)
        .map(|k| (k as f64, rng.random::<f64>() * p.deform.clamp(0.0, 0.25), rng.random::<f64>() * std::f64::consts::TAU))
        .collect();
    let (c, s) = (p.orientation_deg.to_radians().cos(), p.orientation_deg.to_radians().sin());
    let n = 2 * N_HALF;
    let pts = (0..n)
        .map(|i| {
            let phi = std::f64::consts::TAU * i as f64 / n as f64;
            let r = 1.0 + modes.iter().map(|(k, a, ph)| a * (k * phi + ph).cos()).sum::<f64>();
            let (x, y) = (0.5 * p.length_um * r * phi.cos(), 0.5 * p.width_um * r * phi.sin());
            [c * x - s * y, s * x + c * y]
        })
        .collect();
    Polygon { pts }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> OutlineParams {
        OutlineParams { length_um: 7.0, width_um: 6.0, orientation_deg: 0.0, deform: 0.25, flip: false, asymmetry: 0.3, seed: 3 }
    }

    #[test]
    fn polygon_formulas_on_a_rectangle() {
        // 4 x 2 rectangle centred at (1, 0.5): exact area, centroid, moments (w^2/12, h^2/12), extents
        let r = Polygon { pts: vec![[-1.0, -0.5], [3.0, -0.5], [3.0, 1.5], [-1.0, 1.5]] };
        assert!((r.area() - 8.0).abs() < 1e-12);
        let c = r.centroid();
        assert!((c[0] - 1.0).abs() < 1e-12 && (c[1] - 0.5).abs() < 1e-12);
        let (m20, m02, m11) = r.central_moments();
        assert!((m20 - 16.0 / 12.0).abs() < 1e-12 && (m02 - 4.0 / 12.0).abs() < 1e-12 && m11.abs() < 1e-12);
        let (l, w) = r.extents();
        assert!((l - 4.0).abs() < 1e-12 && (w - 2.0).abs() < 1e-12);
        assert!((r.signed_distance(1.0, 0.5) + 1.0).abs() < 1e-12);
        assert!((r.signed_distance(5.0, 0.5) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn croissant_is_mirror_symmetric_about_its_centre_line_and_slipper_is_not() {
        let cr = outline(CellShape::Croissant, &params());
        let c = cr.centroid();
        assert!(c[0].abs() < 1e-9 && c[1].abs() < 1e-9);
        // every vertex has its mirror image (y -> -y) on the outline
        for p in &cr.pts {
            assert!(cr.signed_distance(p[0], -p[1]).abs() < 1e-3);
        }
        let sl = outline(CellShape::Slipper, &OutlineParams { orientation_deg: 15.0, deform: 0.1, ..params() });
        let worst = sl.pts.iter().map(|p| sl.signed_distance(p[0], -p[1]).abs()).fold(0.0, f64::max);
        assert!(worst > 0.3, "slipper must not be mirror-symmetric: {worst}");
    }
}
