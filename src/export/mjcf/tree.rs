//! The kinematic tree MuJoCo integrates and the loop closures it adds as
//! equality constraints.
//!
//! MuJoCo has tree joints for every kind but closes loops exactly only with a
//! point (`connect`) or a whole pose (`weld`): a universal or prismatic joint
//! must be in the tree, a spherical, revolute or fixed one may close a loop.
//! Among the trees that respect that, the one built here is the shallowest
//! (Dijkstra from the root, depth counted in tree degrees of freedom:
//! MuJoCo's mass-matrix factorisation grows with the depth), which puts
//! revolute joints (1 DOF) in the tree before spherical ones (3) and so
//! leaves spherical joints, which close with one `connect`, as closures. A
//! revolute closure needs one `connect` when the tree keeps its axes parallel
//! anyway (every rotating joint between its two bodies is a hinge parallel to
//! it: a planar loop), else two on its axis.

use super::input::Mechanism;
use anyhow::{Result, bail};
use haptloop_solver::JointKind;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// How a joint outside the tree is closed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Closure {
    /// One `connect` at the anchor: a spherical joint, or a revolute joint
    /// whose axes the tree keeps parallel (3 rows).
    Connect,
    /// Two `connect`s, at the anchor and one characteristic length along the
    /// axis: a revolute joint in a spatial loop (6 rows for its 5 conditions).
    TwoConnects,
    /// A `weld`: a fixed joint (6 rows).
    Weld,
}

impl Closure {
    /// Equality rows MuJoCo adds for it.
    pub fn rows(self) -> usize {
        match self {
            Closure::Connect => 3,
            Closure::TwoConnects | Closure::Weld => 6,
        }
    }

    /// The name in the metadata.
    pub fn as_str(self) -> &'static str {
        match self {
            Closure::Connect => "connect",
            Closure::TwoConnects => "two_connects",
            Closure::Weld => "weld",
        }
    }
}

/// Choices a user (or the peers comparison's alternatives) can force.
#[derive(Debug, Clone, Default)]
pub struct TreeOptions {
    /// Joints (indices) kept out of the tree, closed as equalities.
    pub cut: Vec<usize>,
    /// The root of a component without a fixed body (a body index), instead
    /// of the root that gives the shallowest tree.
    pub root: Option<usize>,
    /// Close every revolute loop with two `connect`s, planar or not.
    pub two_connects: bool,
}

/// The tree and its closures. Nodes are bodies; fixed bodies are the world.
#[derive(Debug, Clone)]
pub struct Tree {
    /// Per body: the joint it hangs from (`None`: fixed, or a floating root).
    pub via: Vec<Option<usize>>,
    /// Per body: its parent body (`None`: the world).
    pub parent: Vec<Option<usize>>,
    /// The world's children, then each body's, in the order they were reached.
    pub world_children: Vec<usize>,
    /// Per body.
    pub children: Vec<Vec<usize>>,
    /// Bodies on a `freejoint` (roots of components without a fixed body).
    pub roots: Vec<usize>,
    /// Joints outside the tree, in file order, and how each is closed.
    pub closures: Vec<(usize, Closure)>,
}

/// Degrees of freedom a joint kind has as a tree joint.
pub fn tree_dof(kind: JointKind) -> usize {
    match kind {
        JointKind::Fixed => 0,
        JointKind::Revolute | JointKind::Prismatic => 1,
        JointKind::Universal => 2,
        _ => 3,
    }
}

const WORLD: usize = 0;

struct Graph<'a> {
    m: &'a Mechanism,
    /// Per node: (neighbour, joint) over joints that must be tree joints.
    forced: Vec<Vec<(usize, usize)>>,
    /// Per node: (neighbour, joint) over joints that may be either.
    soft: Vec<Vec<(usize, usize)>>,
}

