//! The multilevel preconditioner against dense products of the same
//! operators, and as a preconditioner against a dense solve.

use super::super::small::cholesky_solve;
use super::multilevel::{MODES, Multilevel};
use super::step::StepCg;
use super::tests::{assembled, assembled_with, dense};
use crate::mechanisms::{lattice_shape, lattice_sized, sphere_toy_shape, sphere_toy_sized};

/// The finest level holds A_JJ (permuted, exactly), and every coarser
/// level's operator, formed block by block, equals Tᵀ A T formed from the
/// dense matrices (to round-off), on a lattice and a sphere toy large
/// enough for two coarsenings or more.
#[test]
fn the_galerkin_operators_equal_the_dense_products() {
    let (lr, lc) = lattice_shape(128).unwrap();
    let (sr, sc) = sphere_toy_shape(132).unwrap();
    for (name, model) in [
        ("lattice 128", lattice_sized(lr, lc).build().unwrap()),
        ("sphere toy 132", sphere_toy_sized(sr, sc).build().unwrap()),
    ] {
        let (gram, group) = assembled(&model);
        let mut ml = Multilevel::new(&gram, &group, MODES);
        ml.factor(&gram).unwrap();
        assert!(ml.depth() >= 3, "{name}: {} levels", ml.depth());
        let (a, n) = (dense(&gram), gram.n_j);
        let (d0, n0) = ml.dense_level(0);
        assert_eq!(n0, n);
        let p = ml.perm();
        for i in 0..n {
            for j in 0..n {
                assert_eq!(d0[p[i] * n + p[j]], a[i * n + j], "{name} ({i}, {j})");
            }
        }
        for l in 0..ml.depth() - 1 {
            let (fine, nf) = ml.dense_level(l);
            let (coarse, nc) = ml.dense_level(l + 1);
            let t = ml.dense_t(l);
            let big = coarse.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            // T's nonzero rows per column, then A T, then Tᵀ (A T).
            let nz: Vec<Vec<usize>> = (0..nc)
                .map(|c| (0..nf).filter(|&i| t[i * nc + c] != 0.0).collect())
                .collect();
            let mut at = vec![0.0; nf * nc];
            for c in 0..nc {
                for &j in &nz[c] {
                    for i in 0..nf {
                        at[i * nc + c] += fine[i * nf + j] * t[j * nc + c];
                    }
                }
            }
            for r in 0..nc {
                for c in 0..nc {
                    let v: f64 = nz[r].iter().map(|&i| t[i * nc + r] * at[i * nc + c]).sum();
                    let got = coarse[r * nc + c];
                    assert!(
                        (got - v).abs() <= 1e-11 * big,
                        "{name} level {l}: ({r}, {c}) {got:e} against {v:e}"
                    );
                }
            }
        }
    }
}

/// The V-cycle is a symmetric positive definite operator (so it serves
/// conjugate gradients), and CG preconditioned by it solves A_JJ x = b to
/// the dense Cholesky solution, in fewer iterations than CG preconditioned
/// by A's diagonal on the same system (sphere toy, 33 bodies).
#[test]
fn the_v_cycle_preconditions_cg_to_the_dense_solution() {
    let (r, c) = sphere_toy_shape(33).unwrap();
    let model = sphere_toy_sized(r, c).build().unwrap();
    let (gram, group) = assembled(&model);
    let n = gram.n_j;
    let mut ml = Multilevel::new(&gram, &group, MODES);
    ml.factor(&gram).unwrap();
    assert!(ml.depth() >= 2);
    // M⁻¹ column by column.
    let mut m = vec![0.0; n * n];
    for j in 0..n {
        let col = &mut m[j * n..(j + 1) * n];
        col[j] = 1.0;
        ml.apply(col, 1);
    }
    let big = m.iter().fold(0.0f64, |b, v| b.max(v.abs()));
    for i in 0..n {
        for j in 0..i {
            let (a, b) = (m[i * n + j], m[j * n + i]);
            assert!((a - b).abs() <= 1e-10 * big, "({i}, {j}): {a:e} {b:e}");
        }
    }
    let mut spd = m.clone();
    assert!(cholesky_solve(&mut spd, &mut vec![1.0; n]), "M⁻¹ not SPD");
    // The system and its dense solution.
    let b: Vec<f64> = (0..n).map(|i| ((i * 7 % 11) as f64 - 5.0) * 0.1).collect();
    let mut want = b.clone();
    assert!(cholesky_solve(&mut dense(&gram), &mut want));
    let mut cg = StepCg::new(n, 1000);
    let mut x = b.clone();
    let rel = cg.solve(&gram, &mut x, 1e-12, |v| ml.apply(v, 1));
    assert!(rel <= 1e-12, "residual {rel:e}");
    let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (g, w) in x.iter().zip(&want) {
        assert!((g - w).abs() <= 1e-7 * scale, "{g:e} against {w:e}");
    }
    let ml_its = cg.iterations;
    let inv_diag: Vec<f64> = gram.diag.iter().map(|&d| 1.0 / gram.values[d]).collect();
    let mut jac = StepCg::new(n, 1000);
    let mut x = b.clone();
    jac.solve(&gram, &mut x, 1e-12, |v| {
        v.iter_mut().zip(&inv_diag).for_each(|(a, d)| *a *= d)
    });
    assert!(
        ml_its < jac.iterations,
        "multilevel {ml_its}, Jacobi {}",
        jac.iterations
    );
}

