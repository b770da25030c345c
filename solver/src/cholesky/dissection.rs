//! Fill-reducing orderings of the leading block: AMD (faer) and a nested
//! dissection for large mesh-like patterns, where AMD's fronts grow with
//! the mesh's width (a planar lattice of loops, a closed surface of beads).
//!
//! The Eq. 7 matrix is a union of cliques, one per moving body (every row
//! touching the body couples with every other), so the dissection works on
//! the bodies: it splits a connected set of bodies in two, and the rows that
//! touch bodies on both sides (the joints cut) are the separator, ordered
//! after both sides. The split is a level structure of the body graph from
//! a pseudo-peripheral body (George & Liu): of the level boundaries that
//! leave each side at least [`BALANCE`] of the rows, the one cutting the
//! fewest rows relative to the smaller side. Pieces of at most
//! [`LEAF_ROWS`] rows are ordered by AMD on their own rows.
//!
//! `Symbolic::analyze` builds the factor for both orders and keeps the one
//! whose factorisation and solves cost fewer multiply-adds
//! ([`Ordering`](super::Ordering)): AMD below a few thousand rows (every
//! built-in scene), the dissection on the 8 × 32 lattice (BENCHMARKS.md).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// Pieces of at most this many rows are ordered by AMD, not bisected: a
/// hybrid that dissects only the top levels. Measured on the Eq. 7
/// matrices of the lattices and sphere toys (BENCHMARKS.md), a full
/// dissection (leaves of 48 rows) cost 1.1–3.5× AMD's multiply-adds: their
/// rows couple in cliques of 10–30 (every row on a body), so a piece's
/// separators outweigh the piece until it is hundreds of rows. With leaves
/// of 1024 rows the 8 × 32 lattice factors with 0.84× AMD's work.
pub(super) const LEAF_ROWS: usize = 1024;

/// Each side of a bisection keeps at least this fraction of the weight.
const BALANCE: f64 = 0.25;

/// perm_inv\[old\] = new: AMD on the symmetric pattern whose columns list
/// their rows (`col_ptr`, `row_idx`: either triangle or both).
pub(super) fn amd_order(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Result<Vec<usize>, faer::sparse::FaerError> {
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    if n > 0 {
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, col_ptr, None, row_idx);
        let mut mem =
            MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(n, row_idx.len()))
                .map_err(|_| faer::sparse::FaerError::OutOfMemory)?;
        amd::order_maybe_unsorted(
            &mut perm,
            &mut perm_inv,
            pattern,
            amd::Control::default(),
            MemStack::new(&mut mem),
        )?;
    }
    Ok(perm_inv)
}

