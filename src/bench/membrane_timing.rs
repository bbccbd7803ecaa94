//! Wall-clock timings of the membrane laws on the paper's meshes, for [`super::periodic`] (`rbc-bench periodic`).

use std::time::Instant;

use nalgebra::Vector3;

use rbc_solver::membrane::bending::{BendingMethod, Helfrich};
use rbc_solver::membrane::skalak::{Skalak, SkalakConvention};
use rbc_solver::membrane::tension::Tension;
use rbc_solver::membrane::{LinearisedLaw, MembraneLaw};
use rbc_solver::mesh;

/// One measured operation.
#[derive(Debug, Clone)]
pub struct Timing {
    /// What was timed.
    pub name: String,
    /// Mean wall-clock time per call (s).
    pub seconds: f64,
}

fn time(name: &str, repeats: usize, mut f: impl FnMut()) -> Timing {
    f(); // warm-up
    let start = Instant::now();
    for _ in 0..repeats {
        f();
    }
    Timing {
        name: name.to_string(),
        seconds: start.elapsed().as_secs_f64() / repeats as f64,
    }
}

/// Times force evaluation (and the Skalak linearisation) of every law on the
/// discocyte at subdivision `level` (4: the paper's 2048 triangles), deformed
/// by a fixed affine map so that nothing is trivially zero.
pub fn membrane_timings(level: usize, repeats: usize) -> Vec<Timing> {
    let reference = mesh::discocyte(level);
    let f = nalgebra::Matrix3::new(1.1, 0.05, 0.0, 0.0, 0.95, 0.02, 0.0, 0.0, 1.03);
    let m = mesh::Mesh {
        vertices: reference.vertices.iter().map(|x| f * x).collect(),
        triangles: reference.triangles.clone(),
    };
    let n = m.vertices.len();
    let mut out = vec![Vector3::zeros(); n];
    let skalak =
        Skalak::new(&reference, SkalakConvention::Krueger, 5e-6, 5e-4).expect("valid parameters");
    let tension = Tension::new(1e-6).expect("valid parameters");
    let v: Vec<Vector3<f64>> = m.vertices.iter().map(|x| x * 0.01).collect();
    let mut rows = vec![
        time("skalak force density", repeats, || {
            skalak.add_force_density(&m, &mut out)
        }),
        time("skalak jacobian-vector product", repeats, || {
            skalak.add_nodal_force_jvp(&m, &v, &mut out)
        }),
        time("skalak stiffness triplets", repeats, || {
            std::hint::black_box(skalak.stiffness_triplets(&m));
        }),
        time("tension force density", repeats, || {
            tension.add_force_density(&m, &mut out)
        }),
    ];
    for method in [
        BendingMethod::CotangentMethodC,
        BendingMethod::QuarticFit,
        BendingMethod::QuarticFitGalerkin,
    ] {
        let law = Helfrich::with_method(3e-19, method).expect("valid parameters");
        rows.push(time(
            &format!("helfrich {method:?} force density"),
            repeats,
            || law.add_force_density(&m, &mut out),
        ));
    }
    for r in &mut rows {
        r.name = format!("{} ({} triangles)", r.name, m.triangles.len());
    }
    rows
}
