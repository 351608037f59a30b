//! LU of small sparse matrices in dense storage, with the pivot order kept from one
//! factorization to the next ([`super::SparseLu`] up to [`super::DENSE_LU_MAX_ORDER`]).
//!
//! The first factorization of a pattern is Gaussian elimination with partial pivoting. Its row
//! order then fixes the structure of `L` and `U` (a symbolic elimination of the pattern's
//! entries in that order: every entry that can be nonzero, whatever the values), and the
//! following factorizations eliminate in the same order over that structure alone, as sparse
//! refactorization does (KLU's `klu_refactor`; Davis and Palamadai Natarajan 2010, "Algorithm
//! 907: KLU", ACM TOMS 37(3)). A mechanism's matrices keep their pattern while their values
//! move, so the order found once stays good for many factorizations, and the work is that of
//! the entries alone (docs/performance.md, "The LU of small matrices", counts it).
//!
//! A kept pivot must be at least [`KEEP_PIVOT`] times the largest entry below it in its column
//! (threshold partial pivoting); where one is not, the matrix is eliminated again with partial
//! pivoting and its order becomes the kept one.

/// A kept pivot must be at least this fraction of the largest entry of its column at its step:
/// 0.1, the threshold of sparse LU codes (Duff, Erisman and Reid, "Direct Methods for Sparse
/// Matrices", section 7.8: each step's growth of the entries is then at most 11 times, against
/// 2 for partial pivoting, and in practice far less). Below it the order is found again.
pub const KEEP_PIVOT: f64 = 0.1;

/// The largest order (the solves work in a stack array of this length): at least
/// [`super::DENSE_LU_MAX_ORDER`].
const WIDTH: usize = 64;
const MASK: usize = WIDTH - 1;
const _: () = assert!(super::DENSE_LU_MAX_ORDER <= WIDTH && WIDTH.is_power_of_two());

/// LU factors `P A = L U` with the structure of the kept order.
#[derive(Debug)]
pub(super) struct DenseLu {
    n: usize,
    /// (n x n) column-major scratch of the elimination with partial pivoting.
    lu: Vec<f64>,
    /// The row interchanges of the elimination that found the order (row `k` swapped with row
    /// `swaps[k] >= k`, in order): `P`.
    swaps: Vec<usize>,
    /// (n) the row of `P A` that each row of `A` becomes.
    position: Vec<usize>,
    /// (n) the row of `A` at each row of `P A`.
    rows: Vec<usize>,
    /// For each column `k`, the rows below `k` of `L`'s structure (`lower[lower_ptr[k]..]`);
    /// `lower_col` holds each entry's column, so that the solves run over the entries in one
    /// loop.
    lower_ptr: Vec<usize>,
    lower: Vec<usize>,
    lower_col: Vec<usize>,
    /// For each column `j`, the rows above `j` of `U`'s structure, and each entry's column.
    upper_ptr: Vec<usize>,
    upper: Vec<usize>,
    upper_col: Vec<usize>,
    /// The factors' values, packed: `L`'s in the order of `lower`, then `U`'s above the
    /// diagonal in the order of `upper`, then the diagonal (`vals[diag + k]`). Once a
    /// factorization is done, `U`'s entries are divided by their row's diagonal (`U = D V`, `V`
    /// unit upper triangular), so that both solves are loops over entries with one scaling.
    vals: Vec<f64>,
    diag: usize,
    /// The reciprocals of `U`'s diagonal.
    dinv: Vec<f64>,
    /// (entries of the pattern) the slot in `vals` of each entry of `A`.
    slot_of_entry: Vec<usize>,
    /// The kept elimination as slots: step `k` updates, for each column `j` right of it with
    /// `U[k, j]` in the structure (`update_ptr[k]..update_ptr[k + 1]` into `factor_slot`), the
    /// entries `(i, j)` for each row `i` of `lower[k]`, whose slots are `targets[t..]` from
    /// `target_ptr` (one run of `|lower[k]|` slots per column).
    update_ptr: Vec<usize>,
    factor_slot: Vec<usize>,
    targets: Vec<usize>,
    /// For each row `k`, the columns right of `k` of `U`'s structure (scratch of the symbolic
    /// elimination).
    right_ptr: Vec<usize>,
    right: Vec<usize>,
    /// (n x n) scratch of the symbolic elimination: structural entries, then their slots.
    filled: Vec<bool>,
    slots: Vec<usize>,
    /// Whether an order has been found (the structure describes `swaps`).
    ordered: bool,
}

