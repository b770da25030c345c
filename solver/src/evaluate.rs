//! [`Evaluation`]: the one entry point that fills C(q) and C_q(q) in place.

use nalgebra::{UnitQuaternion, Vector3};

use crate::constraint::block::{Block, Ctx, NoJacobian};
use crate::constraint::witness::Witness;
use crate::jacobian::Jacobian;
use crate::model::initial_frame;
use crate::rotation::BodyFrame;
use crate::{BodyId, FingerId, Model};

mod partial;
mod since;

/// Where a finger should be this tick (world frame). Not a coordinate: changing
/// it never rebuilds anything.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FingerTarget {
    /// Target of the finger's attachment point, metres, world frame.
    pub position_m: Vector3<f64>,
    /// Orientation the held body should have (rigid grasp only; ignored for a
    /// point grasp), body → world.
    pub orientation: UnitQuaternion<f64>,
}

impl FingerTarget {
    /// A target at `position_m` with identity orientation.
    pub fn at(position_m: Vector3<f64>) -> Self {
        Self {
            position_m,
            orientation: UnitQuaternion::identity(),
        }
    }
}

/// Why an evaluation was refused. Heap-free and `Copy` for the fast path; on
/// error the previous values and Jacobian are left untouched, except for
/// [`EvalError::NonFiniteValue`] (reported after writing).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum EvalError {
    /// The evaluation was created for a different model.
    #[error("this evaluation was created for another model")]
    ModelMismatch,
    /// q has the wrong length.
    #[error("q has {got} entries; the model has {expected} coordinates")]
    CoordinateCount {
        /// Coordinates of the model.
        expected: usize,
        /// Entries given.
        got: usize,
    },
    /// The targets slice has the wrong length.
    #[error("{got} finger targets given; the model has {expected} fingers")]
    TargetCount {
        /// Fingers of the model.
        expected: usize,
        /// Targets given.
        got: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("q[{index}] is not finite")]
    NonFiniteCoordinate {
        /// Its index in q.
        index: usize,
    },
    /// A finger target is NaN or infinite.
    #[error("the target of {finger} is not finite")]
    NonFiniteTarget {
        /// The finger.
        finger: FingerId,
    },
    /// A body's Euler parameters are (nearly) zero or so large that |e|²
    /// overflows, so it has no rotation.
    #[error("{body} has a degenerate quaternion (|e|² below 1e-12 or not finite)")]
    DegenerateQuaternion {
        /// The body.
        body: BodyId,
    },
    /// A value of C overflowed (coordinates astronomically large).
    #[error("row {row} of C is not finite")]
    NonFiniteValue {
        /// The row.
        row: usize,
    },
}

/// Scratch, values of C and the Jacobian C_q of one [`Model`], allocated once by
/// [`Evaluation::new`] and rewritten in place by every evaluation.
#[derive(Debug, Clone)]
pub struct Evaluation {
    model_id: u64,
    /// One per body (fixed bodies pre-filled), then the world.
    pub(crate) frames: Vec<BodyFrame>,
    values: Vec<f64>,
    jacobian: Jacobian,
    /// Parameters of the contact rows, one per slot (see
    /// [`crate::constraint::witness`]).
    witnesses: Vec<Witness>,
    /// The rolling rows' tick-start anchors (`crate::parametric::rolling`),
    /// off until [`Evaluation::anchor_rolling`] sets them.
    pub(crate) rolling: Vec<crate::parametric::rolling::RollAnchor>,
    /// What the rows were written from (`since`; off by default).
    since: since::Since,
}

impl Evaluation {
    /// Every moving body's frame from `q` (those `moved` marks false kept:
    /// an empty `moved` recomputes all), then the freed origins' positions.
    fn set_frames(&mut self, model: &Model, q: &[f64], moved: &[bool]) -> Result<(), EvalError> {
        for (body, o) in model.layout.moving_bodies() {
            if !moved.get(body.index()).copied().unwrap_or(true) {
                continue;
            }
            let r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            let e = [q[o + 3], q[o + 4], q[o + 5], q[o + 6]];
            self.frames[body.index()] =
                BodyFrame::new(r, e).ok_or(EvalError::DegenerateQuaternion { body })?;
        }
        for (b, o) in model.layout.origin_cols.iter().enumerate() {
            if let Some(o) = *o {
                self.frames[b].r = Vector3::new(q[o], q[o + 1], q[o + 2]);
            }
        }
        Ok(())
    }

    /// Allocates everything an evaluation of `model` needs: C (n_rows), the
    /// Jacobian pattern and per-body scratch.
    pub fn new(model: &Model) -> Self {
        let mut frames: Vec<BodyFrame> = model.bodies.iter().map(initial_frame).collect();
        frames.push(BodyFrame::IDENTITY);
        Self {
            model_id: model.id,
            frames,
            values: vec![0.0; model.n_rows()],
            jacobian: Jacobian::new(model),
            witnesses: {
                // Contact slots at the head, semantic surface rows at the
                // tail (`constraint/surface.rs`).
                let mut w = vec![Witness::Off; model.contact.slots];
                w.extend(model.semantic.slots.iter().map(|p| Witness::Plane(*p)));
                w
            },
            rolling: vec![crate::parametric::rolling::RollAnchor::OFF; model.rolling.len()],
            since: since::Since::default(),
        }
    }

    /// C at the last successful evaluation (equalities first, then `≥ 0` rows;
    /// see [`Model::rows`]).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Every body's frame at the last evaluation, then the world's.
    pub(crate) fn frames(&self) -> &[BodyFrame] {
        &self.frames
    }

