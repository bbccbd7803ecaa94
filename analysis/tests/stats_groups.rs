//! Tests of `groups::summarise`: group keys, isolated-only counting, fractions, Wilson intervals, velocities, kde and entry rows.

use rbc_analysis::experiment::groups::{mean_std, summarise, wilson_interval, MIN_KDE_CELLS, Z_95};
use rbc_analysis::experiment::kde::ksdensity;
use rbc_schema::tables::TrackRow;

fn track(p: f64, pos: f64, id: u64, y: f64, v: f64, isolated: bool, shape: &str) -> TrackRow {
    TrackRow {
        recording: format!("rec_{p}_{pos}"),
        pressure_mbar: p,
        position_mm: pos,
        track_id: id,
        n_frames: 20,
        x_first_um: 0.0,
        y_mean_um: y,
        y_std_um: 0.1,
        velocity_mm_s: v,
        velocity_se_mm_s: 0.01,
        isolated,
        gap_um: if isolated { 100.0 } else { 10.0 },
        shape: shape.into(),
        shape_score: 0.0,
        p_croissant: None,
    }
}

/// Wilson score interval, (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n), evaluated by
/// hand with 40-digit decimals (Python `decimal`) for z = 1.959963984540054, rounded to double precision.
#[test]
fn wilson_interval_matches_hand_computation() {
    let cases = [
        (5, 10, 0.236_593_090_512_564, 0.763_406_909_487_436),
        (0, 10, 0.0, 0.277_532_799_862_889_2),
        (10, 10, 0.722_467_200_137_110_8, 1.0),
        (1, 3, 0.061_491_944_720_396_24, 0.792_340_399_197_952_2),
    ];
    for (k, n, lo, hi) in cases {
        let (a, b) = wilson_interval(k, n, Z_95);
        assert!(
            (a - lo).abs() < 1e-15 && (b - hi).abs() < 1e-15,
            "{k}/{n}: ({a}, {b}) vs ({lo}, {hi})"
        );
    }
    // symmetry: the interval of n-k is the mirror image of that of k
    let (a, b) = wilson_interval(3, 17, Z_95);
    let (c, d) = wilson_interval(14, 17, Z_95);
    assert!((a - (1.0 - d)).abs() < 1e-15 && (b - (1.0 - c)).abs() < 1e-15);
}

