//! A planar lattice of parallelogram cells built from bars and revolute
//! joints, lying in the horizontal plane: a mesh-like structure whose loops
//! are planar, so most of their rows are redundant in 3-D.
//!
//! Construction for `rows` × `cols` cells ([`lattice_sized`]; the built-in
//! [`lattice`] is 4 × 16): nodes p(i, j) = i·s·x + s·Σ_{k<j} d_k for i =
//! 0..=cols, j = 0..=rows, with s = [`LATTICE_BAR_M`] and d_k the unit vector
//! 30° off y, towards +x for even k and −x for odd k: each row of cells leans
//! the other way from the one below. (Rows leaning alike would put the top
//! row at full stretch, a singular configuration: the finger could not move
//! it across the lean.) Row j = 0 is the
//! fixed `ground`; every other lattice edge is a bar (a slender rod along its
//! body z, [`LATTICE_BAR_KG`]):
//! - `h{i}.{j}`: from p(i, j) to p(i + 1, j), j = 1..=rows;
//! - `v{i}.{j}`: from p(i, j) to p(i, j + 1), j = 0..rows.
//!
//! Joints, all revolute about world z at a node:
//! - `g{i}`: ground–`v{i}.0` at p(i, 0);
//! - at each node p(i, j), j ≥ 1, the bar below it, `v{i}.{j−1}`, is pinned to
//!   every other bar there: `n{i}.{j}w` to `h{i−1}.{j}`, `n{i}.{j}e` to
//!   `h{i}.{j}`, `n{i}.{j}n` to `v{i}.{j}` (where those bars exist).
//!
//! Counts: rows·(2·cols + 1) bars and rows·(3·cols + 1) joints,
//! rows·cols independent loops (one per cell); 4 × 16: 132 bars, 196
//! revolutes, 64 loops. Planar Grübler: 3·bars − 2·joints = rows degrees of
//! freedom (each row of cells shears on its own), which is also the spatial
//! mobility (the axes are parallel, so nothing leaves the plane): of the 5
//! rows a revolute joint has, 3 per loop are redundant (192 on 4 × 16;
//! rank-tested). Finger `index`: point grasp at the middle of the top row's
//! last bar, `h{cols−1}.{rows}`; it can move in the plane, across the lean
//! up to rows·s·(1 − cos 30°) before the rows stand straight (8 mm on 2 × 8).
//! Gravity −z, across the plane: the joints carry it.
//!
//! The scaling family ([`lattice_shape`]): 2 × 8 (34 bars), 4 × 16 (132) and
//! 8 × 32 (520), nominally 32, 128 and 512 bars.

use nalgebra::{UnitQuaternion, Vector3};

use super::{Assembly, rod_inertia, z_to};
use crate::{BodySpec, FingerSpec, JointKind as K, JointSpec, Model, ModelBuilder};

/// Length of every bar (a cell's side), metres.
pub const LATTICE_BAR_M: f64 = 0.03;
/// Mass of every bar, kilograms.
pub const LATTICE_BAR_KG: f64 = 0.01;

const ROWS: usize = 4;
const COLS: usize = 16;
/// The cells' lean: the "vertical" bars of even rows point 30° off the y
/// axis towards +x, those of odd rows 30° towards −x.
const LEAN_DEG: f64 = 30.0;

/// Rows and columns of cells of [`lattice_sized`] for about `bars` bars, as
/// the scaling benchmarks use them: 32 → 2 × 8, 128 → 4 × 16, 512 → 8 × 32.
pub fn lattice_shape(bars: usize) -> Option<(usize, usize)> {
    match bars {
        32 => Some((2, 8)),
        128 => Some((ROWS, COLS)),
        512 => Some((8, 32)),
        _ => None,
    }
}

/// The 4 × 16-cell lattice (132 bars, 196 revolutes), assembled at q0.
pub fn lattice() -> Model {
    lattice_builder()
        .build()
        .expect("the lattice is valid by construction")
}

/// The specs of [`lattice`] before building (bodies, body-frame joints,
/// fingers, gravity), e.g. to write them as a scene file.
pub fn lattice_builder() -> ModelBuilder {
    lattice_sized(ROWS, COLS)
}

/// The specs of a lattice of `rows` × `cols` parallelogram cells (each at
/// least 1), built as [`lattice`] (which is 4 × 16).
pub fn lattice_sized(rows: usize, cols: usize) -> ModelBuilder {
    let (rows, cols) = (rows.max(1), cols.max(1));
    let lean = LEAN_DEG.to_radians();
    let node = |i: usize, j: usize| {
        let up: Vector3<f64> = (0..j)
            .map(|k| {
                let side = if k % 2 == 0 { 1.0 } else { -1.0 };
                Vector3::new(side * lean.sin(), lean.cos(), 0.0)
            })
            .sum();
        (Vector3::x() * i as f64 + up) * LATTICE_BAR_M
    };
    let mut t = Assembly::new();
    t.body(
        BodySpec::fixed("ground"),
        Vector3::zeros(),
        UnitQuaternion::identity(),
    );
    let mut bar = |name: String, a: Vector3<f64>, b: Vector3<f64>| {
        let spec = BodySpec::new(name)
            .mass(LATTICE_BAR_KG)
            .inertia(rod_inertia(LATTICE_BAR_KG, LATTICE_BAR_M));
        t.body(spec, (a + b) / 2.0, z_to(&(b - a).normalize()));
    };
    for j in 0..=rows {
        if j > 0 {
            for i in 0..cols {
                bar(format!("h{i}.{j}"), node(i, j), node(i + 1, j));
            }
        }
        if j < rows {
            for i in 0..=cols {
                bar(format!("v{i}.{j}"), node(i, j), node(i, j + 1));
            }
        }
    }
    let pin = |a: &str, b: &str, at: Vector3<f64>, name: String| -> JointSpec {
        t.joint(K::Revolute, a, b, at, Some([Vector3::z(); 2]))
            .named(name)
    };
    let mut joints = Vec::new();
    for i in 0..=cols {
        joints.push(pin(
            "ground",
            &format!("v{i}.0"),
            node(i, 0),
            format!("g{i}"),
        ));
    }
    for j in 1..=rows {
        for i in 0..=cols {
            let below = format!("v{i}.{}", j - 1);
            let at = node(i, j);
            if i > 0 {
                let h = format!("h{}.{j}", i - 1);
                joints.push(pin(&below, &h, at, format!("n{i}.{j}w")));
            }
            if i < cols {
                let h = format!("h{i}.{j}");
                joints.push(pin(&below, &h, at, format!("n{i}.{j}e")));
            }
            if j < rows {
                let v = format!("v{i}.{j}");
                joints.push(pin(&below, &v, at, format!("n{i}.{j}n")));
            }
        }
    }
    for j in joints {
        t.builder.joint(j);
    }
    t.builder.finger(FingerSpec::point(
        "index",
        format!("h{}.{rows}", cols - 1),
        [0.0; 3],
    ));
    t.builder
}