impl<'a> Graph<'a> {
    /// The joint graph of `m`: joints MuJoCo must make tree joints (forced:
    /// universal, prismatic), those that may close a loop (soft), and the
    /// joints `options` cuts; or why MuJoCo cannot express `m`.
    fn of(m: &'a Mechanism, options: &TreeOptions) -> Result<(Self, Vec<usize>)> {
        let n = m.bodies.len() + 1;
        let mut g = Graph {
            m,
            forced: vec![Vec::new(); n],
            soft: vec![Vec::new(); n],
        };
        let mut uf: Vec<usize> = (0..n).collect();
        let mut closures = Vec::new();
        for (k, j) in m.joints.iter().enumerate() {
            let closable = matches!(
                j.kind,
                JointKind::Spherical | JointKind::Revolute | JointKind::Fixed
            );
            match j.kind {
                JointKind::Distance | JointKind::Perpendicular | JointKind::PointOnPlane => bail!(
                    "joint `{}`: a {} joint has no MuJoCo joint or exact equality",
                    j.name,
                    j.kind
                ),
                _ => {}
            }
            let (a, b) = (Graph::node(m, j.bodies[0]), Graph::node(m, j.bodies[1]));
            if a == b {
                continue; // between fixed bodies (or a body and itself): nothing moves
            }
            if options.cut.contains(&k) {
                if !closable {
                    bail!(
                        "joint `{}` cannot be cut: MuJoCo closes no loop with a {} joint",
                        j.name,
                        j.kind
                    );
                }
                closures.push(k);
            } else if closable {
                g.soft[a].push((b, k));
                g.soft[b].push((a, k));
            } else {
                let (ra, rb) = (find(&mut uf, a), find(&mut uf, b));
                if ra == rb {
                    bail!(
                        "joint `{}` ({}) closes a loop of universal and prismatic joints: MuJoCo can close a loop only at a spherical, revolute or fixed joint",
                        j.name,
                        j.kind
                    );
                }
                uf[ra] = rb;
                g.forced[a].push((b, k));
                g.forced[b].push((a, k));
            }
        }
        Ok((g, closures))
    }
}

impl Graph<'_> {
    /// The root of `start`'s component: the one `options` names if it is
    /// there, else the node whose tree is shallowest (least total depth).
    fn root_of(&self, start: usize, options: &TreeOptions) -> usize {
        let component = self.grow(start).order;
        match options
            .root
            .map(|b| b + 1)
            .filter(|r| component.contains(r))
        {
            Some(r) => r,
            None => *component
                .iter()
                .min_by_key(|&&r| {
                    let depth = self.grow(r).depth;
                    depth.iter().filter(|&&d| d != usize::MAX).sum::<usize>()
                })
                .expect("a component has a node"),
        }
    }

    /// Node of a body: 0 for the world, body + 1 otherwise.
    fn node(m: &Mechanism, body: usize) -> usize {
        if m.bodies[body].fixed {
            WORLD
        } else {
            body + 1
        }
    }

    /// Depth of every node reached from `root` (in tree DOF), the parent and
    /// joint it was reached by, and the order reached.
    fn grow(&self, root: usize) -> Growth {
        let n = self.forced.len();
        let mut g = Growth {
            depth: vec![usize::MAX; n],
            via: vec![None; n],
            order: Vec::new(),
            heap: BinaryHeap::new(),
        };
        g.depth[root] = 0;
        self.absorb(root, &mut g);
        while let Some(Reverse((d, v, u, k))) = g.heap.pop() {
            if g.depth[v] != usize::MAX {
                continue;
            }
            g.depth[v] = d;
            g.via[v] = Some((u, k));
            self.absorb(v, &mut g);
        }
        g
    }

    /// Reaches `start`'s whole forced component (its joints must all be in
    /// the tree) and queues the soft joints leaving it.
    fn absorb(&self, start: usize, g: &mut Growth) {
        let first = g.order.len();
        let mut stack = vec![start];
        g.order.push(start);
        while let Some(u) = stack.pop() {
            for &(v, k) in &self.forced[u] {
                if g.depth[v] == usize::MAX {
                    g.depth[v] = g.depth[u] + tree_dof(self.m.joints[k].kind);
                    g.via[v] = Some((u, k));
                    g.order.push(v);
                    stack.push(v);
                }
            }
        }
        for i in first..g.order.len() {
            let u = g.order[i];
            for &(v, k) in &self.soft[u] {
                if g.depth[v] == usize::MAX {
                    let d = g.depth[u] + tree_dof(self.m.joints[k].kind);
                    g.heap.push(Reverse((d, v, u, k)));
                }
            }
        }
    }
}

/// A tree being grown from one root.
struct Growth {
    /// Per node, in tree DOF from the root (`usize::MAX`: not reached).
    depth: Vec<usize>,
    /// Per node: the parent node and joint it was reached by.
    via: Vec<Option<(usize, usize)>>,
    /// Nodes in the order reached.
    order: Vec<usize>,
    /// Soft joints leaving the tree: (depth, node, parent, joint).
    heap: BinaryHeap<Reverse<(usize, usize, usize, usize)>>,
}

fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

