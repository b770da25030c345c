//! A cantilever's static deflection under a finger load against beam theory
//! (tip deflection P L³ / 3EI, tip slope P L² / 2EI), the load coming from
//! the fast loop's Eq. 7 and the deflection from its update; and the same
//! load from the dense reference (a different route: null space by SVD).

use haptloop_solver::{BodyId, FingerTarget, SolverSettings, reference_finger_wrenches};
use nalgebra::Vector3;

use crate::flexible::common::{DT, EI, L, cantilever, program};

/// Pulls the tip to `target` (a ramp over 100 ticks, then 600 ticks held)
/// and returns the program.
fn settle(modes: usize, target: Vector3<f64>) -> haptloop_solver::Program {
    let model = cantilever(modes);
    let mut p = program(model.clone(), SolverSettings::default());
    let start = model.initial_targets()[0].position_m;
    for k in 1..=700 {
        let s = (k as f64 / 100.0).min(1.0);
        let t = [FingerTarget::at(start + target * s)];
        let r = p.tick(&t, DT);
        assert_eq!(r.status, haptloop_solver::TickOutcome::Ok, "tick {k}");
    }
    p
}

/// Tip load and tip deflection/slope in y and z (EI and 2 EI), with two,
/// three and four modes: beam theory to 1e-9; one mode (ξ² alone) is 4/3
/// too stiff, which the same check catches.
#[test]
fn cantilever_tip_deflection_and_slope_match_beam_theory() {
    let beam = BodyId(1);
    for modes in 1..=4 {
        let p = settle(modes, Vector3::new(0.0, 4e-3, -3e-3));
        let q = p.q();
        let out = p.finger_outputs()[0];
        let ([v, w], [dv, dw]) = p.model().deflection(q, beam, L).unwrap();
        // The load on the finger pulls the tip back toward rest: P = −F.
        let force = out.constraint_force_n;
        for (dir, (d, slope, ei)) in [(v, dv, EI), (w, dw, 2.0 * EI)].into_iter().enumerate() {
            let p_load = -force[dir + 1];
            let want_d = p_load * L.powi(3) / (3.0 * ei);
            let want_s = p_load * L * L / (2.0 * ei);
            let (rd, rs) = ((d - want_d) / want_d, (slope - want_s) / want_s);
            if modes == 1 {
                assert!((d / want_d - 0.75).abs() < 1e-6, "one mode: {}", d / want_d);
            } else {
                assert!(
                    rd.abs() < 1e-9,
                    "{modes} modes, dir {dir}: deflection off by {rd:e}"
                );
                assert!(
                    rs.abs() < 1e-9,
                    "{modes} modes, dir {dir}: slope off by {rs:e}"
                );
            }
        }
        // The weld carries the axial component: the finger feels none.
        assert!(force.x.abs() < 1e-9 * force.norm(), "{force}");
        // The dense reference at the settled q (at rest) agrees.
        let zeros = vec![0.0; q.len()];
        let r = reference_finger_wrenches(p.model(), q, &zeros, &zeros).unwrap();
        let d = (r[0].force_n - force).norm();
        assert!(
            d < 1e-9 * force.norm(),
            "{modes} modes: reference off by {d:e}"
        );
    }
}

/// The finger is a penalty of weight K w m̄ against the tip stiffness
/// k = 3EI/L³: at rest the tip reaches K w m̄ / (K w m̄ + k) of the target
/// (`crate::flexible`'s docs), and a heavier finger weight tracks closer.
#[test]
fn the_finger_reaches_the_documented_fraction_of_its_target() {
    let model = cantilever(3);
    let m_bar = 0.05;
    let k_tip = 3.0 * EI / L.powi(3);
    for weight in [1.0, 100.0] {
        let settings = SolverSettings {
            finger_weight: weight,
            ..SolverSettings::default()
        };
        let mut p = program(model.clone(), settings);
        let start = model.initial_targets()[0].position_m;
        for k in 1..=400 {
            let s = (k as f64 / 100.0).min(1.0);
            let t = [FingerTarget::at(start + Vector3::new(0.0, 2e-3 * s, 0.0))];
            p.tick(&t, DT);
        }
        let ([v, _], _) = p.model().deflection(p.q(), BodyId(1), L).unwrap();
        let pen = settings.gain * weight * m_bar;
        let want = pen / (pen + k_tip);
        assert!(
            (v / 2e-3 - want).abs() < 1e-6,
            "weight {weight}: {} vs {want}",
            v / 2e-3
        );
        // Eq. 7's force is the elastic load at the reached deflection.
        let f = p.finger_outputs()[0].constraint_force_n.y;
        assert!((f + k_tip * v).abs() < 1e-9, "{f} vs {}", -k_tip * v);
    }
}

/// The strain energy of the settled shape is ½ P δ (Clapeyron), and the
/// shape is the cubic of beam theory along the whole span.
#[test]
fn the_settled_shape_is_the_beam_theory_cubic() {
    let p = settle(2, Vector3::new(0.0, 5e-3, 0.0));
    let q = p.q();
    let ([tip, _], _) = p.model().deflection(q, BodyId(1), L).unwrap();
    let load = -p.finger_outputs()[0].constraint_force_n.y;
    let u = p.model().strain_energy_j(q);
    assert!(
        (u - 0.5 * load * tip).abs() < 1e-9 * u,
        "U {u} vs ½Pδ {}",
        0.5 * load * tip
    );
    for k in 0..=10 {
        let x = L * k as f64 / 10.0;
        let ([v, _], _) = p.model().deflection(q, BodyId(1), x).unwrap();
        let want = load * x * x * (3.0 * L - x) / (6.0 * EI);
        assert!((v - want).abs() < 1e-9 * tip, "x {x}: {v} vs {want}");
    }
}