/// Iterations of CG with the V-cycle from zero to 1e-8 on a consistent
/// system, per size (prints; `cargo test --release -p haptloop-solver --lib
/// probe_multilevel_iterations -- --ignored --nocapture`).
#[test]
#[ignore]
fn probe_multilevel_iterations() {
    use super::multilevel::Prolongation;
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let modes = env("ML_MODES", MODES);
    let sweeps = env("ML_SWEEPS", 20);
    let mut models = Vec::new();
    for b in [32, 128, 512] {
        let (r, c) = lattice_shape(b).unwrap();
        models.push((format!("lattice {b}"), lattice_sized(r, c).build().unwrap()));
    }
    for b in [33, 132, 400] {
        let (r, c) = sphere_toy_shape(b).unwrap();
        models.push((
            format!("sphere {b}"),
            sphere_toy_sized(r, c).build().unwrap(),
        ));
    }
    for (name, model) in models {
        // The tick's pattern: quaternion-norm rows in their bodies' cliques.
        let (gram, group) = assembled_with(&model, false);
        let n = gram.n_j;
        let mut ml = Multilevel::new(&gram, &group, modes);
        ml.prolongation = if sweeps == 0 {
            Prolongation::Eigen
        } else {
            Prolongation::Relaxed(sweeps)
        };
        ml.factor(&gram).unwrap();
        let xs: Vec<f64> = (0..n)
            .map(|i| ((i * 7919 % 101) as f64 - 50.0) / 50.0)
            .collect();
        let mut b = vec![0.0; n];
        super::super::cg::sym_mul(&gram, &xs, &mut b);
        let mut cg = StepCg::new(n, 2000);
        let mut x = b.clone();
        let rel = cg.solve(&gram, &mut x, 1e-8, |v| ml.apply(v, 1));
        let inv_diag: Vec<f64> = gram.diag.iter().map(|&d| 1.0 / gram.values[d]).collect();
        let mut jac = StepCg::new(n, 5000);
        let mut x = b.clone();
        jac.solve(&gram, &mut x, 1e-8, |v| {
            v.iter_mut().zip(&inv_diag).for_each(|(a, d)| *a *= d)
        });
        // Thread-free timings, median of 51: one product with A_JJ, one
        // V-cycle, one refresh of the levels (Galerkin + coarsest factor).
        let time = |f: &mut dyn FnMut()| {
            let mut t: Vec<f64> = (0..51)
                .map(|_| {
                    let s0 = std::time::Instant::now();
                    f();
                    s0.elapsed().as_secs_f64() * 1e6
                })
                .collect();
            t.sort_by(f64::total_cmp);
            t[25]
        };
        let mut y = vec![0.0; n];
        let t_mul = time(&mut || super::super::cg::sym_mul(&gram, &xs, &mut y));
        let t_v = time(&mut || {
            y.copy_from_slice(&b);
            ml.apply(&mut y, 1)
        });
        let t_f = time(&mut || ml.factor(&gram).unwrap());
        println!(
            "{name}: n {n}, levels {:?} nodes {:?}, multilevel {} it. (rel {rel:.1e}), Jacobi {} it.; A x {t_mul:.1} µs, V-cycle {t_v:.1} µs, refresh {t_f:.1} µs",
            ml.stats(0).rows,
            ml.stats(0).nodes,
            cg.iterations,
            jac.iterations
        );
    }
}
