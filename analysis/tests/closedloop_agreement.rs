//! Closed loop: analytic croissant-like and slipper-like 3D cells labelled by the solver's 3D classifier, rendered in bright field, classified by rbc-analyze; the agreement of the two labels.
//!
//! The shapes are those of `solver/tests/classify_shapes.rs` (a cup for the
//! croissant, a bent, sheared, tilted ellipsoid for the slipper), over a family of
//! sizes, offsets, orientations and bends. Croissants move rigidly; slippers
//! tank-tread (their labels circulate about z at 37 Hz) so that the solver can
//! call them slippers; a few shapes are deliberately neither (a slipper shape that
//! does not tank-tread, a yawed cup), which the solver labels `other`.

use rbc_analysis::simulated::closedloop::Agreement;
use rbc_analysis::experiment::pipeline::{analyse_detections, StageConfig};
use rbc_analysis::experiment::classify::classify as classify_2d;
use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::experiment::track::link;
use rbc_analysis::simulated::render3d::{cell_image, single_cell_spec, write_recording_3d, CellMesh, CellMotion, Render3dParams};
use rbc_analysis::simulated::synth::OpticsSpec;
use rbc_schema::results::FinalShape;
use rbc_solver::classify::{classify, volume_centroid, ClassifyConfig, Frame};
use std::f64::consts::PI;

#[derive(Debug, Clone, Copy)]
enum Kind {
    /// Cup: scale, flip (opening upstream), pitch about y (deg), yaw about z (deg), bend factor.
    Cup { s: f64, flip: bool, pitch: f64, yaw: f64, bend: f64 },
    /// Slipper surface: scale, tilt about z (deg), bend factor, tank-treading.
    Slipper { s: f64, tilt: f64, bend: f64, tt: bool },
}

#[derive(Debug, Clone, Copy)]
struct Case {
    kind: Kind,
    /// Volume centroid (y, z), um from the channel axis.
    y: f64,
    z: f64,
}

fn rot_z(p: [f64; 3], a: f64) -> [f64; 3] {
    let (c, s) = (a.cos(), a.sin());
    [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]]
}

fn rot_y(p: [f64; 3], a: f64) -> [f64; 3] {
    let (c, s) = (a.cos(), a.sin());
    [c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2]]
}

/// Surface point of a unit-sphere point `u` (before centring).
fn surface(k: Kind, u: [f64; 3]) -> [f64; 3] {
    match k {
        Kind::Cup { s, flip, pitch, yaw, bend } => {
            // classify_shapes.rs: spheroid 1.2 um along x, 3.6 um across, bent x += 0.18 rho^2
            let (y, z) = (3.6 * s * u[1], 3.6 * s * u[2]);
            let x = 1.2 * s * u[0] + 0.18 * bend / s * (y * y + z * z);
            let p = [if flip { -x } else { x }, y, z];
            rot_z(rot_y(p, pitch.to_radians()), yaw.to_radians())
        }
        Kind::Slipper { s, tilt, bend, .. } => {
            // classify_shapes.rs: ellipsoid (4, 2.2, 1.4), y += 0.15 x^2, x += 0.4 y, tilted about z
            let (x, y, z) = (4.0 * s * u[0], 2.2 * s * u[1], 1.4 * s * u[2]);
            let y = y + 0.15 * bend / s * x * x;
            let x = x + 0.4 * y;
            rot_z([x, y, z], tilt.to_radians())
        }
    }
}

/// The case's vertices at time `t` (tank-treading slippers: labels rotated about z by
/// `2 pi 37 Hz t` on the unit sphere; everything translates at 2 mm/s), centred at (0, y, z) at t = 0.
fn vertices(c: &Case, u: &[[f64; 3]], tri: &[[usize; 3]], t: f64) -> Vec<[f64; 3]> {
    let omega = match c.kind {
        Kind::Slipper { tt: true, .. } => 2.0 * PI * 37.0,
        _ => 0.0,
    };
    let base: Vec<[f64; 3]> = u.iter().map(|&p| surface(c.kind, p)).collect();
    let (_, c0) = volume_centroid(&base, tri);
    // a cell below the axis is the mirror image (y -> -y) of one above it
    let sign = if c.y < 0.0 { -1.0 } else { 1.0 };
    u.iter()
        .map(|&p| {
            let q = surface(c.kind, rot_z(p, omega * t));
            [q[0] - c0[0] + 2000.0 * t, sign * (q[1] - c0[1]) + c.y, q[2] - c0[2] + c.z]
        })
        .collect()
}

