//! Compiling a dexterity objective's chain (Eq. 13/14): the path's joint
//! columns, a closed chain's loop joints, the task rows (linear and Eq. 13's
//! angular ones) and the reach at q0. Split from `compile`.

use nalgebra::Vector3;

use super::compile::Bad;
use super::dexterity::{Axis, Column, Dexterity};
use crate::constraint::Geometry;
use crate::constraint::block::Param3;
use crate::model::{BuildError, Owner};
use crate::{BodyId, Model};

/// A dexterity objective's chain as the spec gives it.
pub(super) struct ChainSpec<'a> {
    pub chain: &'a [String],
    pub closure: &'a [String],
    pub point_m: &'a [f64; 3],
    pub directions: &'a [[f64; 3]],
    pub angular: &'a [[f64; 3]],
}

/// The chain's columns (path, then the loop's closing joints), the tip, the
/// task rows and the reach at q0; a closed chain must move its point in at
/// least as many directions as it has task rows.
pub(super) fn dexterity(
    model: &Model,
    spec: &ChainSpec,
    owner: &dyn Fn() -> Owner,
    bad: Bad,
) -> Result<Dexterity, BuildError> {
    let chain = spec.chain;
    if chain.len() < 2 {
        return Err(bad("chain", "at least two bodies, base first"));
    }
    let id = |n: &String| {
        model.body_id(n).ok_or_else(|| BuildError::UnknownBody {
            owner: owner(),
            body: n.clone(),
        })
    };
    let ids = chain.iter().map(id).collect::<Result<Vec<BodyId>, _>>()?;
    let closing = spec
        .closure
        .iter()
        .map(id)
        .collect::<Result<Vec<BodyId>, _>>()?;
    let revisits = closing[..closing.len().saturating_sub(1)]
        .iter()
        .enumerate()
        .any(|(k, b)| ids.contains(b) || closing[..k].contains(b));
    if !closing.is_empty() && (closing.last() != ids.first() || revisits) {
        return Err(bad(
            "closure",
            "bodies not in the chain, from after its last body back to its base (the last one)",
        ));
    }
    let mut columns = Vec::new();
    let mut points = Vec::new(); // joint points at q0, for the reach
    let frame = |b: usize| model.body_frame(model.q0(), BodyId(b as u32));
    for (k, pair) in ids.windows(2).enumerate() {
        let (p, cols) = joint_columns(model, pair, [&chain[k], &chain[k + 1]], true, owner)?;
        columns.extend(cols);
        let f = frame(p.frame[0]).unwrap_or(crate::rotation::BodyFrame::IDENTITY);
        let k0 = match p.anchor[0] {
            Param3::Const(v) => v,
            Param3::Free(c) => Vector3::new(model.q0()[c], model.q0()[c + 1], model.q0()[c + 2]),
            Param3::Flex(i) => model.flex_anchors[i as usize].k,
        };
        points.push(f.point(&k0));
    }
    let last = *ids.last().expect("two or more");
    if model.bodies()[last.index()].fixed {
        // The point rides on the last body: on a fixed one it never moves,
        // J̃ is zero and F sits at its floor for good.
        return Err(bad(
            "chain",
            "base first, tip last: its last body is fixed, so its point never moves (is the chain reversed?)",
        ));
    }
    let mut around = vec![last];
    around.extend(&closing);
    let mut names = vec![chain.last().expect("two or more")];
    names.extend(spec.closure);
    for (k, pair) in around.windows(2).enumerate() {
        let (_, cols) = joint_columns(model, pair, [names[k], names[k + 1]], false, owner)?;
        columns.extend(cols);
    }
    let tip = Vector3::from(*spec.point_m);
    if let Some(f) = frame(last.index()) {
        points.push(f.point(&tip));
    }
    let reach = points
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .sum::<f64>()
        .max(1e-3);
    let xyz = [Vector3::x(), Vector3::y(), Vector3::z()];
    let (directions, rows) = task_rows(spec.directions, xyz, "directions", bad)?;
    let (angular, angular_rows) = task_rows(spec.angular, xyz, "angular_directions", bad)?;
    // No `directions`: the world's x, y, z (with or without angular rows).
    let rows = if spec.directions.is_empty() { 3 } else { rows };
    let d = Dexterity {
        columns,
        tip: (last, tip),
        directions,
        rows,
        angular,
        angular_rows,
        reach_m: reach,
        closed: !closing.is_empty(),
    };
    if d.closed {
        let mut g = super::grad::BodyGrad::new(model);
        g.frames(model, model.q0())
            .map_err(|_| bad("closure", "a chain with a finite pose at the start"))?;
        let dof = d.loop_dof(&g, model.q0());
        if dof == 0 {
            return Err(bad(
                "closure",
                "a loop that can move (this one is rigid at the start)",
            ));
        }
        if rows + angular_rows > dof {
            return Err(bad(
                "directions",
                "no more task directions (with angular_directions) than the closed chain has degrees of freedom",
            ));
        }
    }
    Ok(d)
}

