//! Convex hulls simplified to a vertex budget at load.
//!
//! The witness machinery's work per pair grows with the hull's size (the
//! separating-axis test pairs every edge direction of one hull with every
//! one of the other; a 1000-vertex hull made a slow-loop cycle take 18 ms),
//! and parry's hull of many points, coplanar ones above all, costs far more
//! than linear time (the 10 000 points of a cylinder took minutes and
//! gigabytes). A convex shape of more than [`MAX_HULL_VERTICES`] points is
//! therefore replaced at load by the hull of [`MAX_HULL_VERTICES`] of its
//! points, chosen greedily on the points themselves: start from a large
//! tetrahedron, then add the point farthest outside the current hull until
//! the budget is spent or none is outside (the refinement step of QuickHull,
//! stopped early; parry only ever builds hulls of the kept points). The
//! result lies inside the given shape, and every point given is within
//! [`Simplified::error_m`] of it (measured exactly, parry's point distance):
//! the tolerance the collision shape keeps, stated by `haptloop check`.
//! Mass and inertia from `density` come from the kept hull too, the shape
//! the contacts see.

use nalgebra::Vector3;
use parry3d_f64::query::PointQuery;
use parry3d_f64::shape::ConvexPolyhedron;

use super::convert::{to_glam, to_na};
use super::polyhedron::HullError;

/// Vertices a convex shape keeps at most (see the module docs).
pub const MAX_HULL_VERTICES: usize = 64;

/// What simplifying a hull did.
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// The kept points, body frame, metres.
    pub points_m: Vec<[f64; 3]>,
    /// Points given.
    pub from_points: usize,
    /// The largest distance of a given point from the kept hull, metres
    /// (how much the shape shrank at most; 0 when the kept points span
    /// every point given).
    pub error_m: f64,
}

/// A body's simplified hull, as reports state it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HullSimplification {
    /// Points given.
    pub from_points: usize,
    /// Points kept.
    pub vertices: usize,
    /// The largest distance of a given point from the kept hull, metres.
    pub error_m: f64,
}

impl Simplified {
    /// What a report states.
    pub fn summary(&self) -> HullSimplification {
        HullSimplification {
            from_points: self.from_points,
            vertices: self.points_m.len(),
            error_m: self.error_m,
        }
    }
}

/// `points` cut to at most `budget` (≥ 4) of them whose hull spans the rest
/// within [`Simplified::error_m`], or `None` when there are no more than
/// `budget`. Allocates; O(budget × points × faces) plus parry's hulls of at
/// most `budget` points.
pub fn simplify_hull(points: &[[f64; 3]], budget: usize) -> Result<Option<Simplified>, HullError> {
    let budget = budget.max(4);
    if points.len() <= budget {
        return Ok(None);
    }
    let verts: Vec<Vector3<f64>> = points.iter().map(|p| Vector3::from(*p)).collect();
    let size = verts
        .iter()
        .map(|v| v.norm())
        .fold(0.0, f64::max)
        .max(1e-300);
    let mut kept = tetrahedron(&verts).ok_or(HullError::Flat)?;
    let mut is_kept = vec![false; verts.len()];
    for &k in &kept {
        is_kept[k] = true;
    }
    let mut current = polyhedron(&verts, &kept)?;
    while kept.len() < budget {
        let planes = face_planes(&current);
        let Some((far, d)) = verts
            .iter()
            .enumerate()
            .filter(|(i, _)| !is_kept[*i])
            .map(|(i, v)| (i, outside(&planes, v)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            break;
        };
        if d <= 1e-12 * size {
            break;
        }
        kept.push(far);
        is_kept[far] = true;
        current = polyhedron(&verts, &kept)?;
    }
    let planes = face_planes(&current);
    let error_m = verts
        .iter()
        .filter(|v| outside(&planes, v) > 1e-12 * size)
        .map(|v| current.distance_to_local_point(to_glam(v), true))
        .fold(0.0, f64::max);
    Ok(Some(Simplified {
        points_m: current.points().iter().map(|p| [p.x, p.y, p.z]).collect(),
        from_points: verts.len(),
        error_m,
    }))
}

fn polyhedron(verts: &[Vector3<f64>], kept: &[usize]) -> Result<ConvexPolyhedron, HullError> {
    let pts: Vec<_> = kept.iter().map(|&i| to_glam(&verts[i])).collect();
    ConvexPolyhedron::from_convex_hull(&pts).ok_or(HullError::Flat)
}

/// (outward unit normal, a point) of every face.
fn face_planes(h: &ConvexPolyhedron) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let adj = h.vertices_adj_to_face();
    h.faces()
        .iter()
        .map(|f| {
            let v = adj[f.first_vertex_or_edge as usize] as usize;
            (to_na(f.normal), to_na(h.points()[v]))
        })
        .collect()
}

