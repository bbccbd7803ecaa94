//! The sweep observer's own state in a run's checkpoint: its ring of classification frames and
//! snapshot samples (`RingEntry`), written as observer fields (`observer_fields`) with the
//! detector's steady and periodic gaps and its orbit's drift, which `rbc-sweep status` reads back
//! for a running run ([`stored_gap`], [`stored_periodic_gap`], [`stored_orbit_drift`]).

use nalgebra::Vector3;
use rbc_solver::run::results::SampleRows;
use rbc_solver::state::{flatten, StateMap};
use rbc_solver::steady::{OrbitDrift, OrbitGap, OrbitPart};

/// An entry of the observer's ring: a classification frame, an `snapshot_every`-th sample, both,
/// or (the last entry only) the latest sample.
#[derive(Debug, Clone)]
pub(super) struct RingEntry {
    pub(super) t_s: f64,
    pub(super) vertices: Vec<[f64; 3]>,
    /// An `snapshot_every`-th sample: stored as a snapshot when it leaves the ring.
    pub(super) regular: bool,
    /// A classification frame.
    pub(super) frame: bool,
}

/// The sweep observer's own checkpoint fields (stored under `rbc_solver::run::persist::OBSERVER_PREFIX`
/// by [`rbc_solver::run::persist::checkpoint_fields`]): the snapshot cadence of `rows` ([`SampleRows::save`]) and
/// the ring, `frame_t_s`, `frame_regular`, `frame_classify` (0 or 1 each) and
/// `frame_vertices_um` (every entry's vertices, flattened), and the detector's steady gap at
/// the checkpoint's sample, `steady_gap` = `[gap, k]` with `k` the index of the observable in
/// [`rbc_solver::steady::OBSERVABLE_NAMES`] (absent while the samples span less than a window),
/// and its periodic gap, `periodic_gap` = `[gap, part, k, period_s, window_start_s]` of
/// [`OrbitGap`] (`part` 0 for the repetition, 1 for the drift; absent where the detector has no
/// candidate period), and the drift of its orbit's radial mean over that candidate's period,
/// `orbit_drift` = `[period_s, span_s, rate, earlier_rate]` of [`OrbitDrift`] (um/s; the earlier
/// rate NaN where there is none; absent without a candidate or whole periods enough), which
/// `rbc-sweep status` shows for a running run, whose results file it cannot open. Written by the observer's checkpoints and by `rbc-sweep reopen`
/// ([`super::reopen`]); read back by [`super::solver_exec::SweepObserver`]'s `restore` (all but the gaps, which the detector
/// computes again).
pub(super) fn observer_fields(rows: &SampleRows, ring: &[&RingEntry], gap: Option<(f64, &str)>, orbit: Option<OrbitGap>, drift: Option<OrbitDrift>) -> StateMap {
    let mut own = StateMap::new();
    rows.save(&mut own);
    if let Some(k) = gap.and_then(|(g, name)| rbc_solver::steady::OBSERVABLE_NAMES.iter().position(|n| *n == name).map(|k| [g, k as f64])) {
        own.insert(GAP_FIELD.into(), k.to_vec());
    }
    if let Some(o) = orbit {
        let part = f64::from(u8::from(o.part == OrbitPart::Drift));
        own.insert(PERIODIC_GAP_FIELD.into(), vec![o.gap, part, o.observable as f64, o.period_s, o.window_start_s]);
    }
    if let Some(d) = drift {
        own.insert(ORBIT_DRIFT_FIELD.into(), vec![d.period_s, d.span_s, d.rate, d.earlier_rate.unwrap_or(f64::NAN)]);
    }
    own.insert("frame_t_s".into(), ring.iter().map(|e| e.t_s).collect());
    own.insert("frame_regular".into(), ring.iter().map(|e| f64::from(u8::from(e.regular))).collect());
    own.insert("frame_classify".into(), ring.iter().map(|e| f64::from(u8::from(e.frame))).collect());
    let verts: Vec<Vector3<f64>> = ring.iter().flat_map(|e| e.vertices.iter().map(|p| Vector3::from(*p))).collect();
    own.insert("frame_vertices_um".into(), flatten(&verts));
    own
}

