//! The example recordings shipped in `examples/frames/`: four pressures at the channel entrance and 10 mm downstream.

use super::shape::CellShape;
use super::spec::{CellSpec, ChannelSpec, FrameFormat, IlluminationSpec, NoiseSpec, OpticsSpec, SynthSpec};

/// Mean cell velocity per applied pressure, mm/s per mbar: the paper's 1000 mbar give 10.6 mm/s.
pub const VELOCITY_PER_MBAR: f64 = 0.0106;

/// One shipped recording: folder name (relative to the examples root), spec and noise seed.
pub struct Example {
    pub name: String,
    pub spec: SynthSpec,
    pub seed: u64,
}

/// Eight recordings (50, 100, 200, 600 mbar x positions 0 and 10 mm), 16 frames of
/// 667 x 74 px at 0.3 um/px each; four cells 52 um apart per recording
/// (isolated), plus, at 10 mm, a fifth cell 24 um behind the last one (a pair
/// closer than 40 um). At 10 mm croissants are centred and slippers off-centre
/// with more slippers at higher pressure (paper, Fig. 3); at the entrance there
/// are more irregular cells and the offsets are spread wider. 600 mbar moves the
/// cells at 6.36 mm/s, the velocity of the study `examples/studies/science-6p5`
/// whose finished runs `examples/results.h5` holds, so that `rbc-predict` has a
/// group at its simulated column.
pub fn examples() -> Vec<Example> {
    use CellShape::{Croissant as C, Other as O, Slipper as S};
    let mut out = Vec::new();
    for (pi, &p) in [50.0, 100.0, 200.0, 600.0].iter().enumerate() {
        for &pos in &[0.0, 10.0] {
            let v = VELOCITY_PER_MBAR * p;
            let n_frames = 16;
            let total = v * 1000.0 / 400.0 * (n_frames - 1) as f64;
            let (shapes, ys): ([CellShape; 4], [f64; 4]) = match (pi, pos > 0.0) {
                (0, true) => ([C, C, O, C], [0.2, -0.3, 0.8, 0.1]),
                (1, true) => ([C, S, C, C], [-0.2, 1.8, 0.3, -0.1]),
                (2, true) => ([S, C, S, S], [-2.0, 0.2, 1.9, -2.2]),
                (3, true) => ([S, C, S, C], [1.7, -0.1, -1.6, 0.2]),
                (0, false) => ([C, O, C, O], [0.3, -2.0, -0.4, 2.2]),
                (1, false) => ([C, O, S, O], [0.2, 2.1, -1.5, -1.2]),
                (2, false) => ([S, C, O, S], [2.3, -0.3, 1.0, -2.0]),
                _ => ([C, S, O, C], [0.3, 1.5, -0.9, -0.6]),
            };
            let mut cells: Vec<CellSpec> = (0..4).map(|i| cell(shapes[i], 12.0 + 52.0 * i as f64 - 0.4 * total, ys[i], v * (0.96 + 0.025 * i as f64), i as u64 + 7 * pi as u64)).collect();
            if pos > 0.0 {
                let last = cells[3];
                cells.push(cell(C, last.x0_um + 24.0, -last.y_um.signum() * 0.4, last.velocity_mm_s, 99));
            }
            let spec = SynthSpec {
                width_px: 667,
                height_px: 74,
                um_per_px: 0.3,
                fps: 400.0,
                n_frames,
                pressure_mbar: p,
                position_mm: pos,
                format: FrameFormat::Png8,
                noise: NoiseSpec { gaussian_sigma: 0.008, full_well: 10000.0 },
                illumination: IlluminationSpec::default(),
                optics: OpticsSpec::default(),
                channel: ChannelSpec { width_um: 11.9, height_um: 9.7, axis_row_px: 36.3, axis_in_toml: false },
                cells,
                debris: Vec::new(),
                wave: None,
            };
            out.push(Example { name: format!("p{:03}mbar_x{:02}mm", p as u32, pos as u32), spec, seed: 1000 + 10 * pi as u64 + pos as u64 });
        }
    }
    out
}

fn cell(shape: CellShape, x0_um: f64, y_um: f64, velocity_mm_s: f64, seed: u64) -> CellSpec {
    let (length_um, width_um, orientation_deg, deform) = match shape {
        CellShape::Croissant => (6.5, 7.5, 0.0, 0.32),
        CellShape::Slipper => (7.8, 4.0, if y_um > 0.0 { -12.0 } else { 12.0 }, 0.12),
        CellShape::Other => (6.8, 5.8, 30.0, 0.15),
    };
    CellSpec { shape, x0_um, y_um, velocity_mm_s, length_um, width_um, orientation_deg, deform, flip: seed % 2 == 1, asymmetry: 0.3, seed }
}