/// The triangles with the winding reversed when the case's map reverses orientation
/// (flip x -> -x, mirror y -> -y), so that the surface stays outward-oriented.
fn oriented(c: &Case, tri: &[[usize; 3]]) -> Vec<[usize; 3]> {
    let flip = matches!(c.kind, Kind::Cup { flip: true, .. });
    if flip != (c.y < 0.0) {
        tri.iter().map(|t| [t[0], t[2], t[1]]).collect()
    } else {
        tri.to_vec()
    }
}

fn unit_sphere(level: usize, rotate: bool) -> (Vec<[f64; 3]>, Vec<[usize; 3]>) {
    let m = rbc_solver::mesh::sphere(level, 1.0);
    let v = m.vertices.iter().map(|p| {
        let q = [p.x, p.y, p.z];
        if rotate {
            rot_z(rot_y(rot_z(q, 0.31), 0.47), 0.83)
        } else {
            q
        }
    });
    (v.collect(), m.triangles.clone())
}

/// The solver's label: 46 frames over 1.84 turns of tank-treading (25 frames per turn).
fn solver_label(c: &Case) -> FinalShape {
    let (u, tri) = unit_sphere(3, true);
    let tri = oriented(c, &tri);
    let dt = 1.0 / (25.0 * 37.0);
    let frames: Vec<(f64, Vec<[f64; 3]>)> = (0..46).map(|k| (k as f64 * dt, vertices(c, &u, &tri, k as f64 * dt))).collect();
    let f: Vec<Frame> = frames.iter().map(|(t, v)| Frame { t_s: *t, vertices: v }).collect();
    classify(&f, &tri, &ClassifyConfig::default()).unwrap().shape
}

/// rbc-analyze's labels of the rendered cell (its longest track): the pipeline's (`tracks.csv`,
/// after the isolation stage's cluster check) and the shape classifier's alone; `none` if nothing was tracked.
fn analysis_labels(c: &Case, seed: u64) -> (String, String) {
    analysis_labels_with(c, seed, &Render3dParams::default(), 0.0)
}

/// [`analysis_labels`] with explicit render parameters; `focus_shift_um` moves the focal plane from the centroid's z.
fn analysis_labels_with(c: &Case, seed: u64, params: &Render3dParams, focus_shift_um: f64) -> (String, String) {
    let (u, tri) = unit_sphere(5, false);
    let tri = oriented(c, &tri);
    let mesh = CellMesh::new(&vertices(c, &u, &tri, 0.0), &tri).unwrap();
    let zf = mesh.volume_centroid().1[2] + focus_shift_um;
    let img = cell_image(&mesh, &OpticsSpec::default(), &Render3dParams { focal_z_um: Some(zf), ..*params }).unwrap();
    let (spec, x0) = single_cell_spec(0.2, 0.01, 2.0, img.bbox_um[1] - img.bbox_um[0]);
    let dir = tempfile::tempdir().unwrap();
    write_recording_3d(dir.path(), &spec, &img, &CellMotion { x0_um: x0, velocity_mm_s: 2.0 }, "", seed).unwrap();
    let rec = Recording::open(dir.path()).unwrap();
    let det = detect_recording(&rec).unwrap();
    let stages = StageConfig::default();
    let t = analyse_detections("closedloop", &rec.config, &det.detections, &stages);
    let Some(best) = t.tracks.iter().max_by_key(|t| t.n_frames) else { return ("none".into(), "none".into()) };
    let tracks = link(&det.detections, rec.config.fps, &stages.tracker);
    let track = tracks.iter().find(|t| t.id == best.track_id).expect("same linking");
    let k = classify_2d(track, &det.detections, &stages.classifier);
    let med = |f: &dyn Fn(&rbc_analysis::types::Detection) -> f64| {
        let mut v: Vec<f64> = track.detections.iter().map(|&i| f(&det.detections[i])).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "    image: y {:+.2} um, asymmetry {:.3}, aspect {:.2}, tilt {:+.0} deg, solidity {:.3}, notch {:.3}, waist {:.3}; in-focus area {:.1} um^2 (detected {:.1})",
        best.y_mean_um,
        k.asymmetry,
        med(&|d| d.length_um / d.width_um),
        med(&|d| d.features.orientation_rad.to_degrees()),
        med(&|d| d.features.solidity),
        med(&|d| d.features.notch),
        med(&|d| d.features.waist),
        img.area_um2,
        med(&|d| d.area_um2)
    );
    (best.shape.clone(), k.shape.as_str().to_string())
}

