//! The pattern-only half of [`Cholesky`](super::Cholesky): ordering,
//! elimination tree, supernodes, the block layout, the update plan; and the
//! triangular solves, which only walk that structure.

use super::Ordering;
use super::dissection;

/// Leading blocks of fewer rows are ordered by AMD alone (the dissection
/// cannot win on so few).
const MIN_DISSECTION: usize = 2 * dissection::LEAF_ROWS;

/// Columns `c0 .. c0 + w` of L, whose rows below the diagonal block are the
/// same `nrows` rows (`rows[rows .. rows + nrows]`, ascending). Its block is
/// `values[val ..]`: (w + nrows) rows of w entries, row-major; the first w
/// rows are the lower-triangular diagonal block.
#[derive(Debug, Clone, Copy)]
pub(super) struct Supernode {
    pub c0: u32,
    pub w: u32,
    pub rows: u32,
    pub nrows: u32,
    pub val: u32,
    /// This supernode's incoming updates: `updates[.0 .. .1]`.
    pub updates: (u32, u32),
}

/// Supernode `src` updates the supernode it is listed under: its below rows
/// `a .. b` fall in the target's columns, and its `m` below rows from `a` on
/// land in the target's block at local rows `rel[rel .. rel + m]`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Update {
    pub src: u32,
    pub a: u32,
    pub b: u32,
    pub m: u32,
    pub rel: u32,
}

#[derive(Debug, Clone)]
pub(super) struct Symbolic {
    pub n: usize,
    /// Trailing rows and columns ordered last and not factored.
    pub tail: usize,
    /// The fill-reducing order of the leading block.
    pub ordering: Ordering,
    /// The order came from a superset pattern (`Superset`).
    pub induced: bool,
    /// Supernodes before the tail's (all of them without a tail).
    pub lead_supernodes: usize,
    /// iperm[original index] = index in the factor's order.
    pub iperm: Vec<u32>,
    /// (value index in the input, index in `values`) of every entry.
    pub load: Vec<(u32, u32)>,
    pub supernodes: Vec<Supernode>,
    pub rows: Vec<u32>,
    pub updates: Vec<Update>,
    pub rel: Vec<u32>,
    len_values: usize,
}

/// The fill-reducing orders `Symbolic::analyze` tries on the `lead`
/// leading rows of the pattern `entries` (`perm_inv[old] = new`): AMD, and
/// for a block of at least `MIN_DISSECTION` rows with `cliques` the nested
/// dissection.
fn orders(
    lead: usize,
    entries: &[(usize, usize, usize)],
    cliques: &[Vec<usize>],
) -> Result<Vec<(Vec<usize>, Ordering)>, faer::sparse::FaerError> {
    let mut cols: Vec<Vec<usize>> = vec![Vec::new(); lead];
    for &(r, c, _) in entries {
        if r < lead {
            cols[c].push(r);
        }
    }
    let mut col_ptr = vec![0usize];
    let mut row_idx = Vec::new();
    for c in &mut cols {
        c.sort_unstable();
        c.dedup();
        row_idx.extend_from_slice(c);
        col_ptr.push(row_idx.len());
    }
    let mut out = vec![(
        dissection::amd_order(lead, &col_ptr, &row_idx)?,
        Ordering::Amd,
    )];
    if lead < MIN_DISSECTION || cliques.is_empty() {
        return Ok(out);
    }
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); lead];
    for (c, rows) in cols.iter().enumerate() {
        for &r in rows {
            if r != c {
                adj[c].push(r);
                adj[r].push(c);
            }
        }
    }
    let nd = dissection::dissection_order(&adj, cliques, dissection::LEAF_ROWS)?;
    out.push((nd, Ordering::Dissection));
    Ok(out)
}