/// perm_inv\[old\] = new by nested dissection (see the module docs).
/// `adj`: each row's neighbours (no self loops, symmetric); `cliques`: the
/// rows of each body (a row in one or two of them; a row in none is ordered
/// first); pieces of at most `leaf_rows` rows are ordered by AMD.
pub(super) fn dissection_order(
    adj: &[Vec<usize>],
    cliques: &[Vec<usize>],
    leaf_rows: usize,
) -> Result<Vec<usize>, faer::sparse::FaerError> {
    let n = adj.len();
    let mut of_row: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (c, rows) in cliques.iter().enumerate() {
        for &r in rows {
            if r < n && !of_row[r].contains(&c) {
                of_row[r].push(c);
            }
        }
    }
    let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); cliques.len()];
    for (r, cs) in of_row.iter().enumerate() {
        for &c in cs {
            rows_of[c].push(r);
        }
    }
    let mut d = Dissect {
        of_row: &of_row,
        rows_of: &rows_of,
        body_mark: vec![0; cliques.len()],
        row_mark: vec![0; n],
        leaf_rows,
        level: vec![usize::MAX; cliques.len()],
        epoch: 0,
        order: Vec::with_capacity(n),
    };
    let loose: Vec<usize> = (0..n).filter(|&r| of_row[r].is_empty()).collect();
    d.order.push(Item::Leaf(loose));
    d.piece((0..cliques.len()).collect());
    // Rows in order; leaves through AMD on their own rows.
    let mut perm: Vec<usize> = Vec::with_capacity(n);
    let mut local = vec![usize::MAX; n];
    for item in &d.order {
        match item {
            Item::Separator(rows) => perm.extend_from_slice(rows),
            Item::Leaf(rows) => {
                for (i, &r) in rows.iter().enumerate() {
                    local[r] = i;
                }
                let (mut cp, mut ri) = (vec![0usize], Vec::new());
                for &r in rows {
                    let from = ri.len();
                    ri.extend(adj[r].iter().filter_map(|&u| {
                        let l = local[u];
                        (l != usize::MAX).then_some(l)
                    }));
                    ri[from..].sort_unstable();
                    cp.push(ri.len());
                }
                let inv = amd_order(rows.len(), &cp, &ri)?;
                let mut sub = vec![0usize; rows.len()];
                for (i, &new) in inv.iter().enumerate() {
                    sub[new] = rows[i];
                }
                perm.extend_from_slice(&sub);
                for &r in rows {
                    local[r] = usize::MAX;
                }
            }
        }
    }
    if perm.len() != n {
        return Err(faer::sparse::FaerError::IndexOverflow);
    }
    let mut perm_inv = vec![0usize; n];
    for (new, &old) in perm.iter().enumerate() {
        perm_inv[old] = new;
    }
    Ok(perm_inv)
}

/// Rows to order as they are (a separator) or by AMD (a leaf).
#[derive(Debug, Clone)]
enum Item {
    Separator(Vec<usize>),
    Leaf(Vec<usize>),
}

struct Dissect<'a> {
    of_row: &'a [Vec<usize>],
    rows_of: &'a [Vec<usize>],
    /// `body_mark[b] == epoch`: b is in the piece being worked on.
    body_mark: Vec<u64>,
    row_mark: Vec<u64>,
    /// Pieces of at most this many rows are leaves.
    leaf_rows: usize,
    /// BFS level of each body of the current piece.
    level: Vec<usize>,
    epoch: u64,
    order: Vec<Item>,
}

