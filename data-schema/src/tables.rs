//! The CSV tables of `rbc-analyze` and `rbc-predict` (`../shared/spec/interfaces.md`).
//!
//! Each table is a row struct whose field names are the required column names
//! (units in the name: `_um`, `_mm_s`, `_s`, `_mbar`). [`write_table`] writes a
//! header row and the rows atomically; [`read_table`] checks that every column
//! the row struct needs is present (error names the file and the column) and
//! that every number parses and is not NaN (error names the file, the data row,
//! counted from 1 after the header, and the column). Extra columns are allowed.

use crate::error::{Result, SchemaError};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// `detections.csv`: one segmented object in one frame (written by `rbc-analyze`; the columns
/// of [`columns::DETECTIONS`] are required, `touches_border`, `track_id` and `mirror_asymmetry`
/// are ours and follow them in this order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DetectionRow {
    pub recording: String,
    pub frame: u64,
    pub t_s: f64,
    /// Centroid along the flow, um from the image's left edge.
    pub x_um: f64,
    /// Centroid across the channel, um from the channel axis (signed).
    pub y_um: f64,
    pub area_um2: f64,
    pub length_um: f64,
    pub width_um: f64,
    /// Object touches the image border (not measured into tracks).
    pub touches_border: bool,
    /// `track_id` of `tracks.csv` (same recording), empty when the detection is in no reported track.
    pub track_id: Option<u64>,
    /// 1 - IoU of the mask and its mirror image about its own y-centre line (0 = mirror-symmetric).
    pub mirror_asymmetry: f64,
}

/// `tracks.csv`: one tracked cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackRow {
    pub recording: String,
    pub pressure_mbar: f64,
    pub position_mm: f64,
    pub track_id: u64,
    pub n_frames: u64,
    pub x_first_um: f64,
    pub y_mean_um: f64,
    pub y_std_um: f64,
    pub velocity_mm_s: f64,
    /// Standard error of the least-squares velocity, mm/s.
    pub velocity_se_mm_s: f64,
    pub isolated: bool,
    /// Distance along x to the nearest other object, um (`inf` when alone).
    pub gap_um: f64,
    /// `croissant`, `slipper` or `other`.
    pub shape: String,
    /// Classifier score in [-1, 1]: > 0 croissant-like, < 0 slipper-like; |score| is the confidence.
    pub shape_score: f64,
    /// Calibrated probability that the cell is a croissant, a sigmoid of `shape_score` (ours;
    /// empty in tables written before it existed).
    #[serde(default)]
    pub p_croissant: Option<f64>,
}

/// `summary.csv`: one recording group (pressure, position), isolated cells only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SummaryRow {
    pub pressure_mbar: f64,
    pub position_mm: f64,
    pub n_cells: u64,
    pub velocity_mean_mm_s: f64,
    pub velocity_std_mm_s: f64,
    pub frac_croissant: f64,
    pub frac_slipper: f64,
    pub frac_other: f64,
    /// Wilson 95 % interval of `frac_croissant`.
    #[serde(default)]
    pub frac_croissant_lo: Option<f64>,
    #[serde(default)]
    pub frac_croissant_hi: Option<f64>,
    #[serde(default)]
    pub frac_slipper_lo: Option<f64>,
    #[serde(default)]
    pub frac_slipper_hi: Option<f64>,
    /// Expected croissant fraction, the mean of `p_croissant` over the group's cells (ours; empty
    /// when a cell has no `p_croissant`).
    #[serde(default)]
    pub frac_croissant_expected: Option<f64>,
    /// Standard deviation of the croissant fraction from the classification uncertainty alone,
    /// `sqrt(sum p (1 - p)) / n_cells` (the cells independent Bernoulli trials of probability p).
    #[serde(default)]
    pub frac_croissant_expected_sd: Option<f64>,
}

/// `kde.csv`: one evaluation point of a y-density.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KdeRow {
    pub pressure_mbar: f64,
    pub position_mm: f64,
    /// `all`, `croissant`, `slipper` or `other`.
    pub shape: String,
    pub y_um: f64,
    /// Probability density, 1/um.
    pub density: f64,
}

/// `entry.csv`: one isolated cell at the channel entrance (`position_mm = 0`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EntryRow {
    pub pressure_mbar: f64,
    pub y_um: f64,
    pub velocity_mm_s: f64,
}

/// `thresholds.csv` of `rbc-predict`: one start shape x simulated velocity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThresholdRow {
    pub start_shape: String,
    pub velocity_mm_s: f64,
    /// Threshold offset, um (`inf` where only croissants exist, 0 where none).
    pub r_trans_um: f64,
    /// Largest croissant offset, um.
    pub r_lo_um: f64,
    /// Smallest slipper offset, um.
    pub r_hi_um: f64,
}