impl DenseLu {
    /// Factors of order `n`, no order found yet. The structure's buffers are reserved for the
    /// densest factors of that order (for the updates, `sum (n - 1 - k)^2`, about `n^3 / 3`: 286
    /// kB at order 48), so that a new order, found when a kept one fails, allocates nothing.
    pub(super) fn new(n: usize) -> DenseLu {
        assert!(n <= WIDTH, "dense LU of order {n} above {WIDTH}");
        let triangle = n * n.saturating_sub(1) / 2;
        let updates = n.saturating_sub(1) * n * (2 * n).saturating_sub(1) / 6;
        DenseLu {
            n,
            lu: vec![0.0; n * n],
            swaps: vec![0; n],
            position: vec![0; n],
            rows: vec![0; n],
            lower_ptr: vec![0; n + 1],
            lower: Vec::with_capacity(triangle),
            lower_col: Vec::with_capacity(triangle),
            upper_ptr: vec![0; n + 1],
            upper: Vec::with_capacity(triangle),
            upper_col: Vec::with_capacity(triangle),
            vals: Vec::with_capacity(n * n),
            diag: 0,
            dinv: vec![0.0; n],
            slot_of_entry: vec![],
            update_ptr: vec![0; n + 1],
            factor_slot: Vec::with_capacity(triangle),
            targets: Vec::with_capacity(updates),
            right_ptr: vec![0; n + 1],
            right: Vec::with_capacity(triangle),
            filled: vec![false; n * n],
            slots: vec![usize::MAX; n * n],
            ordered: false,
        }
    }

    /// Factor the matrix of compressed columns `(col_ptr, row_idx, values)`: in the kept order
    /// when its pivots pass [`KEEP_PIVOT`], else by partial pivoting, whose order is kept. A zero
    /// column at its step is left as it is: the matrix is singular, its solves give infinities,
    /// and the condition estimate says so. True when the kept order was used.
    pub(super) fn factor(&mut self, col_ptr: &[usize], row_idx: &[usize], values: &[f64]) -> bool {
        if self.ordered && self.refactor(values) {
            return true;
        }
        let n = self.n;
        self.lu.fill(0.0);
        for c in 0..n {
            for k in col_ptr[c]..col_ptr[c + 1] {
                self.lu[c * n + row_idx[k]] = values[k];
            }
        }
        partial_pivoting(&mut self.lu, n, &mut self.swaps);
        self.order(col_ptr, row_idx);
        // The factors just made, into their slots.
        for j in 0..n {
            for i in 0..n {
                let slot = self.slots[j * n + i];
                if slot != usize::MAX {
                    self.vals[slot] = self.lu[j * n + i];
                }
            }
            self.dinv[j] = 1.0 / self.lu[j * n + j];
        }
        self.unit_upper();
        false
    }

    /// `U = D V`: `U`'s entries divided by their row's diagonal, once its elimination is done.
    fn unit_upper(&mut self) {
        let nl = self.lower.len();
        let uval = &mut self.vals[nl..self.diag];
        for (u, &i) in uval.iter_mut().zip(&self.upper) {
            *u *= self.dinv[i];
        }
    }

    /// Eliminate in the kept order over its structure, in the packed values; false (the
    /// factors spoiled) when a pivot falls below [`KEEP_PIVOT`] of its column.
    fn refactor(&mut self, values: &[f64]) -> bool {
        let vals = &mut self.vals;
        vals.fill(0.0);
        for (&slot, &v) in self.slot_of_entry.iter().zip(values) {
            vals[slot] = v;
        }
        let mut column = [0.0; WIDTH];
        let mut t = 0;
        for k in 0..self.n {
            let below = self.lower_ptr[k]..self.lower_ptr[k + 1];
            let width = below.len();
            let pivot = vals[self.diag + k];
            // Each entry below against the pivot, rather than their largest: a running maximum
            // is a chain of dependent operations. NaN fails (the comparisons are false), and
            // partial pivoting then sees the same values.
            let size = pivot.abs();
            let kept = size >= 0.0 && vals[below.clone()].iter().all(|x| KEEP_PIVOT * x.abs() <= size);
            if !kept {
                return false;
            }
            let inv = 1.0 / pivot;
            self.dinv[k] = inv;
            let updates = &self.factor_slot[self.update_ptr[k]..self.update_ptr[k + 1]];
            if pivot == 0.0 {
                t += width * updates.len();
                continue;
            }
            let column = &mut column[..width];
            for (c, x) in column.iter_mut().zip(&mut vals[below]) {
                *x *= inv;
                *c = *x;
            }
            for &fs in updates {
                let f = vals[fs];
                let run = &self.targets[t..t + width];
                t += width;
                if f != 0.0 {
                    for (&l, &target) in column.iter().zip(run) {
                        vals[target] -= l * f;
                    }
                }
            }
        }
        self.unit_upper();
        true
    }

