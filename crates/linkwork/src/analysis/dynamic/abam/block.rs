//! The dependent block `B = Phi_q[rows, D]` of the partition, its factors, and the blocks of the
//! partitions before it (a mechanism turning round passes through the same few partitions
//! again).

use crate::linalg::{Pattern, SparseLu};

/// Partitions whose blocks are kept for a return ([`Blocks::select`]): the quick-return under
/// its crank torque passes through 4 to 6 partitions a turn, 97 changes in 2 s, each of which
/// built its block and the symbolic structure of its factors afresh (the block's pattern, its
/// maps and an LU order found by partial pivoting).
const KEPT_BLOCKS: usize = 8;

/// The dependent block `B = Phi_q[rows, dep]` of a partition as a sparse matrix: its pattern
/// (fixed while the partition is), where each entry of `Phi_q` goes, and its LU factors.
pub(super) struct Block {
    /// The partition's independent rows and dependent coordinates, ascending.
    rows: Vec<usize>,
    dep: Vec<usize>,
    /// (entries of `Phi_q`) position of each entry in `B`'s values, `usize::MAX` outside `B`.
    map: Vec<usize>,
    /// (n - r) for each independent coordinate, its entries in the independent rows:
    /// `(position in rows, index into Phi_q's entries)`, the columns of `Phi_q[rows, I]`.
    ind_cols: Vec<Vec<(usize, usize)>>,
    pub(super) lu: SparseLu,
}

impl Block {
    /// The block of the rows `rows` and dependent coordinates `dep` (both ascending) of `Phi_q`
    /// with entries `entries`; `ind` are the other coordinates.
    fn new(entries: &[(usize, usize)], m: usize, n: usize, rows: &[usize], dep: &[usize], ind: &[usize]) -> Block {
        let mut row_pos = vec![usize::MAX; m];
        for (k, &r) in rows.iter().enumerate() {
            row_pos[r] = k;
        }
        // Column role: dependent (local index) or independent (!local index).
        let mut dep_pos = vec![usize::MAX; n];
        let mut ind_pos = vec![usize::MAX; n];
        for (k, &c) in dep.iter().enumerate() {
            dep_pos[c] = k;
        }
        for (k, &c) in ind.iter().enumerate() {
            ind_pos[c] = k;
        }
        let mut ind_cols = vec![vec![]; ind.len()];
        // (local column, local row, entry) of every entry of B, in compressed-column order.
        let mut inside: Vec<(usize, usize, usize)> = Vec::new();
        for (e, &(r, c)) in entries.iter().enumerate() {
            let i = row_pos[r];
            if i == usize::MAX {
                continue;
            }
            if dep_pos[c] != usize::MAX {
                inside.push((dep_pos[c], i, e));
            } else {
                ind_cols[ind_pos[c]].push((i, e));
            }
        }
        inside.sort_unstable();
        let r = dep.len();
        let mut col_ptr = vec![0; r + 1];
        let mut row_idx = Vec::with_capacity(inside.len());
        let mut map = vec![usize::MAX; entries.len()];
        let mut last = (usize::MAX, usize::MAX);
        for &(c, i, e) in &inside {
            if (c, i) != last {
                row_idx.push(i);
                col_ptr[c + 1] += 1;
                last = (c, i);
            }
            map[e] = row_idx.len() - 1;
        }
        for c in 0..r {
            col_ptr[c + 1] += col_ptr[c];
        }
        let pattern = Pattern { col_ptr, row_idx, map: vec![], nrows: r };
        // The pattern has a nonzero pivot in every column (the partition found one), so the
        // symbolic analysis cannot fail for want of one; only allocation can.
        let lu = SparseLu::new(pattern).expect("symbolic LU of the dependent block");
        Block { rows: rows.to_vec(), dep: dep.to_vec(), map, ind_cols, lu }
    }

    /// Factor `B` with the values `jac` of `Phi_q`'s entries; false when it is singular.
    pub(super) fn factor(&mut self, jac: &[f64]) -> bool {
        let (_, values) = self.lu.pattern_and_values();
        values.fill(0.0);
        for (&p, &v) in self.map.iter().zip(jac) {
            if p != usize::MAX {
                values[p] += v;
            }
        }
        self.lu.factor().is_ok()
    }
}

