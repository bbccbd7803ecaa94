//! Shared test helpers: detection lists with exact ground truth (cells moving along +x with jitter and misses).
#![allow(dead_code)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rbc_analysis::experiment::track::Track;
use rbc_analysis::types::{Detection, ShapeFeatures};

/// A detection at (x, y) um in `frame` (400 fps unless `t_s` is changed), 0.2 um/px.
pub fn det(frame: usize, x_um: f64, y_um: f64) -> Detection {
    Detection {
        frame,
        t_s: frame as f64 / 400.0,
        x_px: x_um / 0.2,
        y_px: y_um / 0.2,
        x_um,
        y_um,
        area_um2: 50.0,
        length_um: 8.0,
        width_um: 6.0,
        touches_border: false,
        features: ShapeFeatures {
            solidity: 0.95,
            ..ShapeFeatures::default()
        },
        mask: Default::default(),
        contrast: Default::default(),
    }
}

/// One simulated cell: start x at frame 0, velocity, lateral position.
#[derive(Debug, Clone)]
pub struct Cell {
    pub x0_um: f64,
    pub v_um_per_frame: f64,
    pub y_um: f64,
}

/// A scene: cells in a field of view `[0, fov_um]`, `n_frames` frames, Gaussian centroid jitter,
/// probability that a detection is missed.
#[derive(Debug, Clone)]
pub struct Scene {
    pub cells: Vec<Cell>,
    pub n_frames: usize,
    pub fov_um: f64,
    /// Half length of a cell along x: a cell whose centre is closer than this to an edge touches the border.
    pub half_length_um: f64,
    pub jitter_um: f64,
    pub p_miss: f64,
}

/// Detections with the index of the true cell of each.
pub struct Generated {
    pub dets: Vec<Detection>,
    pub truth: Vec<usize>,
}

impl Scene {
    pub fn generate(&self, seed: u64) -> Generated {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, self.jitter_um.max(1e-300)).unwrap();
        let mut dets = Vec::new();
        let mut truth = Vec::new();
        for f in 0..self.n_frames {
            for (c, cell) in self.cells.iter().enumerate() {
                let x = cell.x0_um + cell.v_um_per_frame * f as f64;
                if x < -self.half_length_um || x > self.fov_um + self.half_length_um {
                    continue;
                }
                if rng.random_bool(self.p_miss) {
                    continue;
                }
                let (jx, jy) = if self.jitter_um > 0.0 {
                    (noise.sample(&mut rng), noise.sample(&mut rng))
                } else {
                    (0.0, 0.0)
                };
                let mut d = det(f, x + jx, cell.y_um + jy);
                d.touches_border = x < self.half_length_um || x > self.fov_um - self.half_length_um;
                dets.push(d);
                truth.push(c);
            }
        }
        // Detections within a frame come in image order (by x), not by cell.
        let mut order: Vec<usize> = (0..dets.len()).collect();
        order.sort_by(|&a, &b| {
            dets[a]
                .frame
                .cmp(&dets[b].frame)
                .then(dets[a].x_um.total_cmp(&dets[b].x_um))
        });
        Generated {
            dets: order.iter().map(|&i| dets[i].clone()).collect(),
            truth: order.iter().map(|&i| truth[i]).collect(),
        }
    }
}

/// Cells one after another along the channel with spacing `spacing_um` (+- `spacing_jitter`),
/// velocities `v * (1 +- v_spread)`, at lateral positions within +-`y_spread`. Faster cells are
/// never allowed to come closer than `min_gap_um` to the cell ahead within `n_frames`
/// (in a 12 um channel cells cannot overtake).
#[allow(clippy::too_many_arguments)] // test helper: every knob of a synthetic train, named at the call site
pub fn train(
    seed: u64,
    n_cells: usize,
    v: f64,
    v_spread: f64,
    spacing_um: f64,
    spacing_jitter: f64,
    y_spread: f64,
    n_frames: usize,
    min_gap_um: f64,
) -> Vec<Cell> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let mut cells: Vec<Cell> = Vec::new();
    let mut x = 0.0;
    for _ in 0..n_cells {
        let vel = v * (1.0 + rng.random_range(-v_spread..=v_spread));
        let mut gap = spacing_um + rng.random_range(-spacing_jitter..=spacing_jitter);
        if let Some(ahead) = cells.last() {
            // Keep the gap >= min_gap over the whole recording.
            let closing = (vel - ahead.v_um_per_frame) * n_frames as f64;
            if closing > 0.0 {
                gap = gap.max(min_gap_um + closing);
            }
        }
        x -= gap;
        cells.push(Cell {
            x0_um: x,
            v_um_per_frame: vel,
            y_um: rng.random_range(-y_spread..=y_spread),
        });
    }
    cells
}

/// Result of comparing tracks with the truth (independent of track labels).
///
/// The targets are the trackable segments of each cell: maximal runs of its non-border
/// detections in which no more than `max_missed` frames in a row are missing (a longer run of
/// misses cannot be bridged by design), with at least `min_frames` detections.
#[derive(Debug, Default, Clone, Copy)]
pub struct Score {
    /// Trackable segments.
    pub n_cells: usize,
    /// Segments whose detections are >= 90 % in one track that contains only that cell.
    pub found: usize,
    /// Tracks containing detections of more than one cell (swaps, wrong links).
    pub mixed: usize,
    /// Extra pure tracks on a segment that already has one (split tracks).
    pub duplicates: usize,
}

impl std::ops::AddAssign for Score {
    fn add_assign(&mut self, o: Score) {
        self.n_cells += o.n_cells;
        self.found += o.found;
        self.mixed += o.mixed;
        self.duplicates += o.duplicates;
    }
}

pub fn score(g: &Generated, tracks: &[Track], min_frames: usize, max_missed: usize) -> Score {
    // Segment id of every non-border detection.
    let mut seg_of = vec![usize::MAX; g.dets.len()];
    let mut last: std::collections::HashMap<usize, (usize, usize)> = Default::default(); // cell -> (frame, segment)
    let mut seg_size: Vec<usize> = Vec::new();
    for (i, (d, &c)) in g.dets.iter().zip(&g.truth).enumerate() {
        if d.touches_border {
            continue;
        }
        let seg = match last.get(&c) {
            Some(&(f, s)) if d.frame - f <= max_missed + 1 => s,
            _ => {
                seg_size.push(0);
                seg_size.len() - 1
            }
        };
        seg_size[seg] += 1;
        seg_of[i] = seg;
        last.insert(c, (d.frame, seg));
    }
    let mut s = Score {
        n_cells: seg_size.iter().filter(|&&n| n >= min_frames).count(),
        ..Default::default()
    };
    let mut best = vec![0usize; seg_size.len()];
    let mut owners = vec![0usize; seg_size.len()];
    for t in tracks {
        let cells: Vec<usize> = t.detections.iter().map(|&i| g.truth[i]).collect();
        if cells.iter().any(|&c| c != cells[0]) {
            s.mixed += 1;
            continue;
        }
        let mut count: std::collections::HashMap<usize, usize> = Default::default();
        for &i in &t.detections {
            *count.entry(seg_of[i]).or_default() += 1;
        }
        for (seg, n) in count {
            owners[seg] += 1;
            best[seg] = best[seg].max(n);
        }
    }
    for k in 0..seg_size.len() {
        if seg_size[k] >= min_frames && best[k] * 10 >= seg_size[k] * 9 {
            s.found += 1;
        }
        s.duplicates += owners[k].saturating_sub(1);
    }
    s
}
