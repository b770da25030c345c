use haptloop_solver::scene;
use haptloop_solver::FingerTarget;
use nalgebra::Vector3;
use crate::common::lockstep;

#[test]
fn arm_debug() {
    let text = std::fs::read_to_string("../scenes/arm-push.toml").unwrap();
    let loaded = scene::parse("arm-push.toml", &text, None).unwrap();
    let compiled = loaded.compile().unwrap();
    let mut l = lockstep(compiled.model, 1000);
    let text = std::fs::read_to_string("/tmp/ap/trace.csv").unwrap();
    let targets: Vec<Vector3<f64>> = text.lines().skip(1).map(|l| {
        let v: Vec<f64> = l.split(',').skip(2).take(3).map(|x| x.parse().unwrap()).collect();
        Vector3::new(v[0], v[1], v[2])
    }).collect();
    for k in 0..4500 {
        let r = l.tick(&[FingerTarget::at(targets[k])]);
        let p = l.position("box");
        if k % 250 == 0 || (4100..4104).contains(&k) {
            let (res, _) = l.program.transitions();
            eprintln!("{k} box {:.5} {:.5} stick {} res {res} slips {} e {:.5} w {:.5}", p.x, p.y, r.sticking, l.program.slips(), r.energy.energy_j, r.energy.finger_work_j);
        }
    }
}