/// The current partition's dependent block with its factors and what was made from them: the
/// values they were made from, where, the sensitivities `B^-1 Phi_q[rows, I]`, and the
/// right-hand side of its solves.
pub(super) struct Blocks {
    /// The sparse dependent block and its factors (`None` before the first choice).
    pub(super) current: Option<Block>,
    /// The blocks of the last [`KEPT_BLOCKS`] other partitions, the newest last.
    kept: Vec<Block>,
    /// The values of `Phi_q`'s entries that `B`'s current factors were made from, and whether
    /// they are factors (false after a singular `B`).
    pub(super) factored: Vec<f64>,
    pub(super) factored_ok: bool,
    /// The positions at which `B` was last factored.
    pub(super) factored_q: Vec<f64>,
    /// (r p) the columns `B^-1 Phi_q[rows, I]` ([`Blocks::sensitivities`]), and whether they are
    /// those of the last evaluation, with `B` as factored now.
    pub(super) sens: Vec<f64>,
    pub(super) sens_fresh: bool,
    /// (r) right-hand side and solution of [`Blocks::solve`].
    pub(super) rhs: Vec<f64>,
}

impl Blocks {
    /// No block yet, for `n` coordinates.
    pub(super) fn new(n: usize) -> Blocks {
        Blocks {
            current: None,
            kept: vec![],
            factored: vec![],
            factored_ok: false,
            factored_q: vec![0.0; n],
            sens: vec![],
            sens_fresh: false,
            rhs: vec![],
        }
    }

    /// Make the block of the rows `rows` and dependent coordinates `dep` (`ind` the others) of
    /// `Phi_q` (`m x n`, entries `entries`) the current one: kept if it is, else taken back
    /// from the kept blocks or built; the block it replaces is kept.
    pub(super) fn select(
        &mut self,
        entries: &[(usize, usize)],
        m: usize,
        n: usize,
        rows: &[usize],
        dep: &[usize],
        ind: &[usize],
    ) {
        if self.current.as_ref().is_some_and(|b| b.rows == rows && b.dep == dep) {
            return;
        }
        let block = match self.kept.iter().position(|b| b.rows == rows && b.dep == dep) {
            Some(k) => self.kept.remove(k),
            None => Block::new(entries, m, n, rows, dep, ind),
        };
        if let Some(old) = self.current.replace(block) {
            if self.kept.len() == KEPT_BLOCKS {
                self.kept.remove(0);
            }
            self.kept.push(old);
        }
    }

    /// Sizes for `r` dependent and `p` independent coordinates; nothing factored.
    pub(super) fn resize(&mut self, r: usize, p: usize) {
        self.rhs.resize(r, 0.0);
        self.sens.resize(r * p, 0.0);
        self.sens_fresh = false;
        self.factored_ok = false;
    }

    /// Whether the factors are those of `B` with the values `jac` of `Phi_q`'s entries.
    pub(super) fn holds(&self, jac: &[f64]) -> bool {
        self.factored_ok && self.factored == jac
    }

    /// Factor `B` with the values `jac` of `Phi_q`'s entries at the positions `q`; false when it
    /// is singular.
    pub(super) fn factor(&mut self, jac: &[f64], q: &[f64]) -> bool {
        self.factored.clear();
        self.factored.extend_from_slice(jac);
        self.factored_q.copy_from_slice(q);
        self.sens_fresh = false;
        self.factored_ok = self.current.as_mut().is_none_or(|b| b.factor(jac));
        self.factored_ok
    }

    /// `rhs <- B^-1 rhs` with the factors of [`Blocks::factor`].
    pub(super) fn solve(&mut self) {
        if let Some(b) = self.current.as_mut() {
            b.lu.solve(&mut self.rhs);
        }
    }

    /// `sens = B^-1 Phi_q[rows, I]` (`p` solves, column `j` that of the `j`-th independent
    /// coordinate), with `B` as factored and the values `jac` of `Phi_q`'s entries.
    pub(super) fn sensitivities(&mut self, jac: &[f64]) {
        let r = self.rhs.len();
        let Some(block) = self.current.as_mut() else { return };
        for (j, col) in block.ind_cols.iter().enumerate() {
            let s = &mut self.sens[j * r..(j + 1) * r];
            s.fill(0.0);
            for &(i, e) in col {
                s[i] += jac[e];
            }
            block.lu.solve(s);
        }
        self.sens_fresh = true;
    }

    /// `rhs <- Phi_q[rows, I] x`, `x: (n - r)` indexed as the independent coordinates, with the
    /// values `jac` of `Phi_q`'s entries.
    pub(super) fn times_independent(&mut self, jac: &[f64], x: &[f64]) {
        self.rhs.fill(0.0);
        let Some(block) = self.current.as_ref() else { return };
        for (col, &xj) in block.ind_cols.iter().zip(x) {
            for &(i, e) in col {
                self.rhs[i] += jac[e] * xj;
            }
        }
    }
}
