//! Data passed between the stages: of the experiment (frames, shape features, detections: here)
//! and of the prediction ([`prediction`], computed by [`crate::predict`], drawn by [`crate::plot`]).
//! The CSV rows are `rbc_schema::tables`.
//!
//! Image convention: pixel (col, row), `x` along the flow = column index
//! (+x downstream = increasing column), `y` across the channel = row index.
//! Physical `y_um` is measured from the channel axis, positive towards
//! increasing rows.

pub mod prediction;

/// A grayscale frame, intensity scaled to [0, 1] whatever the bit depth; row-major, `data[row * width + col]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Frame {
    /// Intensity at (col, row).
    #[inline]
    pub fn at(&self, col: usize, row: usize) -> f32 {
        self.data[row * self.width + col]
    }
}

/// Shape descriptors of one projected cell (dimensionless unless stated).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ShapeFeatures {
    /// 1 - IoU of the mask and its mirror image about the horizontal line through the centroid
    /// (0 = mirror-symmetric about its own y-centre line).
    pub mirror_asymmetry: f64,
    /// Skewness of the mask's y distribution (signed).
    pub skew_y: f64,
    /// Orientation of the principal axis, radians from +x, in (-pi/2, pi/2].
    pub orientation_rad: f64,
    /// Solidity: area / convex hull area.
    pub solidity: f64,
    /// Depth of the deepest notch of the outline below its convex hull, relative to the
    /// width ([`crate::experiment::concavity`]; 0 for a convex outline).
    pub notch: f64,
    /// Depth of the deepest constriction concave on both sides, relative to the width
    /// ([`crate::experiment::concavity`]; 0 for convex and one-sided bent outlines).
    pub waist: f64,
}

/// One segmented object in one frame, measured (pixel units and physical units): what the
/// stages pass on. Its row in `detections.csv` is [`rbc_schema::tables::DetectionRow`] (written
/// by [`crate::experiment::pipeline`], with the recording's name and the track it joined).
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// Frame index within the recording (0-based, file-name order).
    pub frame: usize,
    /// Time of the frame, s.
    pub t_s: f64,
    /// Sub-pixel centroid, pixels (col, row).
    pub x_px: f64,
    pub y_px: f64,
    /// Centroid along the flow, um from the image's left edge.
    pub x_um: f64,
    /// Centroid across the channel, um from the channel axis (signed).
    pub y_um: f64,
    pub area_um2: f64,
    /// Extent along the principal axis, um.
    pub length_um: f64,
    /// Extent across the principal axis, um.
    pub width_um: f64,
    /// Object touches the image border: not measured into tracks.
    pub touches_border: bool,
    pub features: ShapeFeatures,
    /// The segmented mask over its bounding box (empty when the detection was not segmented
    /// from a frame): what [`crate::experiment::median_mask`] combines over a track.
    pub mask: MaskPatch,
    /// The segmentation's contrast around the object (empty when the detection was not
    /// segmented from a frame): what [`crate::experiment::register`] registers a track's frames on.
    pub contrast: ContrastPatch,
}

/// A frame's contrast over a box (pixel units): the segmentation's smoothed relative contrast
/// ([`crate::experiment::segment::Segmentation::contrast`]) around one object.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ContrastPatch {
    /// Column and row of the box's top-left pixel in the frame, px.
    pub col0: usize,
    pub row0: usize,
    /// Size of the box, px.
    pub width: usize,
    pub height: usize,
    /// Row-major over the box.
    pub values: Vec<f32>,
}

impl ContrastPatch {
    /// The box of `image` (row-major, `image_width` px a row) whose top-left pixel is
    /// `(col0, row0)` and whose size is `width x height` px, cut to the image.
    /// (Tests draw patches this way; `recording::detect` computes its patches in place.)
    #[cfg(test)]
    pub fn cut(image: &[f32], image_width: usize, (col0, row0): (usize, usize), (width, height): (usize, usize)) -> ContrastPatch {
        let image_height = image.len() / image_width.max(1);
        let width = width.min(image_width.saturating_sub(col0));
        let height = height.min(image_height.saturating_sub(row0));
        let mut values = Vec::with_capacity(width * height);
        for r in row0..row0 + height {
            values.extend_from_slice(&image[r * image_width + col0..r * image_width + col0 + width]);
        }
        ContrastPatch { col0, row0, width, height, values }
    }

