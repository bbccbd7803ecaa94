//! Validation in flow: capsule and drop in simple shear against small-deformation theory, discocyte at rest.

use rbc_solver::integrate::validation::{run_case, Case};
#[allow(unused_imports)]
use rbc_schema as _;

#[test]
#[ignore]
fn explore() {
    let t0 = std::time::Instant::now();
    let levels: Vec<u32> = std::env::var("LEVELS").unwrap_or("2,3".into()).split(',').map(|s| s.parse().unwrap()).collect();
    let scheme = std::env::var("SCHEME").unwrap_or("bs23".into());
    let ca: f64 = std::env::var("CA").unwrap_or("0.01".into()).parse().unwrap();
    let relax: f64 = std::env::var("RELAX").unwrap_or("30".into()).parse().unwrap();
    let drop = std::env::var("DROP").is_ok();
    for level in levels {
        let case = if drop { Case::Drop { ca, lambda: 1.0 } } else { Case::Capsule { ca, c: 1.0, lambda: 1.0 } };
        let scheme = scheme.as_str();
        let r = run_case(case, level, scheme, 4e-5, relax).unwrap();
        eprintln!("{case:?} level {level} {scheme}: D = {:.5e} ref {:.5e} rel {:+.4} angle {:.3} deg\n{:?}", r.d, r.d_ref, r.relative_error(), r.angle_rad.to_degrees(), r.summary);
        for (t, d) in r.d_history.iter().rev().take(3) { eprintln!("  t {t:.4e} D {d:.5e}"); }
    }
    eprintln!("wall {:?}", t0.elapsed());
}

#[test]
#[ignore]
fn explore_steps() {
    use rbc_solver::run::{Observer, Sample};
    struct P(std::time::Instant);
    impl Observer for P {
        fn sample(&mut self, s: &Sample<'_>) -> Result<(), rbc_solver::SolverError> { eprintln!("sample t {:.3e} step {}", s.t_s, s.step); Ok(()) }
        fn progress(&mut self, t: f64, h: f64, step: usize) { if step < 20 || step % 100 == 0 { eprintln!("step {step} t {t:.3e} h {h:.3e} wall {:?}", self.0.elapsed()); } }
    }
    let case = Case::Capsule { ca: 0.01, c: 1.0, lambda: 1.0 };
    let text = case.scene_toml(2, "bs23", 4e-5, 0.5 * case.relaxation_s());
    let scene = rbc_schema::scene::Scene::parse(&text, std::path::Path::new("v.toml")).unwrap();
    let built = rbc_solver::scene::build(&scene).unwrap();
    let t0 = std::time::Instant::now();
    let f = built.membrane.laws.len();
    eprintln!("laws {f}");
    use rbc_solver::integrate::cell::Stokes;
    let fd = rbc_solver::membrane::MembraneLaw::force_density(&built.membrane, &built.mesh);
    eprintln!("force {:?}", t0.elapsed());
    let u = built.stokes.velocity(&built.mesh, &fd, true, None).unwrap();
    eprintln!("velocity {:?} max {}", t0.elapsed(), u.iter().map(|v| v.norm()).fold(0.0, f64::max));
    let _ = built.run(&mut P(std::time::Instant::now()));
}