fn family() -> Vec<Case> {
    let mut v = Vec::new();
    let cup = |s, flip, pitch, yaw, bend| Kind::Cup { s, flip, pitch, yaw, bend };
    let slip = |s, tilt, bend, tt| Kind::Slipper { s, tilt, bend, tt };
    // croissants: sizes, opening up- or downstream, small offsets, pitch about y, bends
    for s in [0.9, 1.0, 1.1] {
        for flip in [false, true] {
            for (y, z) in [(0.0, 0.0), (0.25, 0.15)] {
                v.push(Case { kind: cup(s, flip, 0.0, 0.0, 1.0), y, z });
            }
        }
    }
    v.push(Case { kind: cup(1.0, false, 12.0, 0.0, 1.0), y: 0.1, z: 0.0 });
    v.push(Case { kind: cup(1.0, true, -12.0, 0.0, 0.7), y: 0.0, z: 0.2 });
    v.push(Case { kind: cup(1.0, false, 0.0, 0.0, 1.4), y: -0.2, z: 0.0 });
    // slippers: sizes, tilts, sides of the axis, bends, offsets 0.9 to 1.5 um
    for s in [0.9, 1.1] {
        for tilt in [10.0, 25.0] {
            for y in [0.9, -1.3] {
                v.push(Case { kind: slip(s, tilt, 1.0, true), y, z: 0.1 });
            }
        }
    }
    v.push(Case { kind: slip(1.0, 15.0, 0.6, true), y: 1.5, z: 0.0 });
    v.push(Case { kind: slip(1.0, 20.0, 1.5, true), y: -1.1, z: -0.2 });
    // neither: a slipper shape moving rigidly, a yawed cup
    v.push(Case { kind: slip(1.0, 25.0, 1.0, false), y: 1.2, z: 0.1 });
    v.push(Case { kind: slip(0.9, 10.0, 1.0, false), y: -1.0, z: 0.0 });
    v.push(Case { kind: cup(1.0, false, 0.0, 20.0, 1.0), y: 0.0, z: 0.0 });
    v
}

/// `cargo test -p rbc-analysis --test closedloop_agreement -- --nocapture` (about 20 s).
#[test]
fn analysis_agrees_with_the_solver_on_rendered_croissants_and_slippers() {
    let cases = family();
    let mut labels = Vec::new();
    for (i, c) in cases.iter().enumerate() {
        let s = solver_label(c);
        let (a, k) = analysis_labels(c, 100 + i as u64);
        println!("{:2} {:?} y {:+.2} z {:+.2}: solver {:9} analysis {a} (classifier alone {k})", i, c.kind, c.y, c.z, s.as_str());
        labels.push((s.as_str(), a, k));
    }
    let pipeline = Agreement::tally(labels.iter().map(|(s, a, _)| (*s, a.as_str())));
    let shape_only = Agreement::tally(labels.iter().map(|(s, _, k)| (*s, k.as_str())));
    let rows = |t: &Agreement| [0, 1, 2].map(|r| t.class(r).1);
    // the solver: the 16 rigid centred cups are croissants (13 symmetric about both planes; the
    // 2 pitched cups are symmetric about the x-z plane only and the yawed cup about the x-y
    // plane only: a croissant needs one mirror plane, rbc_solver::classify), the 10
    // tank-treading slippers slippers; the 2 rigidly moving slipper shapes are other
    assert_eq!(rows(&pipeline), [16, 10, 2], "solver labels of the family");
    println!("\n{}", pipeline.render("rbc-analyze pipeline (tracks.csv shape)"));
    println!("{}", shape_only.render("shape classifier alone (no cluster check)"));
    let (agree, agree_k) = (pipeline.agreeing().0, shape_only.agreeing().0);
    // Achieved (seeded, deterministic): pipeline 25/28 (croissants 15/16, slippers 10/10,
    // other 0/2), classifier alone the same (24/28 with 13/13, 10/10, 1/5 when the solver's
    // croissant needed both mirror planes: the yawed cup is now the croissant the top view
    // calls other). Before the notch/waist evidence in the cluster
    // rule (rbc_analysis::experiment::isolate) the pipeline agreed on 19/28 only: the bent slippers
    // (solidity 0.76-0.88, asymmetric) were flagged as touching cells; their notch is
    // 0.13-0.28 of the width, below the 0.33 of the rule. Limits: a top view cannot see the
    // membrane's tank-treading that separates a slipper
    // from a rigid slipper-shaped cell (the 2 rigid slipper shapes, solver `other`), nor the yaw of
    // a cup about z that keeps its x-y mirror plane (solver croissant, top view other). Asserted
    // with a margin of one case per class for changes in the analysis' thresholds.
    assert!(pipeline.class(0).0 >= 14 && shape_only.class(0).0 >= 14, "croissants: {pipeline:?}");
    assert!(pipeline.class(1).0 >= 9 && shape_only.class(1).0 >= 9, "slippers: {pipeline:?} {shape_only:?}");
    assert!(agree >= 24 && agree_k >= 24, "agreement {agree}, {agree_k}");
}

