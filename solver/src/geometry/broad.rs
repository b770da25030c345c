//! The broad phase: which pairs of shaped bodies are close enough for the
//! narrow phase, from parry's BVH (no all-pairs scan). Each body's AABB at
//! its pose, loosened by the query margin, is a leaf; the tree is built once
//! and refitted every cycle, and its self-traversal reports the overlapping
//! leaf pairs. At a fixed density each body overlaps a bounded number of
//! others, so the cost grows about linearly with the bodies (BENCHMARKS.md).

use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};

use super::convert::Pose3;
use super::shape::Collider;

/// Reusable broad-phase state.
#[derive(Default)]
pub struct BroadPhase {
    bvh: Option<Bvh>,
    workspace: BvhWorkspace,
    aabbs: Vec<Aabb>,
    pairs: Vec<(u32, u32)>,
}

impl std::fmt::Debug for BroadPhase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BroadPhase")
            .field("leaves", &self.aabbs.len())
            .finish_non_exhaustive()
    }
}

impl BroadPhase {
    /// Candidate pairs `(i, j)`, `i < j`, indices into `colliders`, whose
    /// AABBs at `poses`, each loosened by `margin_m`, overlap. The tree is
    /// rebuilt when the number of leaves changes, refitted otherwise.
    pub fn pairs(&mut self, colliders: &[(&Collider, Pose3)], margin_m: f64) -> &[(u32, u32)] {
        self.aabbs.clear();
        for (c, p) in colliders {
            self.aabbs
                .push(c.full.compute_aabb(&p.to_parry()).loosened(margin_m * 0.5));
        }
        let rebuild = self
            .bvh
            .as_ref()
            .is_none_or(|b| b.leaf_count() as usize != self.aabbs.len());
        if rebuild {
            self.bvh = Some(Bvh::from_leaves(BvhBuildStrategy::Binned, &self.aabbs));
        } else if let Some(bvh) = &mut self.bvh {
            for (i, a) in self.aabbs.iter().enumerate() {
                bvh.insert_or_update_partially(*a, i as u32, 0.0);
            }
            bvh.refit(&mut self.workspace);
        }
        self.pairs.clear();
        if let Some(bvh) = &self.bvh {
            let pairs = &mut self.pairs;
            bvh.traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut |i, j| {
                pairs.push((i.min(j), i.max(j)));
            });
        }
        self.pairs.sort_unstable();
        self.pairs.dedup();
        &self.pairs
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shape::Shape;
    use nalgebra::{Matrix3, Vector3};

    /// The BVH's pairs are exactly the brute-force AABB overlaps.
    #[test]
    fn bvh_pairs_equal_brute_force() {
        let c = Shape::Box {
            half_extents_m: [0.02, 0.03, 0.01],
        }
        .collider()
        .unwrap();
        let mut poses = Vec::new();
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..150 {
            poses.push(Pose3 {
                r: Vector3::new(rnd() * 0.5, rnd() * 0.5, rnd() * 0.1),
                rot: Matrix3::identity(),
            });
        }
        let set: Vec<(&Collider, Pose3)> = poses.iter().map(|p| (&c, *p)).collect();
        let mut bp = BroadPhase::default();
        for round in 0..2 {
            let margin = 0.01;
            let got = bp.pairs(&set, margin).to_vec();
            let mut want = Vec::new();
            let boxes: Vec<Aabb> = set
                .iter()
                .map(|(c, p)| c.full.compute_aabb(&p.to_parry()).loosened(margin * 0.5))
                .collect();
            for i in 0..boxes.len() {
                for j in i + 1..boxes.len() {
                    if boxes[i].intersects(&boxes[j]) {
                        want.push((i as u32, j as u32));
                    }
                }
            }
            assert_eq!(got, want, "round {round}");
            assert!(!want.is_empty());
        }
    }
}
