//! The grouping graph (§4): an edge offer object → binding object per
//! satisfied constraint. Moving an object moves its successors (§4.1: only
//! successors; for an undirected cycle, an object with two unordered
//! parents moves with whichever is moved). Directed cycles are never
//! created (Algorithm 1, line 8). Queries cost what the touched part of the
//! graph costs: children are kept per object, parents are read from the
//! object's own binding areas.

use super::area::AreaId;
use super::scene::SemanticScene;
use crate::BodyId;

impl SemanticScene {
    /// The objects bound to one of `o`'s offers (its children), sorted.
    pub fn children_of(&self, o: BodyId) -> Vec<BodyId> {
        let mut c: Vec<BodyId> = self.children[o.index()]
            .iter()
            .map(|b| self.areas[b.index()].body)
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    }

    /// The objects `o` is bound to (its parents), sorted.
    pub fn parents_of(&self, o: BodyId) -> Vec<BodyId> {
        let mut p: Vec<BodyId> = self.objects[o.index()]
            .bindings
            .iter()
            .filter_map(|b| self.bond(*b))
            .map(|bond| self.areas[bond.offer.index()].body)
            .collect();
        p.sort_unstable();
        p.dedup();
        p
    }

    /// `o` and every object reachable from it (its group: what moves with
    /// it), sorted.
    pub fn group(&self, o: BodyId) -> Vec<BodyId> {
        let mut seen = vec![o];
        let mut stack = vec![o];
        while let Some(x) = stack.pop() {
            for b in &self.children[x.index()] {
                let c = self.areas[b.index()].body;
                if !seen.contains(&c) {
                    seen.push(c);
                    stack.push(c);
                }
            }
        }
        seen.sort_unstable();
        seen
    }

    /// Whether `to` is reachable from `from` along the edges (`from`
    /// itself counts).
    pub fn reaches(&self, from: BodyId, to: BodyId) -> bool {
        from == to || self.group(from).binary_search(&to).is_ok()
    }

    /// Whether satisfying binding area `b` with offer area `a` would close a
    /// directed cycle (the offer's object is the binding's object or one of
    /// its successors).
    pub fn would_cycle(&self, b: AreaId, a: AreaId) -> bool {
        self.reaches(self.areas[b.index()].body, self.areas[a.index()].body)
    }

    /// Every edge (offer object, binding object), sorted, without repeats.
    pub fn edges(&self) -> Vec<(BodyId, BodyId)> {
        let mut e: Vec<(BodyId, BodyId)> = self
            .bonds()
            .map(|(b, bond)| {
                (
                    self.areas[bond.offer.index()].body,
                    self.areas[b.index()].body,
                )
            })
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    }

    /// Whether the graph has a directed cycle (never, if only
    /// [`satisfy`](Self::satisfy) and [`satisfy_aligned`](Self::satisfy_aligned)
    /// add edges).
    pub fn has_directed_cycle(&self) -> bool {
        let n = self.objects.len();
        // Kahn: a node set that never drains holds a cycle.
        let mut indeg = vec![0usize; n];
        for (_, c) in self.edges() {
            indeg[c.index()] += 1;
        }
        let mut ready: Vec<usize> = (0..n).filter(|&i| indeg[i] == 0).collect();
        let mut done = 0;
        while let Some(i) = ready.pop() {
            done += 1;
            for c in self.children_of(BodyId(i as u32)) {
                indeg[c.index()] -= 1;
                if indeg[c.index()] == 0 {
                    ready.push(c.index());
                }
            }
        }
        done < n
    }

    /// Whether a satisfied constraint binds `x` and `y` (either way round):
    /// their collisions are not tested (§3.2).
    pub fn bound_pair(&self, x: BodyId, y: BodyId) -> bool {
        let binds = |p: BodyId, q: BodyId| {
            self.objects[p.index()].bindings.iter().any(|b| {
                self.bond(*b)
                    .is_some_and(|bond| self.areas[bond.offer.index()].body == q)
            })
        };
        binds(x, y) || binds(y, x)
    }
}
