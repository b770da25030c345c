//! `Geometry::scale_free_in_e` checked on every scene of the repository:
//! at a configuration with every body's Euler parameters e off the unit
//! sphere (and off the identity), each row of a kind that claims it has a
//! Jacobian whose e columns are orthogonal to e, and (independently of the
//! Jacobian code) the same value when every e is scaled by 1.7.

use std::collections::BTreeSet;

use super::Geometry;

/// e ⊥ ∂C/∂e to 1e-12 of |e| |∂C/∂e| per row, and C(q) = C(q with e × 1.7)
/// to 1e-12 (1 + |C|), for every row of a scale-free kind in every scene
/// under `scenes/`; the norm rows are the one kind that must fail both.
#[test]
fn every_kind_but_the_norm_is_scale_free_in_e() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut kinds = BTreeSet::new();
    let mut scenes = 0;
    let mut paths: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    for path in paths {
        let model = crate::scene::load(&path).unwrap().compile().unwrap().model;
        scenes += 1;
        let mut q = model.q0().to_vec();
        let moving: Vec<usize> = model.layout().moving_bodies().map(|(_, o)| o).collect();
        for (k, &o) in moving.iter().enumerate() {
            for c in 0..4 {
                q[o + 3 + c] += 0.02 * (((3 * k + c) % 7) as f64 - 3.0);
            }
            let s = 1.0 + 0.1 * (k % 3) as f64;
            for c in 0..4 {
                q[o + 3 + c] *= s;
            }
        }
        let mut scaled = q.clone();
        for &o in &moving {
            for c in 0..4 {
                scaled[o + 3 + c] *= 1.7;
            }
        }
        let targets = model.initial_targets();
        let mut ev = model.evaluation();
        ev.anchor_rolling(&model, &q);
        ev.evaluate(&model, &scaled, &targets).unwrap();
        let c_scaled = ev.values().to_vec();
        ev.evaluate(&model, &q, &targets).unwrap();
        let jac = ev.jacobian();
        let (ptr, cols, vals) = (jac.row_ptr(), jac.col_idx(), jac.values());
        let e_of = |col: usize| {
            moving
                .iter()
                .find(|&&o| col >= o + 3 && col < o + 7)
                .map(|_| q[col])
        };
        for (i, row) in model.rows().iter().enumerate() {
            let g: &Geometry = &model.geometry[row.constraint.index()];
            let (mut dot, mut gn, mut en) = (0.0f64, 0.0f64, 0.0f64);
            for p in ptr[i]..ptr[i + 1] {
                if let Some(e) = e_of(cols[p]) {
                    dot += e * vals[p];
                    gn += vals[p] * vals[p];
                    en += e * e;
                }
            }
            let (gn, en) = (gn.sqrt(), en.sqrt());
            let c = ev.values()[i];
            let value_same = (c - c_scaled[i]).abs() <= 1e-12 * (1.0 + c.abs());
            let orthogonal = dot.abs() <= 1e-12 * gn * en.max(1.0);
            let name = format!("{g:?}");
            let kind = name.split('(').next().unwrap().to_string();
            if g.scale_free_in_e() {
                assert!(
                    orthogonal && value_same,
                    "{}: row {i} ({kind}): eᵀ∂C/∂e = {dot:e} (|∂C/∂e| {gn:e}), C {c:e} → {:e}",
                    path.display(),
                    c_scaled[i]
                );
                if gn > 0.0 {
                    kinds.insert(kind);
                }
            } else {
                assert!(matches!(g, Geometry::QuatNorm(_)));
                assert!(!orthogonal && !value_same, "{}: row {i}", path.display());
            }
        }
    }
    println!("{scenes} scenes; kinds checked on e columns: {kinds:?}");
    assert!(kinds.len() >= 8, "{kinds:?}");
}