/// Relaxed amalgamation (as CHOLMOD's `nrelax`/`zrelax`): a merged
/// supernode of at most `w` columns is kept when at most `frac` of its block
/// is explicit zeros. A block of width 1 (a body's quaternion-norm row) pays
/// the loop overhead of a block without its benefit; wide merges with many
/// zeros speed the factorisation up but slow every solve down (measured on
/// the sphere toy's Eq. 7 matrix: (4, 1.0), (16, 0.8), (48, 0.1) gave 64
/// supernodes of width up to 52 and 1.3× the stored values, the
/// factorisation 20 % slower and the solves 10 % slower than these).
const RELAX: [(usize, f64); 2] = [(2, 1.0), (8, 0.3)];

impl Symbolic {
    pub fn len_values(&self) -> usize {
        self.len_values
    }

    /// Sizes and operation counts (see [`FactorShape`](super::FactorShape)).
    pub fn shape(&self) -> super::FactorShape {
        let lead = &self.supernodes[..self.lead_supernodes];
        let mut factor_flops = 0;
        let mut solve_flops = 0;
        for sn in &self.supernodes {
            for u in &self.updates[sn.updates.0 as usize..sn.updates.1 as usize] {
                let wd = self.supernodes[u.src as usize].w as usize;
                let (nb, m) = ((u.b - u.a) as usize, u.m as usize);
                factor_flops += (0..nb).map(|ci| (m - ci) * wd).sum::<usize>();
            }
        }
        for sn in lead {
            let (w, r) = (sn.w as usize, sn.nrows as usize);
            factor_flops += w * w * w / 6 + w * w * r / 2;
            solve_flops += 2 * (w * (w + 1) / 2 + w * r);
        }
        super::FactorShape {
            ordering: self.ordering,
            induced: self.induced,
            n: self.n,
            tail: self.tail,
            supernodes: lead.len(),
            widest: lead.iter().map(|s| s.w as usize).max().unwrap_or(0),
            values: self.len_values,
            factor_flops,
            solve_flops,
        }
    }

    /// `entries`: (row, column, value index) of the lower triangle of the
    /// n × n matrix (row ≥ column; every diagonal entry present); its last
    /// `tail` rows and columns are ordered last and left unfactored.
    /// `cliques`: groups of leading rows that couple with each other (the
    /// rows on one body), for the nested dissection; empty: AMD only.
    ///
    /// `groups`: one key per leading column (original order), or empty:
    /// columns of different keys never share a supernode (the force
    /// solve's contact rows, one key per witness constraint: a pair's rows
    /// switched off together leave a supernode the factorisation skips).
    pub fn analyze(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        groups: &[u32],
        superset: Option<super::Superset>,
    ) -> Result<Self, faer::sparse::FaerError> {
        // 1. Fill-reducing orders of the leading block (the tail keeps its
        //    place at the end): AMD on the pattern of A + Aᵀ, and for a
        //    larger block a nested dissection too; with a superset pattern,
        //    its orders as well (restricted to this pattern, an order fills
        //    no more than it did there: a fill path here is one there).
        //    The cheapest factor of this pattern wins; the superset's
        //    orders, tried first, win ties.
        let mut best: Option<Self> = None;
        let mut consider = |cand: Self| {
            if best
                .as_ref()
                .is_none_or(|b| cand.shape().cost() < b.shape().cost())
            {
                best = Some(cand);
            }
        };
        if let Some(sup) = superset {
            let all: Vec<(usize, usize, usize)> =
                entries.iter().chain(sup.extra).copied().collect();
            for (order, kind) in orders(n - tail, &all, sup.cliques)? {
                let mut cand = Self::with_order(n, tail, entries, &order, kind, groups)?;
                cand.induced = true;
                consider(cand);
            }
        }
        for (order, kind) in orders(n - tail, entries, cliques)? {
            consider(Self::with_order(n, tail, entries, &order, kind, groups)?);
        }
        Ok(best.expect("AMD is always a candidate"))
    }

