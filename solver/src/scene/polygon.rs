//! Checks on semantic-area polygons: enough vertices, planar, not degenerate,
//! not self-intersecting.

/// A point or vector, metres.
type Vec3 = [f64; 3];

fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Ok if `pts` is a simple planar polygon; otherwise what is wrong with it.
pub(super) fn check(pts: &[Vec3]) -> Result<(), String> {
    if pts.len() < 3 {
        return Err(format!(
            "polygon has {} vertices; expected at least 3",
            pts.len()
        ));
    }
    if pts.iter().flatten().any(|x| !x.is_finite()) {
        return Err("polygon has a non-finite coordinate".into());
    }
    // A repeated vertex is named as such (the crossing test below would
    // report it as two edges crossing). Sorted, so O(n log n).
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| {
        pts[a]
            .partial_cmp(&pts[b])
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    if let Some(w) = order.windows(2).find(|w| pts[w[0]] == pts[w[1]]) {
        let (a, b) = (w[0].min(w[1]), w[0].max(w[1]));
        return Err(format!(
            "polygon repeats a vertex: vertices {} and {} are both {:?}",
            a + 1,
            b + 1,
            pts[a]
        ));
    }
    let diameter = pts
        .iter()
        .flat_map(|a| {
            pts.iter()
                .map(move |b| dot(sub(*a, *b), sub(*a, *b)).sqrt())
        })
        .fold(0.0, f64::max);
    // The plane: the largest cross product of two edges from the first vertex.
    // (Newell's normal would cancel to zero for a bow-tie and hide that it
    // crosses itself.)
    let n = (1..pts.len() - 1)
        .map(|k| cross(sub(pts[k], pts[0]), sub(pts[k + 1], pts[0])))
        .max_by(|a, b| dot(*a, *a).total_cmp(&dot(*b, *b)))
        .unwrap_or([0.0; 3]);
    let n_len = dot(n, n).sqrt();
    if diameter == 0.0 || n_len <= 1e-12 * diameter * diameter {
        return Err("polygon has zero area (collinear or repeated vertices)".into());
    }
    let unit = [n[0] / n_len, n[1] / n_len, n[2] / n_len];
    let c = pts[0];
    if let Some((k, d)) = pts
        .iter()
        .map(|p| dot(sub(*p, c), unit).abs())
        .enumerate()
        .find(|(_, d)| *d > 1e-6 * diameter)
    {
        return Err(format!(
            "polygon is not planar: vertex {} is {d:.3e} m off its plane",
            k + 1
        ));
    }
    // Project onto the plane's two dominant axes and test non-adjacent edges.
    let drop = (0..3)
        .max_by(|&a, &b| unit[a].abs().total_cmp(&unit[b].abs()))
        .unwrap_or(2);
    let (ax, ay) = match drop {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let p2: Vec<(f64, f64)> = pts.iter().map(|p| (p[ax], p[ay])).collect();
    let m = p2.len();
    for i in 0..m {
        for j in i + 1..m {
            let adjacent = j == i + 1 || (i == 0 && j == m - 1);
            if !adjacent && segments_cross(p2[i], p2[(i + 1) % m], p2[j], p2[(j + 1) % m]) {
                return Err(format!(
                    "polygon is self-intersecting: edge {} crosses edge {}",
                    i + 1,
                    j + 1
                ));
            }
        }
    }
    Ok(())
}

fn orient(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
    (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
}

/// Proper or touching intersection of segments ab and cd.
fn segments_cross(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    let on = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        r.0 >= p.0.min(q.0) && r.0 <= p.0.max(q.0) && r.1 >= p.1.min(q.1) && r.1 <= p.1.max(q.1)
    };
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on(c, d, a))
        || (d2 == 0.0 && on(c, d, b))
        || (d3 == 0.0 && on(a, b, c))
        || (d4 == 0.0 && on(a, b, d))
}

#[cfg(test)]
mod tests {
    use super::check;

    #[test]
    fn accepts_a_square_and_rejects_bad_polygons() {
        let sq = [
            [0.0, 0.0, 0.4],
            [1.0, 0.0, 0.4],
            [1.0, 1.0, 0.4],
            [0.0, 1.0, 0.4],
        ];
        assert!(check(&sq).is_ok());
        let bow = [
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert!(check(&bow).unwrap_err().contains("self-intersecting"));
        let bent = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.1],
            [0.0, 1.0, 0.0],
        ];
        assert!(check(&bent).unwrap_err().contains("not planar"));
        let line = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert!(check(&line).unwrap_err().contains("zero area"));
        assert!(check(&sq[..2]).unwrap_err().contains("at least 3"));
        // A repeated vertex is named, not reported as crossing edges.
        let rep = [sq[0], sq[1], sq[2], sq[3], sq[1]];
        let e = check(&rep).unwrap_err();
        assert!(e.contains("vertices 2 and 5"), "{e}");
    }
}