impl Dissect<'_> {
    fn enter(&mut self, bodies: &[usize]) -> u64 {
        self.epoch += 1;
        for &b in bodies {
            self.body_mark[b] = self.epoch;
        }
        self.epoch
    }

    /// A row is inside the piece marked `e` iff all its bodies are.
    fn inside(&self, r: usize, e: u64) -> bool {
        self.of_row[r].iter().all(|&c| self.body_mark[c] == e)
    }

    /// The rows inside the piece `bodies` (marked `e`), each once.
    fn rows(&mut self, bodies: &[usize], e: u64) -> Vec<usize> {
        self.epoch += 1;
        let seen = self.epoch;
        let mut out = Vec::new();
        for &b in bodies {
            for &r in &self.rows_of[b] {
                if self.row_mark[r] != seen && self.inside(r, e) {
                    self.row_mark[r] = seen;
                    out.push(r);
                }
            }
        }
        out
    }

    /// Orders the rows inside `bodies` (possibly disconnected).
    fn piece(&mut self, bodies: Vec<usize>) {
        let e = self.enter(&bodies);
        let rows = self.rows(&bodies, e);
        if rows.len() <= self.leaf_rows {
            if !rows.is_empty() {
                self.order.push(Item::Leaf(rows));
            }
            return;
        }
        for comp in self.components(&bodies, e) {
            self.component(comp);
        }
    }

    fn component(&mut self, bodies: Vec<usize>) {
        let e = self.enter(&bodies);
        let rows = self.rows(&bodies, e);
        if rows.len() > self.leaf_rows
            && let Some((a, b, sep)) = self.bisect(&bodies, &rows, e)
        {
            self.piece(a);
            self.piece(b);
            self.order.push(Item::Separator(sep));
            return;
        }
        if !rows.is_empty() {
            self.order.push(Item::Leaf(rows));
        }
    }

    /// Bodies of the piece marked `e` reachable from each other through
    /// rows inside it.
    fn components(&mut self, bodies: &[usize], e: u64) -> Vec<Vec<usize>> {
        for &b in bodies {
            self.level[b] = usize::MAX;
        }
        let mut out = Vec::new();
        for &s in bodies {
            if self.level[s] != usize::MAX {
                continue;
            }
            let comp = self.bfs(s, e).0;
            out.push(comp);
        }
        out
    }

    /// BFS over the bodies of the piece marked `e` from `root` (levels in
    /// `level`, which must be `usize::MAX` on unvisited bodies): the bodies
    /// in BFS order and the number of levels.
    fn bfs(&mut self, root: usize, e: u64) -> (Vec<usize>, usize) {
        let mut queue = vec![root];
        self.level[root] = 0;
        let mut head = 0;
        while head < queue.len() {
            let b = queue[head];
            head += 1;
            for &r in &self.rows_of[b] {
                if !self.inside(r, e) {
                    continue;
                }
                for &c in &self.of_row[r] {
                    if self.level[c] == usize::MAX {
                        self.level[c] = self.level[b] + 1;
                        queue.push(c);
                    }
                }
            }
        }
        let depth = queue.last().map_or(0, |&b| self.level[b] + 1);
        (queue, depth)
    }

    /// Splits a connected piece (marked `e`, rows `rows`) into two body
    /// sets and the rows between them, or `None` when no level boundary
    /// gives a balanced split.
    fn bisect(
        &mut self,
        bodies: &[usize],
        rows: &[usize],
        e: u64,
    ) -> Option<(Vec<usize>, Vec<usize>, Vec<usize>)> {
        let degree = |d: &Self, b: usize| d.rows_of[b].len();
        let mut root = *bodies.iter().min_by_key(|&&b| degree(self, b))?;
        let mut depth = 0;
        // Pseudo-peripheral root: restart from the farthest level's least
        // connected body while the eccentricity grows.
        for _ in 0..8 {
            for &b in bodies {
                self.level[b] = usize::MAX;
            }
            let (queue, d) = self.bfs(root, e);
            if d <= depth {
                break;
            }
            depth = d;
            let last = self.level[*queue.last()?];
            root = *queue
                .iter()
                .filter(|&&b| self.level[b] == last)
                .min_by_key(|&&b| degree(self, b))?;
        }
        for &b in bodies {
            self.level[b] = usize::MAX;
        }
        let (_, depth) = self.bfs(root, e);
        if depth < 2 {
            return None;
        }
        // Rows whose highest body level is ≤ m lie on side A of boundary
        // m; those whose lowest is > m on side B; the others are cut.
        let mut top = vec![0usize; depth];
        let mut bottom = vec![0usize; depth];
        for &r in rows {
            let ls = self.of_row[r].iter().map(|&c| self.level[c]);
            let (lo, hi) = ls.fold((usize::MAX, 0), |(lo, hi), l| (lo.min(l), hi.max(l)));
            top[hi] += 1;
            bottom[lo] += 1;
        }
        let total = rows.len();
        let (mut a, mut best) = (0usize, None);
        let mut b = total;
        for m in 0..depth - 1 {
            a += top[m];
            b -= bottom[m];
            let cut = total - a - b;
            let small = a.min(b) as f64;
            if small < BALANCE * total as f64 {
                continue;
            }
            let score = cut as f64 / small;
            if best.is_none_or(|(s, _)| score < s) {
                best = Some((score, m));
            }
        }
        let (_, m) = best?;
        let (side_a, side_b): (Vec<usize>, Vec<usize>) =
            bodies.iter().partition(|&&b| self.level[b] <= m);
        let sep: Vec<usize> = rows
            .iter()
            .copied()
            .filter(|&r| {
                let mut ls = self.of_row[r].iter().map(|&c| self.level[c] <= m);
                let first = ls.next().unwrap_or(true);
                ls.any(|x| x != first)
            })
            .collect();
        Some((side_a, side_b, sep))
    }
}