/// `prediction.csv` of `rbc-predict`: one start shape x pressure group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PredictionRow {
    pub start_shape: String,
    pub pressure_mbar: f64,
    pub velocity_mm_s: f64,
    pub velocity_std_mm_s: f64,
    pub r_trans_um: f64,
    pub y_trans_um: f64,
    pub phi: f64,
    pub phi_lo: f64,
    pub phi_hi: f64,
    /// Observed croissant fraction; empty without `--observed`.
    pub phi_observed: Option<f64>,
    /// Whether phi is a result: `bracketed` (the simulated runs bracket r_trans over the
    /// group's velocities), `extrapolated` (the velocities leave the simulated range: the
    /// nearest column was used), `unbracketed` (the runs leave r_trans anywhere in [0, inf):
    /// phi says nothing).
    pub status: String,
}

/// Column names of a row type, taken from serializing a sample row (the header the writer emits).
#[cfg(test)]
fn header_of<T: Serialize>(sample: &T) -> Vec<String> {
    let mut w = csv::WriterBuilder::new().has_headers(true).from_writer(Vec::new());
    if w.serialize(sample).is_err() {
        return Vec::new();
    }
    let bytes = w.into_inner().unwrap_or_default();
    let text = String::from_utf8_lossy(&bytes);
    text.lines().next().unwrap_or("").split(',').map(|s| s.to_string()).collect()
}

/// Write `rows` as a CSV table with a header row to `path`, atomically.
/// An empty table still gets its header when `header` is given.
pub fn write_table<T: Serialize>(path: &Path, rows: &[T], header: &[&str]) -> Result<()> {
    crate::atomic::write_atomic(path, |w| {
        let mut cw = csv::WriterBuilder::new().has_headers(!rows.is_empty()).from_writer(w);
        if rows.is_empty() {
            cw.write_record(header).map_err(|e| SchemaError::Csv { path: path.into(), message: e.to_string() })?;
        }
        for r in rows {
            cw.serialize(r).map_err(|e| SchemaError::Csv { path: path.into(), message: e.to_string() })?;
        }
        cw.flush().map_err(|e| SchemaError::io(path, e))?;
        Ok(())
    })
}

/// Read a CSV table, checking `required` columns, parsing each row into `T`,
/// and refusing NaN in the columns listed in `required` (a NaN is no measurement).
pub fn read_table<T: DeserializeOwned>(path: &Path, required: &[&str]) -> Result<Vec<T>> {
    let file = std::fs::File::open(path).map_err(|e| SchemaError::io(path, e))?;
    let mut rdr = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(file);
    let headers = rdr
        .headers()
        .map_err(|e| SchemaError::Csv { path: path.into(), message: e.to_string() })?
        .clone();
    for col in required {
        if !headers.iter().any(|h| h == *col) {
            return Err(SchemaError::MissingColumn { path: path.into(), column: (*col).into() });
        }
    }
    let mut out = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let row = i + 1;
        let rec = rec.map_err(|e| SchemaError::Csv { path: path.into(), message: format!("row {row}: {e}") })?;
        for col in required {
            let idx = headers.iter().position(|h| h == *col).expect("checked above");
            let cell = rec.get(idx).unwrap_or("");
            if cell.eq_ignore_ascii_case("nan") {
                return Err(SchemaError::Cell { path: path.into(), row, column: (*col).into(), message: "NaN is not a value".into() });
            }
        }
        let value: T = rec.deserialize(Some(&headers)).map_err(|e| match e.kind() {
            csv::ErrorKind::Deserialize { err, .. } => {
                let column = err
                    .field()
                    .and_then(|f| headers.get(f as usize))
                    .map(|s| s.to_string())
                    .unwrap_or_else(|| "?".into());
                SchemaError::Cell { path: path.into(), row, column, message: err.kind().to_string() }
            }
            other => SchemaError::Csv { path: path.into(), message: format!("row {row}: {other:?}") },
        })?;
        out.push(value);
    }
    Ok(out)
}

/// Required columns of each table, as in `interfaces.md`.
pub mod columns {
    pub const DETECTIONS: &[&str] = &["recording", "frame", "t_s", "x_um", "y_um", "area_um2", "length_um", "width_um"];
    pub const TRACKS: &[&str] = &[
        "recording", "pressure_mbar", "position_mm", "track_id", "n_frames", "x_first_um", "y_mean_um", "y_std_um",
        "velocity_mm_s", "isolated", "gap_um", "shape", "shape_score",
    ];
    pub const SUMMARY: &[&str] = &[
        "pressure_mbar", "position_mm", "n_cells", "velocity_mean_mm_s", "velocity_std_mm_s", "frac_croissant",
        "frac_slipper", "frac_other",
    ];
    pub const KDE: &[&str] = &["pressure_mbar", "position_mm", "shape", "y_um", "density"];
    pub const ENTRY: &[&str] = &["pressure_mbar", "y_um", "velocity_mm_s"];
    pub const THRESHOLDS: &[&str] = &["start_shape", "velocity_mm_s", "r_trans_um", "r_lo_um", "r_hi_um"];
    pub const PREDICTION: &[&str] = &[
        "start_shape", "pressure_mbar", "velocity_mm_s", "velocity_std_mm_s", "r_trans_um", "y_trans_um", "phi",
        "phi_lo", "phi_hi", "phi_observed", "status",
    ];
}

