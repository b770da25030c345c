//! Passivity of a virtual wall on the simulated arm held by the simulated hand:
//! energy does not grow inside Colgate's bound, and growth above it is detected
//! and reported.

use haptloop_devices::passivity::{WallTest, run_wall};
use haptloop_devices::{OMNI, PREMIUM_1_5};

#[test]
fn energy_decays_inside_the_passivity_bound_and_grows_above_it() {
    for model in [&PREMIUM_1_5, &OMNI] {
        let template = WallTest::new(model, 1000, 1.0);
        let bound = template.colgate_bound_n_per_m();
        // b = b_arm + b_hand ≈ 1.01–1.03 N·s/m ⇒ bound ≈ 2 kN/m at 1 kHz.
        assert!((2000.0..2100.0).contains(&bound), "{bound}");

        let inside = run_wall(&WallTest {
            stiffness_n_per_m: 0.5 * bound,
            ..template
        })
        .unwrap();
        assert!(inside.initial_excess_j > 0.0);
        // Passive: nothing above the start, and decayed to < 5 % by the end
        // (quantisation leaves a small residual limit cycle, hence not zero).
        assert!(
            inside.peak_excess_j <= inside.initial_excess_j * (1.0 + 1e-9),
            "{}: {inside:?}",
            model.name
        );
        assert!(inside.growth_ratio < 0.05, "{}: {inside:?}", model.name);

        let above = run_wall(&WallTest {
            stiffness_n_per_m: 2.0 * bound,
            ..template
        })
        .unwrap();
        assert!(
            above.grows(),
            "{}: growth above the bound must be detected: {above:?}",
            model.name
        );
        assert!(
            above.growth_ratio > 2.0 && above.late_oscillation_m > 1e-3,
            "{}: {above:?}",
            model.name
        );
    }
}

#[test]
fn virtual_damping_lowers_the_bound_as_colgate_predicts() {
    // B = 0.5 N·s/m of virtual damping from a backward-difference velocity
    // halves the margin: bound = 2(b − B)/T.
    let template = WallTest {
        virtual_damping_n_s_per_m: 0.5,
        ..WallTest::new(&PREMIUM_1_5, 1000, 1.0)
    };
    let bound = template.colgate_bound_n_per_m();
    assert!((bound - 2.0 * (1.0114 - 0.5) / 1e-3).abs() < 1e-6);
    assert!(
        !run_wall(&WallTest {
            stiffness_n_per_m: 0.5 * bound,
            ..template
        })
        .unwrap()
        .grows()
    );
    assert!(
        run_wall(&WallTest {
            stiffness_n_per_m: 4.0 * bound,
            ..template
        })
        .unwrap()
        .grows()
    );
}