    /// The shapes of the factor under AMD and under the nested dissection
    /// (comparisons).
    #[cfg(test)]
    pub fn both_shapes(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
    ) -> (super::FactorShape, super::FactorShape) {
        let lead = n - tail;
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); lead];
        for &(r, c, _) in entries {
            if r < lead {
                cols[c].push(r);
            }
        }
        let (mut cp, mut ri) = (vec![0usize], Vec::new());
        for c in &mut cols {
            c.sort_unstable();
            c.dedup();
            ri.extend_from_slice(c);
            cp.push(ri.len());
        }
        let amd = dissection::amd_order(lead, &cp, &ri).unwrap();
        (
            Self::with_order(n, tail, entries, &amd, Ordering::Amd, &[])
                .unwrap()
                .shape(),
            Self::dissected(n, tail, entries, cliques, dissection::LEAF_ROWS).shape(),
        )
    }

    /// The factor under the nested dissection with leaves of `leaf_rows`
    /// (tests).
    #[cfg(test)]
    pub fn dissected(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        cliques: &[Vec<usize>],
        leaf_rows: usize,
    ) -> Self {
        let lead = n - tail;
        let mut adj: Vec<Vec<usize>> = vec![Vec::new(); lead];
        for &(r, c, _) in entries {
            if r < lead && r != c {
                adj[c].push(r);
                adj[r].push(c);
            }
        }
        for a in &mut adj {
            a.sort_unstable();
            a.dedup();
        }
        let nd = dissection::dissection_order(&adj, cliques, leaf_rows).unwrap();
        Self::with_order(n, tail, entries, &nd, Ordering::Dissection, &[]).unwrap()
    }

    /// [`analyze`](Self::analyze) with the leading block's fill-reducing
    /// order given (`perm_inv[old] = new`).
    fn with_order(
        n: usize,
        tail: usize,
        entries: &[(usize, usize, usize)],
        perm_inv: &[usize],
        ordering: Ordering,
        groups: &[u32],
    ) -> Result<Self, faer::sparse::FaerError> {
        // 2. Elimination tree in the postordered order.
        let iperm = postordered(n, tail, entries, perm_inv);
        let rows = permuted_rows(entries, &iperm, n);
        let parent = etree(&rows);
        // 3. Pattern of L, column by column.
        let colpat = column_patterns(&rows, &parent);
        // 4. Supernodes and their rows.
        let starts = supernode_starts(tail, &parent, &colpat, &iperm, groups);
        let mut layout = Layout::new(n, &starts, &colpat)?;
        // 5. Load map: entry (r, c) → its place in L's blocks.
        let load = entries
            .iter()
            .map(|&(rr, c, src)| (src as u32, layout.place(iperm[rr], iperm[c]) as u32))
            .collect();
        // 6. Update plan.
        let (updates, rel) = layout.update_plan();
        let lead_supernodes = layout.supernodes.len() - usize::from(tail > 0);
        Ok(Self {
            n,
            tail,
            ordering,
            induced: false,
            lead_supernodes,
            iperm: iperm.iter().map(|&v| v as u32).collect(),
            load,
            supernodes: layout.supernodes,
            rows: layout.rows,
            updates,
            rel,
            len_values: layout.len_values,
        })
    }
}

/// Row k of the lower triangle of `entries` permuted by `iperm`, restricted
/// to the leading `size` rows and columns: its columns j < k, ascending.
fn permuted_rows(
    entries: &[(usize, usize, usize)],
    iperm: &[usize],
    size: usize,
) -> Vec<Vec<usize>> {
    let mut r = vec![Vec::new(); size];
    for &(rr, c, _) in entries {
        if rr >= size || c >= size {
            continue;
        }
        let (i, j) = (iperm[rr], iperm[c]);
        let (hi, lo) = (i.max(j), i.min(j));
        if hi != lo {
            r[hi].push(lo);
        }
    }
    for row in &mut r {
        row.sort_unstable();
        row.dedup();
    }
    r
}

