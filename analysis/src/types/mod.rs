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
}