/// Writes one rendered croissant and one slipper recording for inspection:
/// `CLOSEDLOOP_OUT=/tmp/cl cargo test -p rbc-analysis --test closedloop_agreement write_examples -- --ignored`
#[test]
#[ignore]
fn write_examples() {
    let root = std::path::PathBuf::from(std::env::var("CLOSEDLOOP_OUT").expect("set CLOSEDLOOP_OUT"));
    let cases = family();
    for (name, c) in [("croissant", cases[4]), ("slipper", cases[16])] {
        let (u, tri) = unit_sphere(5, false);
        let tri = oriented(&c, &tri);
        let mesh = CellMesh::new(&vertices(&c, &u, &tri, 0.0), &tri).unwrap();
        let img = cell_image(&mesh, &OpticsSpec::default(), &Render3dParams::default()).unwrap();
        let (spec, x0) = single_cell_spec(0.2, 0.01, 2.0, img.bbox_um[1] - img.bbox_um[0]);
        let label = solver_label(&c);
        assert_eq!(label.as_str(), name, "case {name} of the family");
        let written = write_recording_3d(&root.join(name), &spec, &img, &CellMotion { x0_um: x0, velocity_mm_s: 2.0 }, label.as_str(), 1).unwrap();
        // the truth beside the frames reads back as written, the cell labelled and moving at 2 mm/s
        let read = rbc_analysis::simulated::synthetic_recording::Truth::read(&root.join(name)).unwrap();
        assert!(!read.rows.is_empty() && read.rows.len() == written.rows.len(), "{name}: {} truth rows", read.rows.len());
        assert!(read.rows.iter().all(|r| r.shape == name && (r.velocity_mm_s - 2.0).abs() < 1e-9), "{name}");
    }
}

/// Agreement against depth of field and focus: the family at sigma 0.25 / 0.5 / 1 um and the
/// focal plane 0.5 um off the mid-plane. Measured (2026-11-25, session 11, a croissant needing
/// one mirror plane): every setting as the default, pipeline and classifier alone 25/28
/// (croissants 15/16, slippers 10/10, other 0/2); asserted
/// with the margin of the default test (one case per class, one overall).
/// `cargo nextest run -p rbc-analysis --run-ignored only --no-capture -E 'test(depth_of_field_and_focus)'` (~1.5 min)
#[test]
#[ignore = "study: agreement against depth of field and focus, asserted"]
fn depth_of_field_and_focus() {
    let cases = family();
    let labels: Vec<FinalShape> = cases.iter().map(solver_label).collect();
    for (sigma, shift) in [(0.25, 0.0), (0.5, 0.0), (1.0, 0.0), (0.5, 0.5), (0.5, -0.5)] {
        let mut found = Vec::new();
        for (i, (c, s)) in cases.iter().zip(&labels).enumerate() {
            let (a, k) = analysis_labels_with(c, 100 + i as u64, &Render3dParams { dof_sigma_um: sigma, ..Default::default() }, shift);
            found.push((s.as_str(), a, k));
        }
        let pipeline = Agreement::tally(found.iter().map(|(s, a, _)| (*s, a.as_str())));
        let shape_only = Agreement::tally(found.iter().map(|(s, _, k)| (*s, k.as_str())));
        println!("{}", pipeline.render(&format!("sigma {sigma} um, focus {shift:+} um: pipeline")));
        println!("{}", shape_only.render(&format!("sigma {sigma} um, focus {shift:+} um: classifier alone")));
        for t in [&pipeline, &shape_only] {
            let (croissants, slippers, agree) = (t.class(0).0, t.class(1).0, t.agreeing().0);
            assert!(croissants >= 14 && slippers >= 9 && agree >= 24, "sigma {sigma} um, focus {shift:+} um: croissants {croissants}/16, slippers {slippers}/10, agreement {agree}/28; measured 15, 10, 25");
        }
    }
}
