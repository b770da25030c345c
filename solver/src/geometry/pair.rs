//! A pair of colliders at their current poses: the frame conversions the
//! witness constructions need. Body frames are A's and B's; "world" is the
//! scene frame.

use nalgebra::{Matrix3, Vector3};

use super::convert::Pose3;
use super::polyhedron::Feature;
use super::shape::Collider;

/// Two colliders at their poses (A = end 0 of the witness rows, B = end 1).
#[derive(Debug, Clone, Copy)]
pub struct PairView<'a> {
    /// Body A's collider.
    pub a: &'a Collider,
    /// Body A's pose.
    pub pa: Pose3,
    /// Body B's collider.
    pub b: &'a Collider,
    /// Body B's pose.
    pub pb: Pose3,
}

impl PairView<'_> {
    /// The sum of both margins, metres.
    pub fn margin(&self) -> f64 {
        self.a.margin_m + self.b.margin_m
    }

    /// Rotates A-frame vectors into B's frame.
    pub fn a_to_b(&self) -> Matrix3<f64> {
        self.pb.rot.tr_mul(&self.pa.rot)
    }

    /// An A-frame point in B's frame.
    pub fn a_in_b(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.pb.local_point(&self.pa.point(p))
    }

    /// A B-frame point in A's frame.
    pub fn b_in_a(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.pa.local_point(&self.pb.point(p))
    }

    /// The same pair seen from B (ends exchanged).
    pub fn swapped(&self) -> Self {
        Self {
            a: self.b,
            pa: self.pb,
            b: self.a,
            pb: self.pa,
        }
    }
}

/// A feature packed into one number: `dimension << 30 | index`.
pub fn pack(f: Feature) -> u32 {
    match f {
        Feature::Vertex(i) => i,
        Feature::Edge(i) => (1 << 30) | i,
        Feature::Face(i) => (2 << 30) | i,
    }
}