/// The ring stored by `observer_fields`, for a cell of `nv` vertices; `Err` names the field
/// that is missing or does not fit the others. A checkpoint of a build whose ring held
/// classification frames only has no `frame_classify`: every entry is then a frame.
pub(super) fn stored_ring(own: &StateMap, nv: usize) -> Result<Vec<RingEntry>, &'static str> {
    let get = |k: &'static str| own.get(k).ok_or(k);
    let (ft, fr, fv) = (get("frame_t_s")?, get("frame_regular")?, get("frame_vertices_um")?);
    let all_frames = vec![1.0; ft.len()];
    let fc = own.get("frame_classify").unwrap_or(&all_frames);
    if fr.len() != ft.len() {
        return Err("frame_regular");
    }
    if fc.len() != ft.len() {
        return Err("frame_classify");
    }
    if fv.len() != ft.len() * nv * 3 {
        return Err("frame_vertices_um");
    }
    Ok(ft
        .iter()
        .enumerate()
        .map(|(k, t)| RingEntry {
            t_s: *t,
            vertices: fv[k * nv * 3..(k + 1) * nv * 3].chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            regular: fr[k] != 0.0,
            frame: fc[k] != 0.0,
        })
        .collect())
}

/// The observer field of the steady gap at a checkpoint (see `observer_fields`).
pub const GAP_FIELD: &str = "steady_gap";

/// The observer field of the periodic gap at a checkpoint (see `observer_fields`).
pub const PERIODIC_GAP_FIELD: &str = "periodic_gap";

/// The observer field of the orbit's drift at a checkpoint (see `observer_fields`).
pub const ORBIT_DRIFT_FIELD: &str = "orbit_drift";

/// The orbit's drift stored in a checkpoint's observer fields by `observer_fields`, if any.
pub fn stored_orbit_drift(own: &StateMap) -> Option<OrbitDrift> {
    match own.get(ORBIT_DRIFT_FIELD).map(|v| v.as_slice()) {
        Some(&[period_s, span_s, rate, earlier]) if [period_s, span_s, rate].iter().all(|v| v.is_finite()) && period_s > 0.0 && span_s > 0.0 && !earlier.is_infinite() => Some(OrbitDrift {
            period_s,
            span_s,
            rate,
            earlier_rate: earlier.is_finite().then_some(earlier),
        }),
        _ => None,
    }
}

/// The periodic gap stored in a checkpoint's observer fields by `observer_fields`, if any.
pub fn stored_periodic_gap(own: &StateMap) -> Option<OrbitGap> {
    match own.get(PERIODIC_GAP_FIELD).map(|v| v.as_slice()) {
        Some(&[gap, part, k, period_s, window_start_s]) if [gap, period_s, window_start_s].iter().all(|v| v.is_finite()) && (part == 0.0 || part == 1.0) && k >= 0.0 && k.fract() == 0.0 => Some(OrbitGap {
            gap,
            part: if part == 1.0 { OrbitPart::Drift } else { OrbitPart::Repeat },
            observable: k as usize,
            period_s,
            window_start_s,
        }),
        _ => None,
    }
}

