//! The 3D bright-field renderer on shapes with exact answers (box, sphere), its recordings read back by the analysis, and bad meshes refused.

use rbc_analysis::experiment::recording::{detect_recording, Recording};
use rbc_analysis::simulated::render3d::{cell_image, single_cell_spec, write_recording_3d, CellMesh, CellMotion, Render3dError, Render3dParams};
use rbc_analysis::simulated::synth::{OpticsSpec, Truth};

/// Axis-aligned box `[-a, a] x [-b, b] x [-c, c]` moved by `o`, 12 outward triangles.
fn boxmesh(a: f64, b: f64, c: f64, o: [f64; 3]) -> CellMesh {
    let mut v = Vec::new();
    for k in 0..8 {
        let s = |bit: usize| if k >> bit & 1 == 1 { 1.0 } else { -1.0 };
        v.push([o[0] + s(0) * a, o[1] + s(1) * b, o[2] + s(2) * c]);
    }
    // faces as quads (counter-clockwise seen from outside), split into two triangles each
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut t = Vec::new();
    for q in quads {
        t.push([q[0], q[1], q[2]]);
        t.push([q[0], q[2], q[3]]);
    }
    CellMesh::new(&v, &t).unwrap()
}

fn sphere(level: usize, r: f64, o: [f64; 3]) -> CellMesh {
    let m = rbc_solver::mesh::sphere(level, r);
    let v: Vec<[f64; 3]> = m.vertices.iter().map(|p| [p.x + o[0], p.y + o[1], p.z + o[2]]).collect();
    CellMesh::new(&v, &m.triangles).unwrap()
}

/// Standard normal CDF by the same erf the renderer uses (statrs).
fn phi(u: f64) -> f64 {
    0.5 * (1.0 + statrs::function::erf::erf(u / std::f64::consts::SQRT_2))
}

#[test]
fn box_thickness_occupancy_and_in_focus_region_are_exact() {
    let m = boxmesh(3.0, 2.0, 1.0, [0.7, -0.4, 0.3]);
    let (vol, c) = m.volume_centroid();
    assert!((vol - 48.0).abs() < 1e-12 && (c[2] - 0.3).abs() < 1e-12);
    let p = Render3dParams::default();
    let img = cell_image(&m, &OpticsSpec::default(), &p).unwrap();
    assert_eq!(img.focal_z_um, c[2], "default focal plane: the centroid's z");
    // flat faces: the ray casting is exact inside (thickness 2 um, f = Phi(2) - Phi(-2))
    let f_in = phi(1.0 / p.dof_sigma_um) - phi(-1.0 / p.dof_sigma_um);
    let (mut n_in, mut worst_t, mut worst_f) = (0, 0.0f64, 0.0f64);
    for j in 0..img.ny {
        for i in 0..img.nx {
            let (x, y) = (img.x0_um + i as f64 * img.h_um, img.y0_um + j as f64 * img.h_um);
            let k = j * img.nx + i;
            let inside = (x - 0.7).abs() < 3.0 && (y + 0.4).abs() < 2.0;
            let (t, f) = if inside { (2.0, f_in) } else { (0.0, 0.0) };
            worst_t = worst_t.max((img.thickness_um[k] - t).abs());
            worst_f = worst_f.max((img.occupancy[k] - f).abs());
            n_in += inside as usize;
        }
    }
    assert!(n_in > 1000);
    assert!(worst_t < 1e-12 && worst_f < 1e-12, "thickness error {worst_t}, occupancy error {worst_f}");
    // in-focus region = the 6 x 4 rectangle: area to one grid row/column of the perimeter,
    // centroid and extents to a grid spacing
    let h = img.h_um;
    assert!((img.area_um2 - 24.0).abs() < 20.0 * h * 0.5 + 1e-9, "area {}", img.area_um2);
    assert!((img.centroid_um[0] - 0.7).abs() < h && (img.centroid_um[1] + 0.4).abs() < h, "{:?}", img.centroid_um);
    assert!((img.length_um - 6.0).abs() <= h && (img.width_um - 4.0).abs() <= h, "{} x {}", img.length_um, img.width_um);
    assert!(img.orientation_rad.abs() < 1e-9);
    // focal plane 3 um above the centre: the slab is 4 sigma below the plane's -> no in-focus region
    let off = cell_image(&m, &OpticsSpec::default(), &Render3dParams { focal_z_um: Some(4.3), ..p }).unwrap_err();
    assert!(matches!(off, Render3dError::Param { field: "focal_z_um", .. }), "{off}");
}