    /// Keep the order of `swaps`: where each row goes, the structure of `L` and `U` that the
    /// pattern's entries fill in that order, the slot of each entry, and the elimination's
    /// updates as slots.
    fn order(&mut self, col_ptr: &[usize], row_idx: &[usize]) {
        let n = self.n;
        // `rows[k]`: the row of A at position k of P A.
        let rows = &mut self.rows;
        rows.iter_mut().enumerate().for_each(|(k, r)| *r = k);
        for (k, &p) in self.swaps.iter().enumerate() {
            rows.swap(k, p);
        }
        for (k, &r) in rows.iter().enumerate() {
            self.position[r] = k;
        }
        let s = &mut self.filled;
        s.fill(false);
        for c in 0..n {
            for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
                s[c * n + self.position[r]] = true;
            }
        }
        // The symbolic elimination: step k fills (i, j) for i in L's column k, j in U's row k.
        let (right, right_ptr) = (&mut self.right, &mut self.right_ptr);
        right.clear();
        self.lower.clear();
        for k in 0..n {
            self.lower_ptr[k] = self.lower.len();
            right_ptr[k] = right.len();
            self.lower.extend((k + 1..n).filter(|&i| s[k * n + i]));
            right.extend((k + 1..n).filter(|&j| s[j * n + k]));
            for &j in &right[right_ptr[k]..] {
                for &i in &self.lower[self.lower_ptr[k]..] {
                    s[j * n + i] = true;
                }
            }
        }
        self.lower_ptr[n] = self.lower.len();
        right_ptr[n] = right.len();
        self.upper.clear();
        for j in 0..n {
            self.upper_ptr[j] = self.upper.len();
            self.upper.extend((0..j).filter(|&i| s[j * n + i]));
        }
        self.upper_ptr[n] = self.upper.len();
        for (cols, ptr) in [(&mut self.lower_col, &self.lower_ptr), (&mut self.upper_col, &self.upper_ptr)] {
            cols.clear();
            cols.extend(ptr.windows(2).enumerate().flat_map(|(k, w)| std::iter::repeat_n(k, w[1] - w[0])));
        }
        // Slots: L's, then U's, then the diagonal.
        let slots = &mut self.slots;
        slots.fill(usize::MAX);
        for k in 0..n {
            for (e, &i) in self.lower.iter().enumerate().take(self.lower_ptr[k + 1]).skip(self.lower_ptr[k]) {
                slots[k * n + i] = e;
            }
        }
        let (nl, nu) = (self.lower.len(), self.upper.len());
        for j in 0..n {
            for (e, &i) in self.upper.iter().enumerate().take(self.upper_ptr[j + 1]).skip(self.upper_ptr[j]) {
                slots[j * n + i] = nl + e;
            }
            slots[j * n + j] = nl + nu + j;
        }
        self.diag = nl + nu;
        self.vals.clear();
        self.vals.resize(nl + nu + n, 0.0);
        self.slot_of_entry.clear();
        for c in 0..n {
            self.slot_of_entry
                .extend(row_idx[col_ptr[c]..col_ptr[c + 1]].iter().map(|&r| slots[c * n + self.position[r]]));
        }
        self.factor_slot.clear();
        self.targets.clear();
        for k in 0..n {
            self.update_ptr[k] = self.factor_slot.len();
            for &j in &right[right_ptr[k]..right_ptr[k + 1]] {
                self.factor_slot.push(slots[j * n + k]);
                self.targets
                    .extend(self.lower[self.lower_ptr[k]..self.lower_ptr[k + 1]].iter().map(|&i| slots[j * n + i]));
            }
        }
        self.update_ptr[n] = self.factor_slot.len();
        self.ordered = true;
    }

    /// Solve `A x = b` in place: `P A = L D V` (`V` unit upper triangular), so `x = V^-1 D^-1
    /// L^-1 P b`, each triangle one loop over its entries in an order where every entry reads a
    /// finished value.
    pub(super) fn solve(&self, b: &mut [f64]) {
        let n = self.n;
        let (lval, vval) = self.vals[..self.diag].split_at(self.lower.len());
        let mut x = [0.0; WIDTH];
        for (xk, &r) in x.iter_mut().zip(&self.rows) {
            *xk = b[r];
        }
        // The masks are the identity (every index is below `n <= WIDTH`); they let the compiler
        // drop the bounds checks of these innermost loops.
        for ((&i, &k), &l) in self.lower.iter().zip(&self.lower_col).zip(lval) {
            x[i & MASK] -= l * x[k & MASK];
        }
        for (xk, &d) in x.iter_mut().zip(&self.dinv) {
            *xk *= d;
        }
        for ((&i, &j), &v) in self.upper.iter().zip(&self.upper_col).zip(vval).rev() {
            x[i & MASK] -= v * x[j & MASK];
        }
        b[..n].copy_from_slice(&x[..n]);
    }

    /// Solve `A^T x = b` in place: `V^T D L^T P x = b`.
    pub(super) fn solve_transpose(&self, b: &mut [f64]) {
        let n = self.n;
        let (lval, vval) = self.vals[..self.diag].split_at(self.lower.len());
        let mut x = [0.0; WIDTH];
        x[..n].copy_from_slice(&b[..n]);
        for ((&i, &j), &v) in self.upper.iter().zip(&self.upper_col).zip(vval) {
            x[j & MASK] -= v * x[i & MASK];
        }
        for (xk, &d) in x.iter_mut().zip(&self.dinv) {
            *xk *= d;
        }
        for ((&i, &k), &l) in self.lower.iter().zip(&self.lower_col).zip(lval).rev() {
            x[k & MASK] -= l * x[i & MASK];
        }
        for (&xk, &r) in x.iter().zip(&self.rows) {
            b[r] = xk;
        }
    }
}