#[test]
fn mean_and_sample_std() {
    // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, sum of squares 32, sample variance 32/7
    let (m, s) = mean_std(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
    assert_eq!(m, 5.0);
    assert!((s - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
    assert_eq!(mean_std(&[3.5]), (3.5, 0.0));
}

#[test]
fn groups_are_keyed_sorted_and_count_only_isolated_cells() {
    let tracks = vec![
        track(200.0, 10.0, 1, 0.5, 3.0, true, "slipper"),
        track(100.0, 10.0, 2, 0.0, 1.0, true, "croissant"),
        track(100.0, 0.0, 3, -1.0, 1.2, true, "other"),
        track(100.0, 10.0, 4, 0.1, 2.0, true, "croissant"),
        track(100.0, 10.0, 5, 0.2, 99.0, false, "slipper"), // not isolated: ignored everywhere
        track(100.0, 10.0, 6, 2.0, 3.0, true, "slipper"),
        track(300.0, 10.0, 7, 2.0, 3.0, false, "slipper"), // group with no isolated cell: no row
    ];
    let g = summarise(&tracks);
    let keys: Vec<(f64, f64)> = g
        .summary
        .iter()
        .map(|r| (r.pressure_mbar, r.position_mm))
        .collect();
    assert_eq!(keys, vec![(100.0, 0.0), (100.0, 10.0), (200.0, 10.0)]);
    let r = &g.summary[1];
    assert_eq!(r.n_cells, 3);
    assert_eq!(
        (r.frac_croissant, r.frac_slipper, r.frac_other),
        (2.0 / 3.0, 1.0 / 3.0, 0.0)
    );
    assert_eq!(r.velocity_mean_mm_s, 2.0);
    assert!((r.velocity_std_mm_s - 1.0).abs() < 1e-15); // 1, 2, 3
    assert_eq!((r.frac_croissant_lo, r.frac_croissant_hi), {
        let (a, b) = wilson_interval(2, 3, Z_95);
        (Some(a), Some(b))
    });
    assert_eq!((r.frac_slipper_lo, r.frac_slipper_hi), {
        let (a, b) = wilson_interval(1, 3, Z_95);
        (Some(a), Some(b))
    });
    // entry rows only at position 0, isolated only
    assert_eq!(g.entry.len(), 1);
    assert_eq!(
        (
            g.entry[0].pressure_mbar,
            g.entry[0].y_um,
            g.entry[0].velocity_mm_s
        ),
        (100.0, -1.0, 1.2)
    );
}

#[test]
fn kde_rows_only_for_shapes_with_enough_isolated_cells() {
    assert_eq!(MIN_KDE_CELLS, 3);
    let mut tracks = Vec::new();
    // 3 croissants, 2 slippers (+2 non-isolated slippers that must not count), 1 other
    for (i, y) in [-0.4, 0.1, 0.5].into_iter().enumerate() {
        tracks.push(track(100.0, 10.0, i as u64, y, 1.0, true, "croissant"));
    }
    tracks.push(track(100.0, 10.0, 10, 3.0, 1.5, true, "slipper"));
    tracks.push(track(100.0, 10.0, 11, -3.1, 1.5, true, "slipper"));
    tracks.push(track(100.0, 10.0, 12, 2.5, 1.5, false, "slipper"));
    tracks.push(track(100.0, 10.0, 13, -2.5, 1.5, false, "slipper"));
    tracks.push(track(100.0, 10.0, 14, 1.0, 0.5, true, "other"));
    let g = summarise(&tracks);
    let shapes: Vec<&str> = {
        let mut s: Vec<&str> = g.kde.iter().map(|k| k.shape.as_str()).collect();
        s.dedup();
        s
    };
    assert_eq!(shapes, vec!["all", "croissant"]);
    assert_eq!(g.kde.iter().filter(|k| k.shape == "all").count(), 100);
    // the 'all' density is ksdensity of exactly the 6 isolated y values
    let y_all = [-0.4, 0.1, 0.5, 3.0, -3.1, 1.0];
    let reference = ksdensity(&y_all, Some((-6.0, 6.0)), 100).unwrap();
    let rows: Vec<_> = g.kde.iter().filter(|k| k.shape == "all").collect();
    for (row, (y, d)) in rows.iter().zip(reference.y.iter().zip(&reference.density)) {
        assert_eq!((row.y_um, row.density), (*y, *d));
        assert_eq!((row.pressure_mbar, row.position_mm), (100.0, 10.0));
    }
}

#[test]
fn unmeasured_or_out_of_support_cells_are_noted_not_densities() {
    let tracks = vec![
        track(50.0, 10.0, 1, 0.1, 1.0, true, "croissant"),
        track(50.0, 10.0, 2, 0.2, 1.0, true, "croissant"),
        track(50.0, 10.0, 3, 0.3, 1.0, true, "croissant"),
        track(50.0, 10.0, 4, 6.5, 1.0, true, "croissant"), // outside [-6, 6]
        track(50.0, 10.0, 5, 0.0, f64::NAN, true, "croissant"),
    ];
    let g = summarise(&tracks);
    assert_eq!(g.summary[0].n_cells, 4); // NaN velocity left out, y = 6.5 still counted as a cell
    assert!(g.kde.iter().all(|k| k.density.is_finite()));
    assert_eq!(g.kde.iter().filter(|k| k.shape == "croissant").count(), 100);
    assert!(g.notes.iter().any(|n| n.contains("6.5")), "{:?}", g.notes);
    assert!(g.notes.iter().any(|n| n.contains("NaN")), "{:?}", g.notes);
}

/// Exact coverage of the Wilson 95 % interval, sum over k of Binomial(n, p)(k) [p in CI(k)],
/// averaged over p in [0.05, 0.95]: close to the nominal 0.95 (Brown, Cai & DasGupta 2001,
/// Stat. Sci. 16:101, Fig. 5). Our values: 0.9536, 0.9518, 0.9500 for n = 20, 50, 100
/// (numpy/scipy gives the same), minimum over p above 0.92.
#[test]
fn wilson_interval_has_nominal_coverage() {
    use statrs::distribution::{Binomial, Discrete};
    for n in [20u64, 50, 100] {
        let mut covs = Vec::new();
        for i in 0..=180 {
            let p = 0.05 + 0.9 * i as f64 / 180.0;
            let b = Binomial::new(p, n).unwrap();
            let cov: f64 = (0..=n)
                .filter(|&k| {
                    let (lo, hi) = wilson_interval(k, n, Z_95);
                    lo <= p && p <= hi
                })
                .map(|k| b.pmf(k))
                .sum();
            covs.push(cov);
        }
        let mean = covs.iter().sum::<f64>() / covs.len() as f64;
        let min = covs.iter().cloned().fold(1.0, f64::min);
        assert!(
            (mean - 0.95).abs() < 0.005 && min > 0.92,
            "n = {n}: mean coverage {mean}, min {min}"
        );
    }
}

#[test]
fn fractions_sum_to_one_and_intervals_contain_them() {
    let shapes = ["croissant", "slipper", "other", "unknown-label"];
    let tracks: Vec<TrackRow> = (0..97u64)
        .map(|i| {
            track(
                [20.0, 50.0, 100.0][(i % 3) as usize],
                10.0,
                i,
                0.0,
                1.0 + i as f64 * 0.01,
                i % 7 != 0,
                shapes[(i * i % 4) as usize],
            )
        })
        .collect();
    let g = summarise(&tracks);
    assert_eq!(
        g.summary.iter().map(|r| r.n_cells).sum::<u64>(),
        tracks.iter().filter(|t| t.isolated).count() as u64
    );
    for r in &g.summary {
        assert!((r.frac_croissant + r.frac_slipper + r.frac_other - 1.0).abs() < 1e-15);
        let (lo, hi) = (r.frac_croissant_lo.unwrap(), r.frac_croissant_hi.unwrap());
        assert!(lo <= r.frac_croissant && r.frac_croissant <= hi);
        let (lo, hi) = (r.frac_slipper_lo.unwrap(), r.frac_slipper_hi.unwrap());
        assert!(lo <= r.frac_slipper && r.frac_slipper <= hi);
    }
}
