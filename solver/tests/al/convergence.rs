//! The fast update: the gradient rule is Eq. 3, both rules converge from a
//! perturbation on every built-in mechanism, and the K rule (rows and columns
//! in metres) matters.

use haptloop_solver::mechanisms::{four_bar, sphere_toy, stewart};
use haptloop_solver::{Model, RowUnit, Sense, SolverSettings, TickOutcome, UpdateRule};

use crate::common::*;

/// Plain Eq. 3 with the default gains.
fn gradient() -> SolverSettings {
    SolverSettings {
        update: UpdateRule::Gradient,
        ..Default::default()
    }
}

/// One `Program::iterate` equals Eq. 3 written out with the stored Jacobian:
/// Δq = −W⁻¹(W(q − q₀) + C_qᵀ(λ + K C)), λ ← λ + k₂ C, K_i = K ℓ_i²,
/// W = 1 on r and L² on e (q = q₀ at the first iteration of a tick).
#[test]
fn iterate_is_eq3_with_the_documented_k_rule() {
    for model in [four_bar(), stewart()] {
        let q = perturbed(&model, 1e-3, 3);
        let mut targets = model.initial_targets();
        targets[0].position_m.x += 2e-4;
        let mut p = program(model, gradient());
        p.set_q(&q).unwrap();
        assert_eq!(p.iterate(&targets, 1), TickOutcome::Ok);
        let m: &Model = p.model();
        let (k, l, h) = (p.settings().gain, p.length_scale_m(), p.step_h());
        let mut ev = m.evaluation();
        ev.evaluate(m, &q, &targets).unwrap();
        let c = ev.values();
        let mut w: Vec<f64> = (0..m.n_rows())
            .map(|i| {
                let row = m.rows()[i];
                let ell = if row.unit == RowUnit::Length { 1.0 } else { l };
                let finger = m.constraints()[row.constraint.index()].finger.is_some();
                let (kk, k2) = (k * ell * ell, p.settings().multiplier_gain * ell * ell);
                if row.sense == Sense::Inequality {
                    // Projected: ν = max(0, 0 − k₂ C), w = −max(0, ν − K C).
                    let nu = (-k2 * c[i]).max(0.0);
                    return -(nu - kk * c[i]).max(0.0);
                }
                // λ starts at 0 and is updated first: λ = k₂ C (fingers: none).
                let lambda = if finger { 0.0 } else { k2 * c[i] };
                lambda + kk * c[i]
            })
            .collect();
        // The pull limit d: a finger's 3-row group with |ℓ C| > d pulls as if d away.
        for f in m.fingers() {
            for rows in m.constraints()[f.constraint.index()]
                .rows
                .clone()
                .step_by(3)
            {
                let ell = |i: usize| {
                    if m.rows()[i].unit == RowUnit::Length {
                        1.0
                    } else {
                        l
                    }
                };
                let norm = (rows..rows + 3)
                    .map(|i| (ell(i) * c[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                let d = p.settings().finger_pull_limit_m;
                if norm > d {
                    for wi in &mut w[rows..rows + 3] {
                        *wi *= d / norm;
                    }
                }
            }
        }
        let mut g = vec![0.0; m.n_coords()];
        ev.jacobian().mul_t_vec(&w, &mut g).unwrap();
        let mut expected = q.clone();
        for (_, o) in m.layout().moving_bodies() {
            for j in 0..7 {
                let winv = if j < 3 { 1.0 } else { 1.0 / (l * l) };
                expected[o + j] -= h * winv * g[o + j];
            }
        }
        let worst = p
            .q()
            .iter()
            .zip(&expected)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let moved = p
            .q()
            .iter()
            .zip(&q)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(moved > 1e-6, "the step moved something");
        assert!(worst < 1e-12 * moved.max(1.0), "worst {worst}");
    }
}

/// Gradient rule: from q0 moved by up to 1 mm per coordinate, the violation
/// falls every decade of iterations and ends below 1 µm (sphere toy: 10 µm; plain AL
/// converges linearly and that structure is the worst conditioned).
#[test]
fn converges_from_a_perturbation_on_every_mechanism() {
    for (name, model, tol) in [
        ("four-bar", four_bar(), 1e-6),
        ("stewart", stewart(), 1e-6),
        ("sphere-toy", sphere_toy(), 1e-5),
    ] {
        let targets = model.initial_targets();
        let q = perturbed(&model, 1e-3, 5);
        let mut p = program(model, gradient());
        p.set_q(&q).unwrap();
        let mut last = f64::INFINITY;
        for cap in [10, 100, 1000, 3000] {
            let r = p.assemble(&targets, cap, 1e-12);
            assert_eq!(r.status, TickOutcome::Ok);
            assert!(
                r.max_scaled_violation_m < last,
                "{name}: {r:?} after {last}"
            );
            last = r.max_scaled_violation_m;
        }
        assert!(last < tol, "{name}: {last}");
        assert!(p.q().iter().all(|v| v.is_finite()));
    }
}

/// The K rule against plain Eq. 3 with one K for every row and column
/// (length scale 1 m): the scaled four-bar and Stewart platform assemble to
/// 10 nm in under a tenth of the iterations the unscaled ones need.
#[test]
fn the_k_rule_speeds_convergence_tenfold() {
    for model in [four_bar, stewart] {
        let iterations = |l: Option<f64>| {
            let m = model();
            let (targets, q) = (m.initial_targets(), perturbed(&m, 1e-3, 7));
            let mut p = program(
                m,
                SolverSettings {
                    length_scale_m: l,
                    ..gradient()
                },
            );
            p.set_q(&q).unwrap();
            let r = p.assemble(&targets, 40_000, 1e-8);
            (r.converged, r.iterations)
        };
        let (ok_scaled, n_scaled) = iterations(None);
        let (ok_unscaled, n_unscaled) = iterations(Some(1.0));
        assert!(ok_scaled, "scaled converges");
        // Both must converge: a capped unscaled run would make any ratio hold.
        assert!(
            ok_unscaled,
            "unscaled did not converge in {n_unscaled} iterations"
        );
        assert!(10 * n_scaled < n_unscaled, "{n_scaled} vs {n_unscaled}");
    }
}

/// Settings that would diverge are refused with the stability numbers.
#[test]
fn unstable_gains_are_refused() {
    let s = SolverSettings {
        multiplier_gain: 1e5,
        ..gradient()
    };
    let err = haptloop_solver::Program::new(std::sync::Arc::new(four_bar()), s).unwrap_err();
    assert!(
        matches!(err, haptloop_solver::ProgramError::Unstable { .. }),
        "{err}"
    );
    let s = SolverSettings {
        step: 2.0,
        ..Default::default()
    };
    assert!(haptloop_solver::Program::new(std::sync::Arc::new(four_bar()), s).is_err());
}

/// Projected rule: the same perturbations assemble to round-off in a handful
/// of Gauss–Newton steps, and each step shrinks the violation.
#[test]
fn projected_assembly_converges_in_a_few_steps_on_every_mechanism() {
    for (name, model) in [
        ("four-bar", four_bar()),
        ("stewart", stewart()),
        ("sphere-toy", sphere_toy()),
    ] {
        let targets = model.initial_targets();
        let q = perturbed(&model, 1e-3, 5);
        let mut p = program(model, SolverSettings::default());
        p.set_q(&q).unwrap();
        let mut last = f64::INFINITY;
        for cap in [1, 2, 3] {
            let r = p.assemble(&targets, cap, 1e-13);
            assert_eq!(r.status, TickOutcome::Ok);
            // Each step gains a decade until round-off (1e-14 m).
            let bound = (0.1 * last).max(1e-14);
            assert!(
                r.max_scaled_violation_m < bound,
                "{name}: {r:?} after {last}"
            );
            last = r.max_scaled_violation_m;
        }
        let r = p.assemble(&targets, 20, 1e-12);
        assert!(r.converged && r.iterations < 10, "{name}: {r:?}");
    }
}