/// The factor's order (`iperm[old] = new`): the fill-reducing order
/// `perm_inv` of the leading block followed by a postorder of its
/// elimination tree (every subtree a contiguous range of columns), then the
/// tail: a topological order of the whole tree.
fn postordered(
    n: usize,
    tail: usize,
    entries: &[(usize, usize, usize)],
    perm_inv: &[usize],
) -> Vec<usize> {
    let lead = n - tail;
    let parent = etree(&permuted_rows(entries, perm_inv, lead));
    let post = postorder(&parent);
    // post[new] = old (in the AMD order); compose.
    let mut post_inv = vec![0usize; lead];
    for (new, &old) in post.iter().enumerate() {
        post_inv[old] = new;
    }
    let mut iperm: Vec<usize> = perm_inv.iter().map(|&v| post_inv[v]).collect();
    iperm.extend(lead..n);
    iperm
}

/// Pattern of L, column by column (rows strictly below the diagonal,
/// ascending): row k's pattern is the union of the tree paths from its
/// entries up to k.
fn column_patterns(rows: &[Vec<usize>], parent: &[usize]) -> Vec<Vec<u32>> {
    let n = rows.len();
    let mut colpat: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut mark = vec![usize::MAX; n];
    for (k, row) in rows.iter().enumerate() {
        mark[k] = k;
        for &i in row {
            let mut j = i;
            while mark[j] != k {
                mark[j] = k;
                colpat[j].push(k as u32);
                j = parent[j];
                if j == usize::MAX {
                    break;
                }
            }
        }
    }
    colpat
}

/// First columns of the supernodes, then the end. Fundamental supernodes (a
/// column joins its only child's run when its pattern is the child's minus
/// the child itself), then relaxed amalgamation: a supernode absorbs the
/// child that ends right before it when the explicit zeros that adds stay
/// few; `groups` splits them again. The tail is one supernode of its own.
fn supernode_starts(
    tail: usize,
    parent: &[usize],
    colpat: &[Vec<u32>],
    iperm: &[usize],
    groups: &[u32],
) -> Vec<usize> {
    let n = parent.len();
    let lead = n - tail;
    let mut children = vec![0u32; n];
    for &p in parent {
        if p != usize::MAX {
            children[p] += 1;
        }
    }
    let mut starts = vec![0usize];
    for j in 1..lead {
        let same =
            parent[j - 1] == j && children[j] == 1 && colpat[j - 1].len() == colpat[j].len() + 1;
        if !same {
            starts.push(j);
        }
    }
    starts.push(lead);
    let mut starts = if lead > 0 {
        split_groups(&amalgamate(&starts, parent, colpat), iperm, groups)
    } else {
        vec![0]
    };
    if tail > 0 {
        starts.push(n);
    }
    starts
}

/// The supernodes' block layout, while the symbolic factor is built.
struct Layout {
    supernodes: Vec<Supernode>,
    /// Every supernode's below rows, concatenated.
    rows: Vec<u32>,
    /// Supernode of each column.
    col_sn: Vec<u32>,
    len_values: usize,
}

