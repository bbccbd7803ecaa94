//! What every renderer's camera does to the light: the positions of a moving object over the exposure (motion blur), the lamp's flicker from frame to frame, the sensor's shot and read noise and the quantisation to 8 or 16 bits.
//!
//! The synthesiser ([`crate::simulated::synth`]), the 3D renderer ([`crate::simulated::render3d`])
//! and the wave-optics renderer ([`crate::simulated::wave`]) form their images differently and
//! share this camera.

use crate::simulated::synth::spec::SynthSpec;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Poisson};

/// Positions (um) of an object's reference point over an exposure of `exposure_s` s while it moves
/// at `velocity_mm_s` along x from `x_um` at mid-exposure: the midpoints of `n` equal sub-intervals,
/// `x + travel ((j + 1/2) / n - 1/2)` with `travel = v t_exp`, `n` such that successive positions lie at
/// most 0.2 px apart (1 to 64). Averaging the image over them is the motion blur.
pub fn exposure_positions(x_um: f64, velocity_mm_s: f64, exposure_s: f64, um_per_px: f64) -> Vec<f64> {
    let travel = velocity_mm_s * 1000.0 * exposure_s; // um during the exposure (mm/s = 1000 um/s)
    let n_sub = ((travel.abs() / (0.2 * um_per_px)).ceil() as usize).clamp(1, 64);
    (0..n_sub).map(|j| x_um + travel * ((j as f64 + 0.5) / n_sub as f64 - 0.5)).collect()
}

/// Half the distance (um) an object at `velocity_mm_s` travels during the exposure: how far its
/// blurred image reaches beyond its outline along the flow.
pub fn half_blur_um(velocity_mm_s: f64, exposure_s: f64) -> f64 {
    0.5 * velocity_mm_s.abs() * 1000.0 * exposure_s
}

/// The lamp's brightness in one frame relative to its mean, `1 + flicker N(0, 1)` (one draw from `rng`).
pub fn flicker_gain(spec: &SynthSpec, rng: &mut ChaCha8Rng) -> f64 {
    1.0 + spec.illumination.flicker * Normal::new(0.0, 1.0).expect("unit normal").sample(rng)
}

/// The frame's counts (row-major) from its intensities (full scale = 1): shot and read noise, then
/// quantised to the spec's bit depth (0..=255 or 0..=65535).
pub fn expose(intensity: &[f64], spec: &SynthSpec, rng: &mut ChaCha8Rng) -> Vec<u16> {
    let max = if spec.format.sixteen_bit() { 65535.0 } else { 255.0 };
    add_noise_and_quantise(intensity, spec, rng, max)
}

/// Turn intensities (full scale = 1) into noisy, quantised counts of `max` (255 or 65535): Poisson
/// shot noise of `noise.full_well` electrons at full scale (its normal limit above 50), then
/// Gaussian read noise of `noise.gaussian_sigma` (fraction of full scale).
fn add_noise_and_quantise(intensity: &[f64], spec: &SynthSpec, rng: &mut ChaCha8Rng, max: f64) -> Vec<u16> {
    let n = &spec.noise;
    let read = Normal::new(0.0, n.gaussian_sigma.max(0.0)).expect("sigma >= 0");
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    intensity
        .iter()
        .map(|&i| {
            let mut v = i.max(0.0);
            if n.full_well > 0.0 {
                let lambda = v * n.full_well;
                let electrons = if lambda < 50.0 {
                    Poisson::new(lambda.max(1e-9)).map(|p| p.sample(rng)).unwrap_or(0.0)
                } else {
                    // normal limit of the Poisson distribution, exact to < 1 % in the tails for lambda >= 50
                    lambda + lambda.sqrt() * unit.sample(rng)
                };
                v = electrons / n.full_well;
            }
            if n.gaussian_sigma > 0.0 {
                v += read.sample(rng);
            }
            (v.clamp(0.0, 1.0) * max).round() as u16
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_positions_are_centred_on_mid_exposure_and_at_most_a_fifth_of_a_pixel_apart() {
        // 10 mm/s over 20 us: 0.2 um of travel, at 0.1 um/px at most 0.02 um apart -> 10 positions
        let xs = exposure_positions(5.0, 10.0, 2e-5, 0.1);
        assert_eq!(xs.len(), 10);
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        assert!((mean - 5.0).abs() < 1e-12, "{mean}");
        assert!((xs[9] - xs[0] - 0.18).abs() < 1e-12 && (xs[1] - xs[0] - 0.02).abs() < 1e-12, "{xs:?}");
        // at rest (or without exposure time) one position; very fast, at most 64
        assert_eq!(exposure_positions(5.0, 0.0, 2e-5, 0.1), vec![5.0]);
        assert_eq!(exposure_positions(5.0, 1e4, 1e-3, 0.1).len(), 64);
        assert_eq!(half_blur_um(-10.0, 2e-5), 0.1);
    }
}