/// One joint's columns between successive bodies `pair` (named `names`).
fn joint_columns(
    model: &Model,
    pair: &[BodyId],
    names: [&String; 2],
    on_path: bool,
    owner: &dyn Fn() -> Owner,
) -> Result<(crate::constraint::block::Pair, Vec<Column>), BuildError> {
    let (a, b) = (pair[0], pair[1]);
    let joint = model.constraints().iter().enumerate().find(|(_, c)| {
        c.finger.is_none()
            && c.limits.is_none()
            && (c.bodies == [Some(a), Some(b)] || c.bodies == [Some(b), Some(a)])
    });
    let Some((ci, info)) = joint else {
        return Err(BuildError::ChainNotJoined {
            owner: owner(),
            a: names[0].clone(),
            b: names[1].clone(),
        });
    };
    let origin = |p: &crate::constraint::block::Pair| Some((p.frame[0], p.anchor[0]));
    let world = |i: usize| Axis::World(Vector3::ith(i, 1.0));
    let col = |axis, origin| Column {
        axis,
        origin,
        on_path,
    };
    Ok(match &model.geometry[ci] {
        Geometry::Revolute(j) => (
            j.pair,
            vec![col(
                Axis::Body(j.pair.frame[0], j.axes.h_i),
                origin(&j.pair),
            )],
        ),
        Geometry::Prismatic(j) => (
            j.pair,
            vec![col(Axis::Body(j.pair.frame[0], j.axes.h_i), None)],
        ),
        Geometry::Spherical(j) => (
            j.pair,
            (0..3).map(|i| col(world(i), origin(&j.pair))).collect(),
        ),
        Geometry::Universal(j) => (
            j.pair,
            (0..2)
                .map(|e| col(Axis::Body(j.pair.frame[e], j.axes[e]), origin(&j.pair)))
                .collect(),
        ),
        _ => {
            return Err(BuildError::ChainJointKind {
                owner: owner(),
                joint: info.name.clone(),
                kind: info.kind,
            });
        }
    })
}

/// Up to three independent unit world directions (`given`, normalised) and
/// how many were given (the rest of the array is `default`).
fn task_rows(
    given: &[[f64; 3]],
    default: [Vector3<f64>; 3],
    field: &'static str,
    bad: Bad,
) -> Result<([Vector3<f64>; 3], usize), BuildError> {
    let mut dirs = default;
    if given.len() > 3 {
        return Err(bad(field, "one to three world directions"));
    }
    for (d, v) in dirs.iter_mut().zip(given) {
        let v = Vector3::from(*v);
        if v.norm() < 1e-12 {
            return Err(bad(field, "non-zero vectors"));
        }
        *d = v.normalize();
    }
    let n = given.len();
    let gram = nalgebra::DMatrix::from_fn(n, n, |a, b| dirs[a].dot(&dirs[b]));
    if n > 0 && gram.determinant() < 1e-6 {
        return Err(bad(field, "independent (not parallel) directions"));
    }
    Ok((dirs, n))
}