impl Layout {
    /// Lays out the supernodes starting at `starts`. A relaxed supernode's
    /// columns take the union of their patterns (the last column's rows plus
    /// the explicit zeros of the earlier ones): below rows = ∪ colpat[j]
    /// minus the supernode's own columns.
    fn new(
        n: usize,
        starts: &[usize],
        colpat: &[Vec<u32>],
    ) -> Result<Self, faer::sparse::FaerError> {
        let mut supernodes = Vec::with_capacity(starts.len());
        let mut all_rows: Vec<u32> = Vec::new();
        let mut col_sn = vec![0u32; n];
        let mut val = 0usize;
        for win in starts.windows(2) {
            let (c0, c1) = (win[0], win[1]);
            let mut below: Vec<u32> = (c0..c1)
                .flat_map(|j| colpat[j].iter().copied())
                .filter(|&r| r as usize >= c1)
                .collect();
            below.sort_unstable();
            below.dedup();
            let w = c1 - c0;
            for c in &mut col_sn[c0..c1] {
                *c = supernodes.len() as u32;
            }
            supernodes.push(Supernode {
                c0: c0 as u32,
                w: w as u32,
                rows: all_rows.len() as u32,
                nrows: below.len() as u32,
                val: val as u32,
                updates: (0, 0),
            });
            val += (w + below.len()) * w;
            all_rows.extend_from_slice(&below);
        }
        if val > u32::MAX as usize || all_rows.len() > u32::MAX as usize {
            return Err(faer::sparse::FaerError::IndexOverflow);
        }
        Ok(Self {
            supernodes,
            rows: all_rows,
            col_sn,
            len_values: val,
        })
    }

    /// Supernode `s`'s rows below its diagonal block.
    fn below(&self, s: &Supernode) -> &[u32] {
        &self.rows[s.rows as usize..(s.rows + s.nrows) as usize]
    }

    /// Local row of global row r in supernode s (r ≥ its first column).
    fn local(&self, s: &Supernode, r: usize) -> usize {
        let c0 = s.c0 as usize;
        if r < c0 + s.w as usize {
            r - c0
        } else {
            s.w as usize
                + self
                    .below(s)
                    .binary_search(&(r as u32))
                    .expect("a row of L's pattern is in its supernode's rows")
        }
    }

    /// Index in the values of the entry at permuted row `i`, column `j` (either
    /// triangle).
    fn place(&self, i: usize, j: usize) -> usize {
        let (r, cc) = (i.max(j), i.min(j));
        let s = &self.supernodes[self.col_sn[cc] as usize];
        let lr = self.local(s, r);
        s.val as usize + lr * s.w as usize + (cc - s.c0 as usize)
    }

    /// Update plan: each supernode d updates the supernodes that own its
    /// below rows; the rows falling in one target's columns are a contiguous
    /// run of d's ascending rows. Sets every supernode's `updates` range and
    /// returns the updates and their local rows.
    fn update_plan(&mut self) -> (Vec<Update>, Vec<u32>) {
        let mut incoming: Vec<Vec<Update>> = vec![Vec::new(); self.supernodes.len()];
        let mut rel = Vec::new();
        for (d, sd) in self.supernodes.iter().enumerate() {
            let below = self.below(sd);
            let mut a = 0;
            while a < below.len() {
                let t = self.col_sn[below[a] as usize] as usize;
                let st = &self.supernodes[t];
                let end_col = (st.c0 + st.w) as usize;
                let mut b = a;
                while b < below.len() && (below[b] as usize) < end_col {
                    b += 1;
                }
                let r0 = rel.len();
                for &r in &below[a..] {
                    rel.push(self.local(st, r as usize) as u32);
                }
                incoming[t].push(Update {
                    src: d as u32,
                    a: a as u32,
                    b: b as u32,
                    m: (below.len() - a) as u32,
                    rel: r0 as u32,
                });
                a = b;
            }
        }
        let mut updates = Vec::new();
        for (s, inc) in incoming.into_iter().enumerate() {
            let first = updates.len() as u32;
            updates.extend(inc);
            self.supernodes[s].updates = (first, updates.len() as u32);
        }
        (updates, rel)
    }
}

