//! A uniform hash grid over axis-aligned boxes: which objects (or offer
//! areas) are near a box, at a cost that depends on how many are near, not
//! on how many there are (§7: "these factors depend mainly on the local
//! complexity of the scene"). An entry covering more than [`MAX_CELLS`]
//! cells (a floor, a wall) is kept in a short list every query returns
//! instead of in thousands of cells.

use std::collections::HashMap;

use nalgebra::Vector3;

/// Cells an entry may cover before it counts as large.
pub const MAX_CELLS: i64 = 64;

type Cell = (i32, i32, i32);

/// See the module docs.
#[derive(Debug, Clone)]
pub struct Grid {
    cell_m: f64,
    cells: HashMap<Cell, Vec<u32>>,
    /// Per entry: the cell range it is in (`None`: absent or large).
    span: Vec<Option<(Cell, Cell)>>,
    large: Vec<u32>,
}

impl Grid {
    /// An empty grid of cubic cells of side `cell_m` (> 0).
    pub fn new(cell_m: f64) -> Self {
        Self {
            cell_m: if cell_m.is_finite() && cell_m > 0.0 {
                cell_m
            } else {
                1.0
            },
            cells: HashMap::new(),
            span: Vec::new(),
            large: Vec::new(),
        }
    }

    fn cell(&self, p: &Vector3<f64>) -> Cell {
        let c = |x: f64| (x / self.cell_m).floor().clamp(-1e9, 1e9) as i32;
        (c(p.x), c(p.y), c(p.z))
    }

    fn range(&self, lo: &Vector3<f64>, hi: &Vector3<f64>) -> (Cell, Cell) {
        (self.cell(lo), self.cell(hi))
    }

    /// Cells in the range, saturating: a box loosened by a huge snap
    /// distance spans more cells than an `i64` holds, and a wrapped product
    /// (negative or small) would have looked like a small box and been
    /// walked cell by cell.
    fn count(r: &(Cell, Cell)) -> i64 {
        let (a, b) = r;
        let side = |lo: i32, hi: i32| i64::from(hi) - i64::from(lo) + 1;
        side(a.0, b.0)
            .saturating_mul(side(a.1, b.1))
            .saturating_mul(side(a.2, b.2))
    }

    /// Puts entry `id` at the box `[lo, hi]` (moving it if present).
    pub fn set(&mut self, id: u32, lo: &Vector3<f64>, hi: &Vector3<f64>) {
        let r = self.range(lo, hi);
        let k = id as usize;
        if self.span.len() <= k {
            self.span.resize(k + 1, None);
        }
        if self.span[k] == Some(r) {
            return;
        }
        self.remove(id);
        if Self::count(&r) > MAX_CELLS {
            self.large.push(id);
            return;
        }
        for x in r.0.0..=r.1.0 {
            for y in r.0.1..=r.1.1 {
                for z in r.0.2..=r.1.2 {
                    self.cells.entry((x, y, z)).or_default().push(id);
                }
            }
        }
        self.span[k] = Some(r);
    }

    /// Takes entry `id` out.
    pub fn remove(&mut self, id: u32) {
        let k = id as usize;
        if let Some(pos) = self.large.iter().position(|&x| x == id) {
            self.large.swap_remove(pos);
        }
        let Some(r) = self.span.get_mut(k).and_then(Option::take) else {
            return;
        };
        for x in r.0.0..=r.1.0 {
            for y in r.0.1..=r.1.1 {
                for z in r.0.2..=r.1.2 {
                    if let Some(v) = self.cells.get_mut(&(x, y, z)) {
                        v.retain(|&e| e != id);
                        if v.is_empty() {
                            self.cells.remove(&(x, y, z));
                        }
                    }
                }
            }
        }
    }

    /// Entries whose cells meet the box `[lo, hi]`, plus every large one,
    /// sorted, without repeats (appended to `out` after clearing it). A box
    /// covering more than [`MAX_CELLS`] cells is answered with every entry.
    pub fn query(&self, lo: &Vector3<f64>, hi: &Vector3<f64>, out: &mut Vec<u32>) {
        out.clear();
        out.extend_from_slice(&self.large);
        let r = self.range(lo, hi);
        if Self::count(&r) > MAX_CELLS {
            out.extend(self.cells.values().flatten().copied());
        } else {
            for x in r.0.0..=r.1.0 {
                for y in r.0.1..=r.1.1 {
                    for z in r.0.2..=r.1.2 {
                        if let Some(v) = self.cells.get(&(x, y, z)) {
                            out.extend_from_slice(v);
                        }
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn queries_find_what_overlaps_and_follow_moves() {
        let mut g = Grid::new(1.0);
        let v = Vector3::new;
        g.set(0, &v(0.1, 0.1, 0.1), &v(0.2, 0.2, 0.2));
        g.set(1, &v(5.1, 0.1, 0.1), &v(5.2, 0.2, 0.2));
        g.set(2, &v(-50.0, -50.0, -1.0), &v(50.0, 50.0, 0.0)); // large
        let mut out = Vec::new();
        g.query(&v(0.0, 0.0, 0.0), &v(0.5, 0.5, 0.5), &mut out);
        assert_eq!(out, vec![0, 2]);
        g.set(0, &v(5.3, 0.1, 0.1), &v(5.4, 0.2, 0.2));
        g.query(&v(0.0, 0.0, 0.0), &v(0.5, 0.5, 0.5), &mut out);
        assert_eq!(out, vec![2]);
        g.query(&v(5.0, 0.0, 0.0), &v(5.5, 0.5, 0.5), &mut out);
        assert_eq!(out, vec![0, 1, 2]);
        g.remove(2);
        g.query(&v(5.0, 0.0, 0.0), &v(5.5, 0.5, 0.5), &mut out);
        assert_eq!(out, vec![0, 1]);
    }

    /// A box loosened by a snap distance of 5e5 m to 1e300 m spans more
    /// cells than an i64 counts: it is a large entry (no cell is walked),
    /// and a query that big answers every entry. The old product wrapped
    /// and walked ~1e21 cells (`check` hung at gigabytes).
    #[test]
    fn huge_boxes_are_large_entries_not_cell_walks() {
        let v = Vector3::new;
        for reach in [5e5, 1e6, 1e9, 1e300] {
            let mut g = Grid::new(0.04);
            let (lo, hi) = (v(-reach, -reach, -reach), v(reach, reach, reach));
            assert!(Grid::count(&g.range(&lo, &hi)) > MAX_CELLS, "reach {reach}");
            g.set(0, &v(0.1, 0.1, 0.1), &v(0.2, 0.2, 0.2));
            g.set(1, &v(-reach, -reach, -reach), &v(reach, reach, reach));
            assert_eq!(g.large, vec![1], "reach {reach}");
            assert!(
                g.cells.len() <= 64,
                "reach {reach}: {} cells",
                g.cells.len()
            );
            let mut out = Vec::new();
            g.query(
                &v(-reach, -reach, -reach),
                &v(reach, reach, reach),
                &mut out,
            );
            assert_eq!(out, vec![0, 1], "reach {reach}");
            g.remove(1);
            assert!(g.large.is_empty());
        }
    }
}