#[test]
fn sphere_in_focus_contour_follows_the_depth_of_field_formula() {
    // ray through a sphere of radius R at distance rho from its centre: chord 2 sqrt(R^2 - rho^2)
    // centred on the focal plane, f = 2 Phi(sqrt(R^2 - rho^2) / sigma) - 1 = 1/2 at
    // sqrt(R^2 - rho^2) = sigma Phi^-1(3/4) = 0.67449 sigma: in-focus area pi (R^2 - (0.67449 sigma)^2)
    let r = 3.0;
    let m = sphere(5, r, [0.0, 0.9, -0.2]);
    for sigma in [0.25, 0.5, 1.0] {
        let img = cell_image(&m, &OpticsSpec::default(), &Render3dParams { dof_sigma_um: sigma, ..Default::default() }).unwrap();
        let want = std::f64::consts::PI * (r * r - (0.674_489_75 * sigma).powi(2));
        // level-5 mesh (8192 triangles): inscribed polyhedron, edge e ~ 0.18 um, mean radius deficit
        // ~ e^2 / (6 R) ~ 2e-3 um, i.e. ~1.2e-3 of the area; plus the grid's area count (random
        // boundary cells, ~1e-4): 3e-3
        let rel = img.area_um2 / want - 1.0;
        println!("sigma {sigma}: in-focus area {:.4} um^2, formula {want:.4} um^2 ({rel:+.2e})", img.area_um2);
        assert!(rel.abs() < 3e-3, "sigma {sigma}: {rel}");
        assert!(img.centroid_um[0].abs() < 0.01 && (img.centroid_um[1] - 0.9).abs() < 0.01);
    }
    // thickness at the centre: 2 R (inscribed mesh: slightly less)
    let img = cell_image(&m, &OpticsSpec::default(), &Render3dParams::default()).unwrap();
    let t_max = img.thickness_um.iter().copied().fold(0.0, f64::max);
    assert!(t_max < 2.0 * r && t_max > 2.0 * r * (1.0 - 2e-3), "{t_max}");
}

#[test]
fn rendered_recording_is_read_back_by_the_analysis_at_the_truth() {
    // a 7 x 4.4 x 2 um box (the simplest exact in-focus outline), 1.2 um off the axis
    let m = boxmesh(3.5, 2.2, 1.0, [0.0, 1.2, 0.0]);
    let img = cell_image(&m, &OpticsSpec::default(), &Render3dParams::default()).unwrap();
    let (spec, x0) = single_cell_spec(0.2, 0.01, 2.0, 7.0);
    let dir = tempfile::tempdir().unwrap();
    let motion = CellMotion { x0_um: x0, velocity_mm_s: 2.0 };
    let truth = write_recording_3d(dir.path(), &spec, &img, &motion, "other", 7).unwrap();
    // refused a second time (frames already there)
    assert!(write_recording_3d(dir.path(), &spec, &img, &motion, "other", 7).is_err());
    let back = Truth::read(dir.path()).unwrap();
    assert_eq!(back.rows, truth.rows, "truth.csv round trip");
    assert!(truth.rows.iter().all(|r| r.visible), "the whole path is inside the field");
    let det = detect_recording(&Recording::open(dir.path()).unwrap()).unwrap();
    let mut errs = Vec::new();
    for t in &truth.rows {
        let d = det.detections.iter().filter(|d| d.frame as u64 == t.frame).min_by(|a, b| (a.x_um - t.x_um).abs().total_cmp(&(b.x_um - t.x_um).abs()));
        let d = d.expect("the cell is detected in every frame");
        errs.push(((d.x_um - t.x_um).hypot(d.y_um - t.y_um), d.area_um2 / t.area_um2 - 1.0, d.length_um - t.length_um));
    }
    errs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let med = errs[errs.len() / 2];
    println!("box: {} frames, median centroid error {:.4} um, area {:+.3}, length {:+.3} um", errs.len(), med.0, med.1, med.2);
    // the synthesiser's own accuracy bound for the centroid (frames_accuracy: median <= 0.05 um)
    // doubled for the absorption halo of a 3D body; area and length within the rim width
    assert!(med.0 < 0.1, "centroid {}", med.0);
    assert!(med.1.abs() < 0.15 && med.2.abs() < 0.6, "area {} length {}", med.1, med.2);
}

#[test]
fn bad_meshes_and_parameters_are_refused() {
    let good = boxmesh(1.0, 1.0, 1.0, [0.0; 3]);
    // inside-out (clockwise) surface: negative volume
    let flipped: Vec<[usize; 3]> = good.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect();
    assert!(matches!(CellMesh::new(&good.vertices, &flipped), Err(Render3dError::Degenerate { .. })));
    let mut bad = good.triangles.clone();
    bad[5][1] = 8;
    assert!(matches!(CellMesh::new(&good.vertices, &bad), Err(Render3dError::BadTriangle { triangle: 5, vertex: 8, .. })));
    let mut nan = good.vertices.clone();
    nan[3][2] = f64::NAN;
    assert!(matches!(CellMesh::new(&nan, &good.triangles), Err(Render3dError::NonFinite { vertex: 3 })));
    let e = cell_image(&good, &OpticsSpec::default(), &Render3dParams { dof_sigma_um: 0.0, ..Default::default() }).unwrap_err();
    assert!(e.to_string().contains("dof_sigma_um"), "{e}");
    let (mut spec, _) = single_cell_spec(0.2, 0.01, 1.0, 2.0);
    spec.cells.push(rbc_analysis::simulated::synth::random_spec(1, 0.2, 0.01, 1.0).cells[0]);
    let img = cell_image(&good, &OpticsSpec::default(), &Render3dParams::default()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let e = write_recording_3d(dir.path(), &spec, &img, &CellMotion { x0_um: 10.0, velocity_mm_s: 1.0 }, "x", 0).unwrap_err();
    assert!(e.to_string().contains("spec.cells"), "{e}");
}