/// Relaxed amalgamation of the fundamental supernodes `starts` (first
/// columns, then the end): walking them in order (a postorder of the supernodal
/// tree), each absorbs the merged supernode just before it while that one
/// is its child and the merged block stays within [`RELAX`].
fn amalgamate(starts: &[usize], parent: &[usize], colpat: &[Vec<u32>]) -> Vec<usize> {
    let end = *starts.last().expect("starts end with the last column + 1");
    // True entries of column j of L (diagonal included).
    let count = |j: usize| colpat[j].len() + 1;
    // Merged runs so far: (first column, last column + 1, true entries).
    let mut runs: Vec<(usize, usize, usize)> = Vec::new();
    for win in starts.windows(2) {
        let (mut c0, c1) = (win[0], win[1]);
        let mut entries: usize = (c0..c1).map(count).sum();
        // Rows below the run: those of its last column minus the run.
        let below = colpat[c1 - 1].len();
        while let Some(&(p0, p1, pe)) = runs.last() {
            // The previous run is a child iff its last column's parent is in
            // this run.
            let par = parent[p1 - 1];
            if par == usize::MAX || par < c0 || par >= c1 {
                break;
            }
            let w = c1 - p0;
            let block = w * (w + 1) / 2 + w * below;
            let zeros = block.saturating_sub(entries + pe);
            let ok = RELAX
                .iter()
                .any(|&(max_w, frac)| w <= max_w && zeros as f64 <= frac * block as f64)
                || zeros as f64 <= 0.05 * block as f64;
            if !ok {
                break;
            }
            runs.pop();
            c0 = p0;
            entries += pe;
        }
        runs.push((c0, c1, entries));
    }
    let mut out: Vec<usize> = runs.iter().map(|r| r.0).collect();
    out.push(end);
    out
}

/// Elimination tree (Liu) from each row's columns below the diagonal;
/// `usize::MAX` marks a root.
fn etree(rows: &[Vec<usize>]) -> Vec<usize> {
    let n = rows.len();
    let mut parent = vec![usize::MAX; n];
    let mut ancestor = vec![usize::MAX; n];
    for (k, row) in rows.iter().enumerate() {
        for &i in row {
            let mut j = i;
            while ancestor[j] != usize::MAX && ancestor[j] != k {
                let next = ancestor[j];
                ancestor[j] = k;
                j = next;
            }
            if ancestor[j] == usize::MAX {
                ancestor[j] = k;
                parent[j] = k;
            }
        }
    }
    parent
}

/// A postorder of the forest `parent`: post[new] = old, children before
/// parents, each subtree contiguous, children in increasing order.
fn postorder(parent: &[usize]) -> Vec<usize> {
    let n = parent.len();
    let mut head = vec![usize::MAX; n];
    let mut next = vec![usize::MAX; n];
    for j in (0..n).rev() {
        if parent[j] != usize::MAX {
            next[j] = head[parent[j]];
            head[parent[j]] = j;
        }
    }
    let mut post = Vec::with_capacity(n);
    let mut stack = Vec::new();
    for (root, &p) in parent.iter().enumerate() {
        if p != usize::MAX {
            continue;
        }
        stack.push(root);
        while let Some(&top) = stack.last() {
            let child = head[top];
            if child == usize::MAX {
                post.push(top);
                stack.pop();
            } else {
                head[top] = next[child];
                stack.push(child);
            }
        }
    }
    post
}

/// Supernode starts (`starts`, ending with the leading block's end) split
/// wherever two consecutive columns have different `groups` keys (original
/// order; `iperm[old] = new`); unchanged when `groups` is empty. Any run of
/// a supernode's columns is a valid (relaxed) supernode: splitting never
/// adds fill.
fn split_groups(starts: &[usize], iperm: &[usize], groups: &[u32]) -> Vec<usize> {
    let lead = *starts.last().unwrap_or(&0);
    if groups.len() != lead {
        return starts.to_vec();
    }
    let mut perm = vec![0usize; lead];
    for (old, &new) in iperm[..lead].iter().enumerate() {
        perm[new] = old;
    }
    let mut out = Vec::with_capacity(starts.len());
    for w in starts.windows(2) {
        out.push(w[0]);
        for j in w[0] + 1..w[1] {
            if groups[perm[j]] != groups[perm[j - 1]] {
                out.push(j);
            }
        }
    }
    out.push(lead);
    out
}