    /// C_q at the last successful [`evaluate`](Self::evaluate).
    pub fn jacobian(&self) -> &Jacobian {
        &self.jacobian
    }

    /// The witness table: the parameters of the model's contact rows, one
    /// entry per slot ([`Model::contact`]; all `Off` until set), followed by
    /// the semantic surface rows' ([`Model::semantic`]).
    pub fn witnesses(&self) -> &[Witness] {
        &self.witnesses
    }

    /// The witness table, to change in place.
    ///
    /// # Real-time
    /// No allocation: the table's length is fixed by the model.
    pub fn witnesses_mut(&mut self) -> &mut [Witness] {
        self.since.touch();
        &mut self.witnesses
    }

    /// Fills C(q) and C_q(q) for configuration `q` and one target per finger.
    ///
    /// # Real-time
    /// No allocation, no locks, no syscalls. Time is bounded by O(bodies + nnz):
    /// one pass over q, one frame per moving body, one fixed-size block per
    /// constraint.
    pub fn evaluate(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), EvalError> {
        self.run(model, q, targets, true)
    }

    /// Fills C(q) only (line searches, residual reports); the Jacobian keeps its
    /// previous values. Same real-time properties as [`evaluate`](Self::evaluate).
    pub fn evaluate_values(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
    ) -> Result<(), EvalError> {
        self.run(model, q, targets, false)
    }

    fn run(
        &mut self,
        model: &Model,
        q: &[f64],
        targets: &[FingerTarget],
        jac: bool,
    ) -> Result<(), EvalError> {
        if model.id != self.model_id {
            return Err(EvalError::ModelMismatch);
        }
        check_inputs(model, q, targets)?;
        // Frames are scratch: a failure here leaves C and C_q untouched.
        self.set_frames(model, q, &[])?;
        let tracked = self.since.on();
        if tracked {
            self.since.mark(q, &self.witnesses);
        }
        let Self {
            frames,
            values,
            jacobian,
            witnesses,
            rolling,
            since,
            ..
        } = self;
        let x = Ctx {
            q,
            frames,
            targets,
            witnesses,
            flex: &model.flex_anchors,
            surfaces: &model.surfaces,
            rolling,
        };
        let (blocks, vals) = jacobian.blocks_and_values_mut();
        let flexible = !model.flex_anchors.is_empty();
        for (k, ((g, info), b)) in model
            .geometry
            .iter()
            .zip(&model.constraints)
            .zip(blocks)
            .enumerate()
        {
            if tracked && since.keeps(k) {
                continue;
            }
            let c = &mut values[info.rows.clone()];
            if jac {
                let [f0, f1] = g.frames();
                let flex = if flexible {
                    g.anchors().map(|a| match a {
                        crate::constraint::block::Param3::Flex(i) => {
                            Some(&model.flex_anchors[i as usize])
                        }
                        _ => None,
                    })
                } else {
                    [None, None]
                };
                let mut sink = Block {
                    vals: &mut vals[b.start..b.start + c.len() * b.width],
                    width: b.width,
                    pos: b.pos,
                    frames: [&frames[f0], &frames[f1]],
                    flex,
                };
                g.eval(&x, c, &mut sink);
            } else {
                g.eval(&x, c, &mut NoJacobian);
                if tracked {
                    since.wrote_value(k);
                }
            }
        }
        if tracked && jac {
            since.wrote_jacobian(q, witnesses);
        }
        if all_finite(values) {
            return Ok(());
        }
        let row = values.iter().position(|v| !v.is_finite()).unwrap_or(0);
        Err(EvalError::NonFiniteValue { row })
    }
}

/// The checks every evaluation of `model` at `q` toward `targets` makes
/// first: coordinate and target counts, finite coordinates and targets.
#[inline]
pub(crate) fn check_inputs(
    model: &Model,
    q: &[f64],
    targets: &[FingerTarget],
) -> Result<(), EvalError> {
    let (expected, got) = (model.n_coords(), q.len());
    if expected != got {
        return Err(EvalError::CoordinateCount { expected, got });
    }
    let (expected, got) = (model.fingers.len(), targets.len());
    if expected != got {
        return Err(EvalError::TargetCount { expected, got });
    }
    if !all_finite(q) {
        let index = q.iter().position(|v| !v.is_finite()).unwrap_or(0);
        return Err(EvalError::NonFiniteCoordinate { index });
    }
    for (k, t) in targets.iter().enumerate() {
        let finite = t
            .position_m
            .iter()
            .chain(t.orientation.coords.iter())
            .all(|v| v.is_finite());
        if !finite {
            return Err(EvalError::NonFiniteTarget {
                finger: FingerId(k as u32),
            });
        }
    }
    Ok(())
}

/// True when every entry is finite: a branch-free sum of `v · 0` (NaN iff some
/// v is NaN or infinite) that vectorises, unlike an early-exit search.
#[inline]
pub(crate) fn all_finite(v: &[f64]) -> bool {
    let mut lanes = [0.0f64; 4];
    let mut chunks = v.chunks_exact(4);
    for c in &mut chunks {
        for k in 0..4 {
            lanes[k] += c[k] * 0.0;
        }
    }
    let tail: f64 = chunks.remainder().iter().map(|x| x * 0.0).sum();
    (lanes[0] + lanes[1] + lanes[2] + lanes[3] + tail) == 0.0
}

impl Model {
    /// Shorthand for [`Evaluation::new`].
    pub fn evaluation(&self) -> Evaluation {
        Evaluation::new(self)
    }
}
