//! Measures the largest stable virtual-wall stiffness of the simulated arms at
//! 1, 4 and 10 kHz, next to Colgate's passivity bound and CHAI3D's published
//! stable stiffness, and prints a Markdown table (pasted into BENCHMARKS.md).
//!
//! Run: `CARGO_TARGET_DIR=target/devices cargo run --release -p haptloop-devices --example stiffness`
//!
//! Deterministic: no clock, no randomness; the same build prints the same table.

use haptloop_devices::passivity::{WallTest, max_stable_stiffness, run_wall};
use haptloop_devices::{Grip, OMNI, PREMIUM_1_5};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    const ITERATIONS: u32 = 14;
    let grips = [
        ("default (300 N/m, 1.0 N·s/m)", Grip::default()),
        ("light (100 N/m, 0.3 N·s/m)", Grip::light()),
    ];
    println!(
        "| model | grip | rate | b = b_arm + b_hand (N·s/m) | Colgate bound 2b/T (N/m) | measured K_max (N/m) | K_max / bound | growth ratio at 2×bound | CHAI3D stable @1 kHz (N/m) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for model in [&PREMIUM_1_5, &OMNI] {
        for (grip_name, grip) in grips {
            for rate in [1000u32, 4000, 10_000] {
                let template = WallTest {
                    grip,
                    ..WallTest::new(model, rate, 1.0)
                };
                let search = max_stable_stiffness(&template, ITERATIONS)?;
                let over = run_wall(&WallTest {
                    stiffness_n_per_m: 2.0 * search.colgate_bound_n_per_m,
                    ..template
                })?;
                println!(
                    "| {} | {} | {} kHz | {:.4} | {:.0} | {:.0} | {:.2} | {:.3e} | {} |",
                    model.name,
                    grip_name,
                    rate / 1000,
                    template.physical_damping_n_s_per_m(),
                    search.colgate_bound_n_per_m,
                    search.k_max_n_per_m,
                    search.k_max_n_per_m / search.colgate_bound_n_per_m,
                    over.growth_ratio,
                    if rate == 1000 {
                        format!("{:.0}", model.stable_stiffness_1khz_n_per_m)
                    } else {
                        "–".into()
                    },
                );
            }
        }
    }
    Ok(())
}