    /// Bilinear samples at the frame positions `(x + u0 + u, y + v0 + v)` for `u < width`,
    /// `v < height` of the grid `(width, height)` (px), row-major into `out` (`width height`
    /// values), NaN where the four neighbours are not all inside the box; pixel centres on
    /// integers, the same weights for every sample.
    pub fn resample(&self, (x, y): (f64, f64), (u0, v0): (i64, i64), (gw, gh): (usize, usize), out: &mut [f64]) {
        assert_eq!(out.len(), gw * gh, "grid size");
        let (xf, yf) = (x.floor(), y.floor());
        let (fx, fy) = (x - xf, y - yf);
        // the box's column and row of the grid's first sample's top-left neighbour
        let c0 = xf as i64 + u0 - self.col0 as i64;
        let r0 = yf as i64 + v0 - self.row0 as i64;
        // grid columns u whose neighbours c0 + u and c0 + u + 1 lie in the box
        let cols = (-c0).clamp(0, gw as i64) as usize..(self.width as i64 - 1 - c0).clamp(0, gw as i64) as usize;
        out.fill(f64::NAN);
        for v in 0..gh {
            let r = r0 + v as i64;
            if r < 0 || r + 1 >= self.height as i64 {
                continue;
            }
            let (top, bottom) = (&self.values[r as usize * self.width..], &self.values[(r as usize + 1) * self.width..]);
            for u in cols.clone() {
                let c = (c0 + u as i64) as usize;
                let (a, b, cc, d) = (f64::from(top[c]), f64::from(top[c + 1]), f64::from(bottom[c]), f64::from(bottom[c + 1]));
                out[v * gw + u] = (1.0 - fy) * ((1.0 - fx) * a + fx * b) + fy * ((1.0 - fx) * cc + fx * d);
            }
        }
    }
}

/// A binary mask over a bounding box of a frame (pixel units), one bit per pixel.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MaskPatch {
    /// Column and row of the box's top-left pixel in the frame, px.
    pub col0: usize,
    pub row0: usize,
    /// Size of the box, px.
    pub width: usize,
    pub height: usize,
    /// Row-major over the box, bit `row * width + col` of the words: the pixel belongs to the object.
    bits: Vec<u64>,
}

impl MaskPatch {
    /// The box whose top-left pixel is `(col0, row0)` and whose size is `width x height` px,
    /// holding the pixels `(col, row)` (in the box) where `inside(col, row)`.
    pub fn from_fn(col0: usize, row0: usize, width: usize, height: usize, inside: impl Fn(usize, usize) -> bool) -> MaskPatch {
        let mut m = MaskPatch { col0, row0, width, height, bits: vec![0; (width * height).div_ceil(64)] };
        for r in 0..height {
            for c in 0..width {
                if inside(c, r) {
                    m.set(c, r);
                }
            }
        }
        m
    }

    /// The pixels `pixels` (linear indices `row * frame_width + col` in the frame) inside the box
    /// whose top-left pixel is `(col0, row0)` and whose size is `width x height` px; pixels outside
    /// the box are left out.
    pub fn from_pixels(pixels: &[u32], frame_width: usize, (col0, row0): (usize, usize), (width, height): (usize, usize)) -> MaskPatch {
        let mut m = MaskPatch { col0, row0, width, height, bits: vec![0; (width * height).div_ceil(64)] };
        for &i in pixels {
            let (r, c) = (i as usize / frame_width, i as usize % frame_width);
            if (col0..col0 + width).contains(&c) && (row0..row0 + height).contains(&r) {
                m.set(c - col0, r - row0);
            }
        }
        m
    }

    fn set(&mut self, col: usize, row: usize) {
        let k = row * self.width + col;
        self.bits[k / 64] |= 1 << (k % 64);
    }

    /// Whether pixel `(col, row)` of the box belongs to the object (false outside the box).
    #[inline]
    pub fn get(&self, col: usize, row: usize) -> bool {
        if col >= self.width || row >= self.height {
            return false;
        }
        let k = row * self.width + col;
        self.bits[k / 64] >> (k % 64) & 1 == 1
    }
}
