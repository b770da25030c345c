//! The spanning tree of the joint graph: which joints are tree joints (their
//! rates are the joint coordinates) and which close loops (their rows stay
//! rows, like the fingers').
//!
//! Nodes are the moving bodies and one ground node (the world and every
//! fixed body); edges are the joints this module knows (revolute,
//! universal, spherical, prismatic). The tree is found breadth-first from
//! the ground, joints taken in model order, so the tree is the shallowest
//! one and deterministic. Every moving body must be reached: a floating
//! body has no joint coordinates here.

use std::collections::VecDeque;

use nalgebra::Vector3;

use super::ReducedError;
use crate::constraint::Geometry;
use crate::constraint::block::Param3;
use crate::{BodyId, ConstraintKind, Model};

/// How a tree joint lets its child move relative to its parent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Freedom {
    /// One rotation about the axis of the child end (`axes[child_end]`,
    /// body frames of ends i and j).
    Revolute { axes: [Vector3<f64>; 2] },
    /// Two rotations: about `axes[0]` (body frame of end i) and `axes[1]`
    /// (body frame of end j).
    Universal { axes: [Vector3<f64>; 2] },
    /// Three rotations about the world axes.
    Spherical,
    /// One translation along `axis` (body frame of end i).
    Prismatic { axis: Vector3<f64> },
    /// None: a weld (the child moves with its parent).
    Fixed,
}

impl Freedom {
    /// Number of joint coordinates.
    pub fn dofs(&self) -> usize {
        match self {
            Self::Revolute { .. } | Self::Prismatic { .. } => 1,
            Self::Universal { .. } => 2,
            Self::Spherical => 3,
            Self::Fixed => 0,
        }
    }
}

/// One tree joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TreeJoint {
    /// The constraint.
    pub constraint: usize,
    /// The parent body (`None`: ground).
    pub parent: Option<BodyId>,
    /// The child body (always moving).
    pub child: BodyId,
    /// Which end of the constraint (0 = i, 1 = j) the child is.
    pub child_end: usize,
    /// The tree joint whose child is `parent` (`None`: parent is ground).
    pub parent_joint: Option<usize>,
    /// The body-frame anchors of ends i and j.
    pub anchors: [Vector3<f64>; 2],
    /// The end bodies (`None`: world), i then j.
    pub ends: [Option<BodyId>; 2],
    pub freedom: Freedom,
    /// First joint coordinate.
    pub dof: usize,
}

/// The spanning tree and the partition of the rows.
#[derive(Debug, Clone)]
pub struct JointTree {
    /// Tree joints in breadth-first order (a parent before its children).
    pub(crate) joints: Vec<TreeJoint>,
    /// For each body (model order): the tree joint whose child it is.
    pub(crate) joint_of_body: Vec<Option<usize>>,
    /// Joint coordinates.
    pub(crate) dofs: usize,
    /// Equality rows kept as rows: the loop-closing joints' and any other
    /// non-finger equality constraint's (not the tree joints', not the
    /// quaternion norms').
    pub(crate) loop_rows: Vec<usize>,
    /// Finger rows.
    pub(crate) finger_rows: Vec<usize>,
    /// Rows of the tree joints (for tests).
    pub(crate) tree_rows: Vec<usize>,
    /// The quaternion-norm rows.
    pub(crate) norm_rows: Vec<usize>,
    /// The joint limits' rows (`limits`).
    pub(crate) limit_rows: Vec<usize>,
}

fn is_ground(model: &Model, b: Option<BodyId>) -> bool {
    b.is_none_or(|b| model.layout().body_offset(b).is_none())
}

fn constant(p: &Param3) -> Option<Vector3<f64>> {
    match *p {
        Param3::Const(v) => Some(v),
        _ => None,
    }
}

/// The freedom and anchors of a joint constraint, `None` for other kinds.
fn joint_data(g: &Geometry) -> Option<(Freedom, [Param3; 2])> {
    Some(match g {
        Geometry::Revolute(j) => (
            Freedom::Revolute {
                axes: [j.axes.h_i, j.axes.h_j],
            },
            j.pair.anchor,
        ),
        Geometry::Universal(j) => (Freedom::Universal { axes: j.axes }, j.pair.anchor),
        Geometry::Spherical(j) => (Freedom::Spherical, j.pair.anchor),
        Geometry::Prismatic(j) => (Freedom::Prismatic { axis: j.axes.h_i }, j.pair.anchor),
        Geometry::Weld(j) => (Freedom::Fixed, j.pair.anchor),
        _ => return None,
    })
}

/// The tree joints found breadth-first (`JointTree::new`).
struct Grown {
    joints: Vec<TreeJoint>,
    joint_of_body: Vec<Option<usize>>,
    /// Per constraint: a tree joint.
    is_tree: Vec<bool>,
    /// Per body: reached from the ground.
    reached: Vec<bool>,
    dofs: usize,
}

/// Design variables, auxiliary columns and inequality rows other than
/// revolute and prismatic limits are refused.
fn refuse_unhandled(model: &Model) -> Result<(), ReducedError> {
    let layout = model.layout();
    if layout.design_coords() > 0 || layout.aux_coords() > 0 {
        return Err(ReducedError::Unsupported(
            "design variables or auxiliary columns".into(),
        ));
    }
    let limit = |r: usize| {
        let k = model.constraints()[model.rows()[r].constraint.index()].kind;
        matches!(
            k,
            ConstraintKind::RevoluteLimit | ConstraintKind::PrismaticLimit
        )
    };
    if !model.inequality_rows().all(limit) {
        return Err(ReducedError::Unsupported(
            "inequality rows other than revolute and prismatic limits".into(),
        ));
    }
    Ok(())
}