/// How far `p` lies outside the planes (≤ 0: inside all).
fn outside(planes: &[(Vector3<f64>, Vector3<f64>)], p: &Vector3<f64>) -> f64 {
    planes
        .iter()
        .map(|(n, o)| n.dot(&(p - o)))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Four points spanning a large tetrahedron: the farthest from the
/// centroid, the farthest from it, the farthest from their line, the
/// farthest from their plane.
fn tetrahedron(v: &[Vector3<f64>]) -> Option<Vec<usize>> {
    let argmax = |f: &dyn Fn(&Vector3<f64>) -> f64| {
        (0..v.len()).max_by(|&a, &b| f(&v[a]).total_cmp(&f(&v[b])))
    };
    let c = v.iter().sum::<Vector3<f64>>() / v.len() as f64;
    let a = argmax(&|p| (p - c).norm())?;
    let b = argmax(&|p| (p - v[a]).norm())?;
    let ab = (v[b] - v[a]).try_normalize(1e-300)?;
    let line = |p: &Vector3<f64>| ((p - v[a]) - ab * ab.dot(&(p - v[a]))).norm();
    let c3 = argmax(&line)?;
    let n = (v[b] - v[a]).cross(&(v[c3] - v[a])).try_normalize(1e-300)?;
    let d = argmax(&|p| n.dot(&(p - v[a])).abs())?;
    let set = vec![a, b, c3, d];
    let distinct = (0..4).all(|i| (i + 1..4).all(|j| set[i] != set[j]));
    distinct.then_some(set)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a sphere of radius r (a Fibonacci lattice).
    fn sphere(n: usize, r: f64) -> Vec<[f64; 3]> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|k| {
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
                let s = (1.0 - z * z).sqrt();
                let a = golden * k as f64;
                [r * s * a.cos(), r * s * a.sin(), r * z]
            })
            .collect()
    }

    /// The simplified hull keeps the budget, lies inside the original and
    /// its stated error is what a brute-force check of every original
    /// point against the simplified hull's face planes allows: no point is
    /// farther outside any plane than the error, and one is that far from
    /// the hull (the error is attained, not a loose bound).
    #[test]
    fn a_sphere_hull_is_cut_to_the_budget_with_its_error_stated() {
        let r = 0.05;
        for n in [200, 1000] {
            let pts = sphere(n, r);
            let s = simplify_hull(&pts, MAX_HULL_VERTICES).unwrap().unwrap();
            assert_eq!(s.from_points, n);
            assert!(s.points_m.len() <= MAX_HULL_VERTICES);
            assert!(
                s.points_m.len() >= MAX_HULL_VERTICES - 2,
                "{}",
                s.points_m.len()
            );
            // Every kept point is an original one (inside the original hull).
            for p in &s.points_m {
                assert!(pts.iter().any(|q| q == p), "{p:?} is not an input point");
            }
            // A 64-vertex polytope inscribed in a sphere misses it by at
            // most r (1 − cos θ), θ ≈ the angular spacing; here ≈ 2 mm.
            assert!(s.error_m > 0.0 && s.error_m < 0.1 * r, "{}", s.error_m);
            let pts_na: Vec<_> = s
                .points_m
                .iter()
                .map(|p| to_glam(&Vector3::from(*p)))
                .collect();
            let h = ConvexPolyhedron::from_convex_hull(&pts_na).unwrap();
            let planes = face_planes(&h);
            let worst = pts
                .iter()
                .map(|p| outside(&planes, &Vector3::from(*p)))
                .fold(0.0, f64::max);
            assert!(worst <= s.error_m * (1.0 + 1e-9), "{worst} > {}", s.error_m);
            assert!(worst >= 0.5 * s.error_m, "{worst} vs {}", s.error_m);
        }
    }

    /// A hull within the budget is left alone; one whose points lie inside
    /// the hull of the budget's worth keeps exactly those.
    #[test]
    fn small_hulls_stay_and_interior_points_cost_nothing() {
        let cube: Vec<[f64; 3]> = (0..8)
            .map(|k| {
                let s = |b: usize| if k >> b & 1 == 1 { 0.1 } else { -0.1 };
                [s(0), s(1), s(2)]
            })
            .collect();
        assert_eq!(simplify_hull(&cube, 8).unwrap(), None);
        // Interior points cost nothing: the corners span them exactly.
        let mut many = cube.clone();
        many.extend(sphere(500, 0.05));
        let s = simplify_hull(&many, 8).unwrap().unwrap();
        assert_eq!(s.error_m, 0.0);
        let mut got = s.points_m.clone();
        got.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut want = cube.clone();
        want.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(got, want);
    }
}