impl Tree {
    /// The shallowest tree of `m` under `options`, or why MuJoCo cannot
    /// have one (a joint kind it cannot express, a loop of joints that must
    /// all be tree joints, a cut joint that must be one).
    pub fn of(m: &Mechanism, options: &TreeOptions) -> Result<Tree> {
        let (g, closures) = Graph::of(m, options)?;
        let mut tree = Tree {
            via: vec![None; m.bodies.len()],
            parent: vec![None; m.bodies.len()],
            world_children: Vec::new(),
            children: vec![Vec::new(); m.bodies.len()],
            roots: Vec::new(),
            closures: Vec::new(),
        };
        let mut reached = vec![false; m.bodies.len() + 1];
        let has_world = m.bodies.iter().any(|b| b.fixed);
        let mut pending: Vec<usize> = Vec::new();
        if has_world {
            pending.push(WORLD);
        }
        pending.extend(
            (0..m.bodies.len())
                .filter(|&b| !m.bodies[b].fixed)
                .map(|b| b + 1),
        );
        for start in pending {
            if reached[start] {
                continue;
            }
            let root = if start == WORLD {
                WORLD
            } else {
                g.root_of(start, options)
            };
            tree.attach(&g, root, &mut reached);
        }
        tree.close(m, closures, options);
        Ok(tree)
    }

    /// Adds the tree `g` grows from `root` (marking its nodes `reached`).
    fn attach(&mut self, g: &Graph, root: usize, reached: &mut [bool]) {
        let Growth { via, order, .. } = g.grow(root);
        if root != WORLD {
            self.roots.push(root - 1);
            self.world_children.push(root - 1);
        }
        for v in order {
            reached[v] = true;
            if let Some((u, k)) = via[v] {
                let body = v - 1;
                self.via[body] = Some(k);
                if u == WORLD {
                    self.world_children.push(body);
                } else {
                    self.parent[body] = Some(u - 1);
                    self.children[u - 1].push(body);
                }
            }
        }
    }

    /// The loop closures: the joints `closures` cut, and every joint
    /// between moving nodes the tree left out, in joint order.
    fn close(&mut self, m: &Mechanism, mut closures: Vec<usize>, options: &TreeOptions) {
        let in_tree: Vec<bool> = (0..m.joints.len())
            .map(|k| self.via.contains(&Some(k)))
            .collect();
        for (k, j) in m.joints.iter().enumerate() {
            let (a, b) = (Graph::node(m, j.bodies[0]), Graph::node(m, j.bodies[1]));
            if a != b && !in_tree[k] && !closures.contains(&k) {
                closures.push(k);
            }
        }
        closures.sort_unstable();
        self.closures = closures
            .into_iter()
            .map(|k| (k, self.closure(m, k, options.two_connects)))
            .collect();
    }

    /// How joint `k` (outside the tree) is closed.
    fn closure(&self, m: &Mechanism, k: usize, two_connects: bool) -> Closure {
        let j = &m.joints[k];
        match j.kind {
            JointKind::Fixed => Closure::Weld,
            JointKind::Revolute if two_connects || !self.keeps_parallel(m, k) => {
                Closure::TwoConnects
            }
            _ => Closure::Connect,
        }
    }

    /// The ancestors of `body` (itself first), up to its root; `None` for
    /// the world.
    fn ancestors(&self, m: &Mechanism, body: usize) -> Vec<Option<usize>> {
        let mut out = Vec::new();
        let mut at = (!m.bodies[body].fixed).then_some(body);
        while let Some(b) = at {
            out.push(Some(b));
            at = self.parent[b];
        }
        out.push(None);
        out
    }

    /// Does the tree keep revolute joint `k`'s two axes parallel by itself?
    /// True when every joint on the tree path between its bodies is a hinge
    /// parallel to it at q0 (parallel hinges stay parallel), a slide or a
    /// weld, and the path passes no `freejoint`.
    fn keeps_parallel(&self, m: &Mechanism, k: usize) -> bool {
        let j = &m.joints[k];
        let axis = m.world_axis(j, 0).expect("a revolute joint has axes");
        let (up_a, up_b) = (
            self.ancestors(m, j.bodies[0]),
            self.ancestors(m, j.bodies[1]),
        );
        let Some(common) = up_a.iter().find(|x| up_b.contains(x)).copied() else {
            return false;
        };
        let path = up_a
            .iter()
            .take_while(|&&x| x != common)
            .chain(up_b.iter().take_while(|&&x| x != common));
        for b in path.flatten() {
            let Some(t) = self.via[*b] else {
                return false; // a floating root: its freejoint turns it
            };
            let tj = &m.joints[t];
            let ok = match tj.kind {
                JointKind::Prismatic | JointKind::Fixed => true,
                JointKind::Revolute => m
                    .world_axis(tj, 0)
                    .is_some_and(|a| a.cross(&axis).norm() < 1e-9),
                _ => false,
            };
            if !ok {
                return false;
            }
        }
        true
    }

    /// Tree degrees of freedom: MuJoCo's `nv`.
    pub fn dof(&self, m: &Mechanism) -> usize {
        let joints: usize = self
            .via
            .iter()
            .flatten()
            .map(|&k| tree_dof(m.joints[k].kind))
            .sum();
        joints + 6 * self.roots.len()
    }
}
