//! The optics of the wave-optics renderer: the `[wave]` table of a synthetic spec (wavelength, objective and condenser apertures, focus, refractive indices, absorption), with its ranges.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// The optics of the wave renderer (`[wave]` table of a synthetic spec); units in the names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WaveOptics {
    /// Wavelength of the illumination in vacuum, um (green filter).
    pub wavelength_um: f64,
    /// Numerical aperture of the objective.
    pub na: f64,
    /// Numerical aperture of the condenser (partial coherence `sigma = condenser_na / na`).
    pub condenser_na: f64,
    /// Focal plane above (+) or below (-) the cell's mid-plane, um.
    pub defocus_um: f64,
    /// Refractive index of the suspending medium (buffer) and of the cell (haemoglobin solution).
    pub n_medium: f64,
    pub n_cell: f64,
    /// Intensity absorption coefficient of the cell, 1/um: oxy-haemoglobin at 541 nm, 14.5 /(cm mM)
    /// per haem, 20.5 mM haem (MCHC 33 g/dL), `ln 10 x 14.5 x 20.5 / 1e4 = 0.068 /um`.
    pub absorption_per_um: f64,
    /// Refractive index of the channel's PDMS walls.
    pub n_pdms: f64,
    /// Volume of a cell drawn from an outline, um^3 (a red cell's ~90).
    pub cell_volume_um3: f64,
}

impl Default for WaveOptics {
    fn default() -> Self {
        WaveOptics {
            wavelength_um: 0.55,
            na: 0.8,
            condenser_na: 0.4,
            defocus_um: 1.0,
            n_medium: 1.335,
            n_cell: 1.40,
            absorption_per_um: 0.068,
            n_pdms: 1.41,
            cell_volume_um3: 90.0,
        }
    }
}

impl WaveOptics {
    /// Distance the transmitted field is propagated to the imaged plane, um: `-defocus_um`
    /// (inverted microscope, see the module documentation).
    pub fn propagation_um(&self) -> f64 {
        -self.defocus_um
    }

    /// Sampling of the object, um: at most a quarter of the finest period the optics pass
    /// (`lambda / (NA + NA_c)`) and 0.1 um, and a whole fraction of the pixel.
    pub fn fine_spacing(&self, um_per_px: f64) -> (f64, usize) {
        let limit = (0.25 * self.wavelength_um / (self.na + self.condenser_na)).min(0.1);
        let m = (um_per_px / limit).ceil().max(1.0) as usize;
        (um_per_px / m as f64, m)
    }

    /// Check the ranges; the error names `path` and the field (`wave.<field>`).
    pub fn validate(&self, path: &Path) -> Result<(), rbc_schema::SchemaError> {
        use rbc_schema::recording::positive;
        let f = |field: &str, msg: String| rbc_schema::SchemaError::field(path, format!("wave.{field}"), msg);
        positive(path, "wave.wavelength_um", self.wavelength_um)?;
        if !(0.2..=2.0).contains(&self.wavelength_um) {
            return Err(f("wavelength_um", format!("must be in 0.2..=2 um (light), got {}", self.wavelength_um)));
        }
        if !(1.0..=2.0).contains(&self.n_medium) {
            return Err(f("n_medium", format!("must be in 1..=2, got {}", self.n_medium)));
        }
        for (name, v) in [("n_cell", self.n_cell), ("n_pdms", self.n_pdms)] {
            if !(1.0..=2.5).contains(&v) {
                return Err(f(name, format!("must be in 1..=2.5, got {v}")));
            }
        }
        if !(self.na > 0.0 && self.na < self.n_medium) {
            return Err(f("na", format!("must be in (0, n_medium = {}) (an objective in the medium), got {}", self.n_medium, self.na)));
        }
        if !(self.condenser_na >= 0.0 && self.condenser_na <= self.na) {
            return Err(f("condenser_na", format!("must be in 0..=na = {} (bright field), got {}", self.na, self.condenser_na)));
        }
        if !(self.defocus_um.is_finite() && self.defocus_um.abs() <= 20.0) {
            return Err(f("defocus_um", format!("must be within +-20 um, got {}", self.defocus_um)));
        }
        if !(self.absorption_per_um >= 0.0 && self.absorption_per_um <= 10.0) {
            return Err(f("absorption_per_um", format!("must be in 0..=10 /um, got {}", self.absorption_per_um)));
        }
        if !(self.cell_volume_um3 >= 10.0 && self.cell_volume_um3 <= 1000.0) {
            return Err(f("cell_volume_um3", format!("must be in 10..=1000 um^3, got {}", self.cell_volume_um3)));
        }
        Ok(())
    }
}