/// Which end of a joint with ends `bodies` is the child when it leaves
/// `node` (`None`: the ground) toward a moving body; `None` if it does not.
fn child_end(model: &Model, node: Option<BodyId>, bodies: [Option<BodyId>; 2]) -> Option<usize> {
    let [a, b] = bodies;
    let at_node = |x: Option<BodyId>| match node {
        None => is_ground(model, x),
        Some(n) => x == Some(n),
    };
    if at_node(a) && !is_ground(model, b) {
        Some(1)
    } else if at_node(b) && !is_ground(model, a) {
        Some(0)
    } else {
        None
    }
}

/// The tree joints breadth-first from the ground, joints in model order.
fn grow(model: &Model) -> Result<Grown, ReducedError> {
    let nb = model.bodies().len();
    let mut g = Grown {
        joints: Vec::new(),
        joint_of_body: vec![None; nb],
        is_tree: vec![false; model.constraints().len()],
        reached: vec![false; nb],
        dofs: 0,
    };
    let mut queue: VecDeque<Option<BodyId>> = VecDeque::from([None]);
    while let Some(node) = queue.pop_front() {
        for (k, info) in model.constraints().iter().enumerate() {
            let Some((freedom, anchors)) = joint_data(&model.geometry[k]) else {
                continue;
            };
            if g.is_tree[k] {
                continue;
            }
            let Some(child_end) = child_end(model, node, info.bodies) else {
                continue;
            };
            let child = info.bodies[child_end].expect("moving");
            if g.reached[child.index()] {
                continue;
            }
            let anchors = [constant(&anchors[0]), constant(&anchors[1])];
            let [Some(ai), Some(aj)] = anchors else {
                return Err(ReducedError::Unsupported(format!(
                    "joint `{}` has a free anchor",
                    info.name
                )));
            };
            g.reached[child.index()] = true;
            g.is_tree[k] = true;
            g.joint_of_body[child.index()] = Some(g.joints.len());
            g.joints.push(TreeJoint {
                constraint: k,
                parent: node,
                child,
                child_end,
                parent_joint: node.and_then(|n| g.joint_of_body[n.index()]),
                anchors: [ai, aj],
                ends: info.bodies,
                freedom,
                dof: g.dofs,
            });
            g.dofs += freedom.dofs();
            queue.push_back(Some(child));
        }
    }
    Ok(g)
}

impl JointTree {
    /// The breadth-first spanning tree of `model`'s joint graph.
    ///
    /// # Errors
    /// Design variables, auxiliary columns, free anchors, inequality rows
    /// other than revolute and prismatic limits, or a moving body no joint path connects to the ground.
    pub fn new(model: &Model) -> Result<Self, ReducedError> {
        refuse_unhandled(model)?;
        let g = grow(model)?;
        let layout = model.layout();
        if let Some((id, _)) = layout.moving_bodies().find(|(b, _)| !g.reached[b.index()]) {
            return Err(ReducedError::Unsupported(format!(
                "body `{}` is not connected to the ground by joints",
                model.bodies()[id.index()].name
            )));
        }
        let (mut loop_rows, mut finger_rows, mut tree_rows, mut norm_rows) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut limit_rows = Vec::new();
        for (k, info) in model.constraints().iter().enumerate() {
            let dest = if g.is_tree[k] {
                &mut tree_rows
            } else if info.kind.sense() == crate::Sense::Inequality {
                &mut limit_rows
            } else if info.finger.is_some() {
                &mut finger_rows
            } else if info.kind == ConstraintKind::QuaternionNorm {
                &mut norm_rows
            } else {
                &mut loop_rows
            };
            dest.extend(info.rows.clone());
        }
        Ok(Self {
            joints: g.joints,
            joint_of_body: g.joint_of_body,
            dofs: g.dofs,
            loop_rows,
            finger_rows,
            tree_rows,
            norm_rows,
            limit_rows,
        })
    }

    /// Number of joint coordinates (the tree's degrees of freedom).
    pub fn dofs(&self) -> usize {
        self.dofs
    }

    /// Rows kept as rows besides the fingers' (loop closures).
    pub fn loop_rows(&self) -> &[usize] {
        &self.loop_rows
    }

    /// Finger rows.
    pub fn finger_rows(&self) -> &[usize] {
        &self.finger_rows
    }

    /// Rows of the tree joints (they vanish along S).
    pub fn tree_rows(&self) -> &[usize] {
        &self.tree_rows
    }

    /// The quaternion-norm rows.
    pub fn norm_rows(&self) -> &[usize] {
        &self.norm_rows
    }

    /// Tree joints.
    pub fn tree_joints(&self) -> usize {
        self.joints.len()
    }

    /// Over every joint coordinate, the joint coordinates on its path to
    /// the ground (its own joint's included): their sum (the entries of H
    /// and of a body's projection the tick touches) and their largest (the
    /// deepest path). The joint tick's cost model reads them.
    pub(crate) fn path_dofs(&self) -> (usize, usize) {
        let mut above = vec![0usize; self.joints.len()];
        let (mut sum, mut deepest) = (0, 0);
        for (k, j) in self.joints.iter().enumerate() {
            let own = j.freedom.dofs();
            above[k] = own + j.parent_joint.map_or(0, |p| above[p]);
            sum += own * above[k];
            deepest = deepest.max(above[k]);
        }
        (sum, deepest)
    }

    /// The tree joints from `body` up to the ground (the body's own first).
    pub(crate) fn path(&self, body: BodyId) -> impl Iterator<Item = &TreeJoint> + '_ {
        let mut next = self.joint_of_body.get(body.index()).copied().flatten();
        std::iter::from_fn(move || {
            let j = &self.joints[next?];
            next = j.parent_joint;
            Some(j)
        })
    }
}
