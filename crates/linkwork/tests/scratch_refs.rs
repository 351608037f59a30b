mod common;
use common::references::*;
use linkwork::analysis::dynamic::IntegratorKind;
use linkwork::{Model, Overrides};

#[test]
fn refs() {
    let k = (std::f64::consts::PI / 4.0).sin();
    let kk = elliptic_k(k);
    eprintln!(
        "sn(K)={} sn(0)={} sn(3K)={} sn(5K)={}",
        sn(kk, k),
        sn(0.0, k),
        sn(3.0 * kk, k),
        sn(5.0 * kk + 2000.0 * 4.0 * kk, k)
    );
    // pendulum ODE check: theta'' = -g sin theta via x,y
    let th = |t: f64| {
        let p = pendulum_a01(t);
        (-p[0]).atan2(-p[1])
    };
    let h = 1e-3;
    let mut worst = 0.0f64;
    for i in 0..2000 {
        let t = 0.37 + i as f64 * 0.997;
        let acc = (th(t + h) - 2.0 * th(t) + th(t - h)) / (h * h);
        worst = worst.max((acc + 9.81 * th(t).sin()).abs());
    }
    eprintln!("pendulum ODE residual {worst:.2e}");
    let model = Model::load(common::example("quick_return_a.yaml")).unwrap();
    let qr = QuickReturn::new(&model, 6.283);
    for (integ, tols) in
        [(IntegratorKind::Abam, [1e-6, 1e-8, 1e-10, 1e-12]), (IntegratorKind::Bdf, [1e-6, 1e-8, 1e-10, 1e-12])]
    {
        for tol in tols {
            let o = Overrides { integrator: Some(integ), rtol: Some(tol), atol: Some(tol), ..Default::default() };
            let r = match model.run_with("dynamics", &o) {
                Ok(r) => r,
                Err(f) => {
                    eprintln!("fail {}", f.error);
                    f.results
                }
            };
            let mut worst = 0.0f64;
            for name in qr.names() {
                let c = r.column(name).unwrap();
                for (i, &t) in r.time.iter().enumerate() {
                    worst = worst.max((c[i] - qr.position(name, t)).abs());
                }
            }
            eprintln!("{integ:?} {tol:e}: {worst:.2e} steps {}", r.summary["statistics"]["steps"]);
        }
    }
}