/// The steady gap stored in a checkpoint's observer fields by `observer_fields`, if any.
pub fn stored_gap(own: &StateMap) -> Option<(f64, &'static str)> {
    match own.get(GAP_FIELD).map(|v| v.as_slice()) {
        Some(&[g, k]) if g.is_finite() && k >= 0.0 && k.fract() == 0.0 => rbc_solver::steady::OBSERVABLE_NAMES.get(k as usize).map(|n| (g, *n)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ring a checkpoint stores comes back entry by entry (time, vertices, regular, frame); a
    /// checkpoint of a build without `frame_classify` reads every entry as a frame; a field that
    /// does not fit the others, or the cell's vertex count, is named.
    #[test]
    fn a_checkpoints_ring_reads_back_as_written() {
        let entry = |t_s: f64, regular: bool, frame: bool| RingEntry { t_s, vertices: vec![[t_s, 1.0, 2.0], [3.0, t_s, 4.0]], regular, frame };
        let ring = [entry(0.1, true, false), entry(0.2, false, true), entry(0.3, true, true)];
        let own = observer_fields(&SampleRows::new(4), &ring.iter().collect::<Vec<_>>(), None, None, None);
        let back = stored_ring(&own, 2).unwrap();
        assert_eq!(back.len(), 3);
        for (a, b) in ring.iter().zip(&back) {
            assert_eq!((a.t_s, &a.vertices, a.regular, a.frame), (b.t_s, &b.vertices, b.regular, b.frame));
        }
        let mut old = own.clone();
        old.remove("frame_classify");
        assert!(stored_ring(&old, 2).unwrap().iter().all(|e| e.frame));
        assert_eq!(stored_ring(&own, 3).err(), Some("frame_vertices_um"));
        let mut short = own.clone();
        short.insert("frame_regular".into(), vec![1.0]);
        assert_eq!(stored_ring(&short, 2).err(), Some("frame_regular"));
        short.remove("frame_t_s");
        assert_eq!(stored_ring(&short, 2).err(), Some("frame_t_s"));
    }

    /// The gaps a checkpoint stores come back as they were written, the periodic one with its
    /// part, observable, period and window, the orbit's drift with or without its earlier rate; a
    /// field of another shape (a hand-edited or foreign
    /// checkpoint) reads as none, not as a wrong gap.
    #[test]
    fn a_checkpoints_gaps_read_back_as_written() {
        let orbit = OrbitGap { gap: 1.836, part: OrbitPart::Drift, observable: 3, period_s: 0.3414, window_start_s: 2.1 };
        let drift = OrbitDrift { period_s: 0.3414, span_s: 1.3656, rate: -0.033, earlier_rate: Some(-0.021) };
        let own = observer_fields(&SampleRows::new(4), &[], Some((28.9, "extent_x_um")), Some(orbit), Some(drift));
        assert_eq!(stored_gap(&own), Some((28.9, "extent_x_um")));
        assert_eq!(stored_periodic_gap(&own), Some(orbit));
        assert_eq!(stored_orbit_drift(&own), Some(drift));
        let repeat = OrbitGap { part: OrbitPart::Repeat, ..orbit };
        let young = OrbitDrift { earlier_rate: None, ..drift };
        let own = observer_fields(&SampleRows::new(4), &[], None, Some(repeat), Some(young));
        assert_eq!((stored_periodic_gap(&own), stored_orbit_drift(&own)), (Some(repeat), Some(young)));
        let none = observer_fields(&SampleRows::new(4), &[], None, None, None);
        assert_eq!((stored_gap(&none), stored_periodic_gap(&none), stored_orbit_drift(&none)), (None, None, None));
        for bad in [vec![0.34, 1.4, -0.03], vec![0.0, 1.4, -0.03, -0.02], vec![0.34, 1.4, f64::NAN, -0.02], vec![0.34, 1.4, -0.03, f64::INFINITY]] {
            let mut own = none.clone();
            own.insert(ORBIT_DRIFT_FIELD.into(), bad.clone());
            assert_eq!(stored_orbit_drift(&own), None, "{bad:?}");
        }
        for bad in [vec![1.8, 2.0, 3.0, 0.34, 2.1], vec![1.8, 1.0, 3.5, 0.34, 2.1], vec![f64::NAN, 1.0, 3.0, 0.34, 2.1], vec![1.8, 1.0, 3.0]] {
            let mut own = none.clone();
            own.insert(PERIODIC_GAP_FIELD.into(), bad.clone());
            assert_eq!(stored_periodic_gap(&own), None, "{bad:?}");
        }
    }
}