/// `P A = L U` in place by Gaussian elimination with partial pivoting (column-major `a` of order
/// `n`, the row interchanges in `swaps`); zero multipliers are skipped column by column. A zero
/// pivot column is left as it is.
fn partial_pivoting(a: &mut [f64], n: usize, swaps: &mut [usize]) {
    for k in 0..n {
        let col = &a[k * n..(k + 1) * n];
        let p = (k..n).fold(k, |best, i| if col[i].abs() > col[best].abs() { i } else { best });
        swaps[k] = p;
        if p != k {
            for j in 0..n {
                a.swap(j * n + k, j * n + p);
            }
        }
        let pivot = a[k * n + k];
        if pivot == 0.0 {
            continue;
        }
        let inv = 1.0 / pivot;
        for v in &mut a[k * n + k + 1..(k + 1) * n] {
            *v *= inv;
        }
        let (left, right) = a.split_at_mut((k + 1) * n);
        let l = &left[k * n + k + 1..(k + 1) * n];
        for column in right.chunks_exact_mut(n) {
            let f = column[k];
            if f != 0.0 {
                for (x, &li) in column[k + 1..].iter_mut().zip(l) {
                    *x -= li * f;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A column-major dense matrix as compressed columns of all its entries.
    fn columns(n: usize) -> (Vec<usize>, Vec<usize>) {
        ((0..=n).map(|c| c * n).collect(), (0..n * n).map(|k| k % n).collect())
    }

    /// The kept order is used while its pivots pass the threshold and found again when one does
    /// not: `[[1, 2], [3, 4]]` is ordered with row 1 first (partial pivoting); with the
    /// entries moved to `[[1, 2], [0.05, 4]]` that order's pivot 0.05 is below 0.1 of the 1 under
    /// it, and the order is found again (row 0 first). Each solve is checked against the exact
    /// inverse, in both directions.
    #[test]
    fn kept_order_until_a_pivot_fails_the_threshold() {
        let n = 2;
        let solve_both = |lu: &DenseLu, a: [[f64; 2]; 2]| {
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            let b = [1.0, 2.0];
            let x_exact = [(a[1][1] * b[0] - a[0][1] * b[1]) / det, (a[0][0] * b[1] - a[1][0] * b[0]) / det];
            let y_exact = [(a[1][1] * b[0] - a[1][0] * b[1]) / det, (a[0][0] * b[1] - a[0][1] * b[0]) / det];
            let (mut x, mut y) = (b, b);
            lu.solve(&mut x);
            lu.solve_transpose(&mut y);
            for (u, v) in x.iter().zip(&x_exact).chain(y.iter().zip(&y_exact)) {
                assert!((u - v).abs() < 1e-14, "{x:?} {y:?} against {x_exact:?} {y_exact:?}");
            }
        };
        let mut lu = DenseLu::new(n);
        let (col_ptr, row_idx) = columns(n);
        let a = [[1.0, 2.0], [3.0, 4.0]];
        assert!(!lu.factor(&col_ptr, &row_idx, &[a[0][0], a[1][0], a[0][1], a[1][1]]));
        assert_eq!(lu.position, [1, 0]);
        solve_both(&lu, a);
        // Row 1 first still passes: 3.5 against 1.
        let a = [[1.0, 2.0], [3.5, 4.0]];
        assert!(lu.factor(&col_ptr, &row_idx, &[a[0][0], a[1][0], a[0][1], a[1][1]]));
        assert_eq!(lu.position, [1, 0]);
        solve_both(&lu, a);
        let a = [[1.0, 2.0], [0.05, 4.0]];
        assert!(!lu.refactor(&[a[0][0], a[1][0], a[0][1], a[1][1]]));
        assert!(!lu.factor(&col_ptr, &row_idx, &[a[0][0], a[1][0], a[0][1], a[1][1]]));
        assert_eq!(lu.position, [0, 1]);
        solve_both(&lu, a);
    }

    /// A chain's saddle-point matrix (order 29, the quick-return's Newton matrix shape) whose
    /// values drift over 400 factorizations of one pattern, by steps of 2% and with a jump of
    /// every value every 50: each solve, in both directions, leaves a residual within 10 times
    /// that of partial pivoting afresh (the threshold's bound on the growth; measured at most
    /// about 3 times, on the ill-conditioned draws), or below `1e-14`; the kept order serves most
    /// factorizations, and the jumps make it be found again.
    #[test]
    fn drifting_values_keep_the_order_and_solve() {
        let (nb, m) = (15, 14);
        let n = nb + m;
        let mut seed = 5u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut dense = vec![0.0; n * n];
        for i in 0..nb {
            dense[i * n + i] = 1.0 + random();
        }
        for i in nb..n {
            dense[i * n + i] = -1e-10;
        }
        for r in 0..m {
            let body = (r / 3).min(3);
            for c in 3 * body..3 * body + 6 {
                let v = random();
                dense[c * n + nb + r] = v;
                dense[(nb + r) * n + c] = v;
            }
        }
        // The pattern: the entries that are not zero now.
        let mut col_ptr = vec![0];
        let mut row_idx = vec![];
        for c in 0..n {
            row_idx.extend((0..n).filter(|&r| dense[c * n + r] != 0.0));
            col_ptr.push(row_idx.len());
        }
        let mut lu = DenseLu::new(n);
        let (mut kept, mut found) = (0, 0);
        for step in 0..400 {
            let jump = step % 50 == 49;
            for c in 0..nb {
                for r in nb..n {
                    if dense[c * n + r] == 0.0 {
                        continue;
                    }
                    let v = if jump { random() } else { dense[c * n + r] * (1.0 + 0.04 * random()) };
                    dense[c * n + r] = v;
                    dense[r * n + c] = v;
                }
            }
            let values: Vec<f64> = (0..n)
                .flat_map(|c| row_idx[col_ptr[c]..col_ptr[c + 1]].iter().map(move |&r| (c, r)))
                .map(|(c, r)| dense[c * n + r])
                .collect();
            if lu.factor(&col_ptr, &row_idx, &values) {
                kept += 1;
            } else {
                found += 1;
            }
            let b: Vec<f64> = (0..n).map(|_| random()).collect();
            let (mut x, mut y) = (b.clone(), b.clone());
            lu.solve(&mut x);
            lu.solve_transpose(&mut y);
            let residual = |x: &[f64], transpose: bool| {
                (0..n)
                    .map(|i| {
                        let ax: f64 =
                            (0..n).map(|j| if transpose { dense[i * n + j] } else { dense[j * n + i] } * x[j]).sum();
                        (ax - b[i]).abs()
                    })
                    .fold(0.0, f64::max)
            };
            let (r1, r2) = (residual(&x, false), residual(&y, true));
            // Partial pivoting afresh, the reference.
            let mut fresh = DenseLu::new(n);
            fresh.factor(&col_ptr, &row_idx, &values);
            let (mut x, mut y) = (b.clone(), b.clone());
            fresh.solve(&mut x);
            fresh.solve_transpose(&mut y);
            let (f1, f2) = (residual(&x, false), residual(&y, true));
            assert!(
                r1.max(r2) <= 10.0 * f1.max(f2).max(1e-14),
                "step {step}: residuals {r1:e} {r2:e} against {f1:e} {f2:e}"
            );
        }
        assert!(kept > 300 && found > 1, "kept {kept}, found again {found}");
    }
}