/// Read `entry.csv` (from `rbc-analyze` or a user's own file with these columns).
pub fn read_entry(path: &Path) -> Result<Vec<EntryRow>> {
    read_table(path, columns::ENTRY)
}

/// Read `summary.csv`.
pub fn read_summary(path: &Path) -> Result<Vec<SummaryRow>> {
    read_table(path, columns::SUMMARY)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(p: f64, y: f64, v: f64) -> EntryRow {
        EntryRow { pressure_mbar: p, y_um: y, velocity_mm_s: v }
    }

    #[test]
    fn header_matches_required_columns() {
        let h = header_of(&entry(1.0, 2.0, 3.0));
        assert_eq!(h, columns::ENTRY);
        let t = TrackRow {
            recording: "r".into(), pressure_mbar: 1.0, position_mm: 0.0, track_id: 1, n_frames: 2, x_first_um: 0.0,
            y_mean_um: 0.0, y_std_um: 0.0, velocity_mm_s: 1.0, velocity_se_mm_s: 0.0, isolated: true,
            gap_um: f64::INFINITY, shape: "other".into(), shape_score: 0.0, p_croissant: Some(0.5),
        };
        let h = header_of(&t);
        for c in columns::TRACKS {
            assert!(h.iter().any(|x| x == c), "{c} missing from {h:?}");
        }
    }

    #[test]
    fn round_trip_entry_and_infinite_values() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("entry.csv");
        let rows = vec![entry(100.0, -1.25, 3.5), entry(200.0, 0.5, 7.0)];
        write_table(&p, &rows, columns::ENTRY).unwrap();
        assert_eq!(read_entry(&p).unwrap(), rows);
        let th = vec![ThresholdRow { start_shape: "discocyte".into(), velocity_mm_s: 2.0, r_trans_um: f64::INFINITY, r_lo_um: 3.0, r_hi_um: f64::INFINITY }];
        let q = dir.path().join("thresholds.csv");
        write_table(&q, &th, columns::THRESHOLDS).unwrap();
        let back: Vec<ThresholdRow> = read_table(&q, columns::THRESHOLDS).unwrap();
        assert_eq!(back, th);
        assert!(std::fs::read_to_string(&q).unwrap().contains("inf"));
    }

    /// `detections.csv` as `rbc-analyze` writes it: the required columns first, then ours, an
    /// empty `track_id` for a detection in no track; read back exactly.
    #[test]
    fn detections_columns_and_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("detections.csv");
        let row = |frame: u64, track_id: Option<u64>| DetectionRow {
            recording: "rec".into(), frame, t_s: 0.0025, x_um: 10.5, y_um: -1.25, area_um2: 30.0, length_um: 8.0,
            width_um: 6.5, touches_border: frame == 1, track_id, mirror_asymmetry: 0.125,
        };
        let rows = vec![row(0, Some(3)), row(1, None)];
        write_table(&p, &rows, columns::DETECTIONS).unwrap();
        assert_eq!(
            std::fs::read_to_string(&p).unwrap(),
            "recording,frame,t_s,x_um,y_um,area_um2,length_um,width_um,touches_border,track_id,mirror_asymmetry\n\
             rec,0,0.0025,10.5,-1.25,30.0,8.0,6.5,false,3,0.125\n\
             rec,1,0.0025,10.5,-1.25,30.0,8.0,6.5,true,,0.125\n"
        );
        assert!(header_of(&rows[0]).starts_with(&columns::DETECTIONS.iter().map(|c| c.to_string()).collect::<Vec<_>>()));
        let back: Vec<DetectionRow> = read_table(&p, columns::DETECTIONS).unwrap();
        assert_eq!(back, rows);
    }

    #[test]
    fn empty_table_has_header() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("entry.csv");
        write_table::<EntryRow>(&p, &[], columns::ENTRY).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap().trim(), "pressure_mbar,y_um,velocity_mm_s");
        assert!(read_entry(&p).unwrap().is_empty());
    }

    #[test]
    fn missing_column_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("entry.csv");
        std::fs::write(&p, "pressure_mbar,velocity_mm_s\n100,3\n").unwrap();
        let e = read_entry(&p).unwrap_err().to_string();
        assert!(e.contains("entry.csv") && e.contains("y_um"), "{e}");
    }

    #[test]
    fn non_numeric_and_nan_cells_are_named_with_row() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("entry.csv");
        std::fs::write(&p, "pressure_mbar,y_um,velocity_mm_s\n100,1,3\n100,abc,3\n").unwrap();
        let e = read_entry(&p).unwrap_err().to_string();
        assert!(e.contains("row 2") && e.contains("y_um"), "{e}");
        std::fs::write(&p, "pressure_mbar,y_um,velocity_mm_s\n100,NaN,3\n").unwrap();
        let e = read_entry(&p).unwrap_err().to_string();
        assert!(e.contains("row 1") && e.contains("y_um") && e.contains("NaN"), "{e}");
    }
}
