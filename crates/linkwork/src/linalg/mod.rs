//! Linear algebra, knowing no mechanics: compressed-column patterns built from lists of
//! entries ([`Pattern`]), and LU for square systems of a fixed pattern ([`SparseLu`]): symbolic
//! factorization once per analysis (faer's COLAMD ordering and elimination structure), numeric
//! factorization per matrix, and a 1-norm condition estimate from the factors (Hager 1984,
//! Higham 1988) to detect singular positions; up to [`DENSE_LU_MAX_ORDER`] a dense elimination
//! of our own, where that is faster, which keeps its pivot order from one factorization of a
//! pattern to the next and eliminates over the structure of that order alone (`small.rs`).
//! [`dense`]: rank, null space, minimum-norm solutions and the smallest
//! singular value of small dense matrices by the SVD. [`rows`]: the same questions of the rows
//! of a sparse matrix of any size (the SVD when small, the Cholesky factorization of `A A^T`
//! when large). [`ColMatrix`]: an owned compressed-column matrix.

pub mod dense;
pub mod rows;
mod small;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::factor::PartialPivLuParams;
use faer::sparse::linalg::lu::{factorize_symbolic_lu, NumericLu, SymbolicLu};
use faer::sparse::linalg::LuError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Spec};

/// A compressed-column pattern (each column's rows ascending, each entry once), fixed for an
/// analysis, and the position in the value array of each entry it was built from.
#[derive(Debug, Clone)]
pub struct Pattern {
    /// (columns + 1) column pointers.
    pub col_ptr: Vec<usize>,
    /// (nnz) row index of each value.
    pub row_idx: Vec<usize>,
    /// (entries) value position of each entry given to [`Pattern::new`], in the order given;
    /// `usize::MAX` for an entry left out. Empty for a pattern given by its arrays.
    pub map: Vec<usize>,
    /// Number of rows.
    pub nrows: usize,
}

impl Pattern {
    /// The pattern of `entries` in `nrows` rows and `ncols` columns: each entry is `(row, column)`,
    /// in any order, or `None` for one left out; repeated entries share one value (a caller
    /// that fills the values adds them up).
    pub fn new(nrows: usize, ncols: usize, entries: impl IntoIterator<Item = Option<(usize, usize)>>) -> Pattern {
        // (column, row, entry) of every entry kept, sorted into compressed-column order.
        let mut kept: Vec<(usize, usize, usize)> = Vec::new();
        let mut count = 0;
        for (k, entry) in entries.into_iter().enumerate() {
            count = k + 1;
            if let Some((row, col)) = entry {
                kept.push((col, row, k));
            }
        }
        kept.sort_unstable();
        let mut col_ptr = vec![0; ncols + 1];
        let mut row_idx = Vec::with_capacity(kept.len());
        let mut map = vec![usize::MAX; count];
        let mut last = None;
        for &(col, row, k) in &kept {
            if last != Some((col, row)) {
                row_idx.push(row);
                col_ptr[col + 1] += 1;
                last = Some((col, row));
            }
            map[k] = row_idx.len() - 1;
        }
        for c in 0..ncols {
            col_ptr[c + 1] += col_ptr[c];
        }
        Pattern { col_ptr, row_idx, map, nrows }
    }
}

/// An owned matrix in compressed columns (each column's rows ascending, each entry once).
#[derive(Debug, Clone)]
pub struct ColMatrix {
    /// Number of rows.
    pub nrows: usize,
    /// (columns + 1) column pointers.
    pub col_ptr: Vec<usize>,
    /// (nnz) row index of each value.
    pub row_idx: Vec<usize>,
    /// (nnz) values.
    pub values: Vec<f64>,
}

impl ColMatrix {
    /// The matrix of `pattern` with `values`.
    pub fn new(pattern: &Pattern, values: Vec<f64>) -> ColMatrix {
        ColMatrix { nrows: pattern.nrows, col_ptr: pattern.col_ptr.clone(), row_idx: pattern.row_idx.clone(), values }
    }

    /// The matrix of `pattern` whose entries, in the order the pattern was built from, have
    /// `entry_values` (repeated entries added up).
    pub fn from_entries(pattern: &Pattern, entry_values: &[f64]) -> ColMatrix {
        let mut values = vec![0.0; pattern.row_idx.len()];
        for (&pos, v) in pattern.map.iter().zip(entry_values) {
            if pos != usize::MAX {
                values[pos] += v;
            }
        }
        ColMatrix::new(pattern, values)
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.col_ptr.len() - 1
    }

    /// The columns `cols` of this matrix, in that order.
    pub fn columns(&self, cols: &[usize]) -> ColMatrix {
        let mut out = ColMatrix { nrows: self.nrows, col_ptr: vec![0], row_idx: Vec::new(), values: Vec::new() };
        for &c in cols {
            let range = self.col_ptr[c]..self.col_ptr[c + 1];
            out.row_idx.extend_from_slice(&self.row_idx[range.clone()]);
            out.values.extend_from_slice(&self.values[range]);
            out.col_ptr.push(out.row_idx.len());
        }
        out
    }

    /// `A x`, `x: (columns)`.
    pub fn times(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.nrows];
        for (w, xc) in self.col_ptr.windows(2).zip(x) {
            for (&i, v) in self.row_idx[w[0]..w[1]].iter().zip(&self.values[w[0]..w[1]]) {
                y[i] += v * xc;
            }
        }
        y
    }

    /// `A^T y`, `y: (rows)`.
    pub fn transpose_times(&self, y: &[f64]) -> Vec<f64> {
        self.col_ptr
            .windows(2)
            .map(|w| self.row_idx[w[0]..w[1]].iter().zip(&self.values[w[0]..w[1]]).map(|(&i, v)| v * y[i]).sum())
            .collect()
    }

    /// A view for faer.
    pub fn as_ref(&self) -> SparseColMatRef<'_, usize, f64> {
        let sym = SymbolicSparseColMatRef::new_checked(self.nrows, self.ncols(), &self.col_ptr, None, &self.row_idx);
        SparseColMatRef::new(sym, &self.values)
    }
}

/// Why a factorization failed.
#[derive(Debug, Clone, PartialEq)]
pub enum FactorError {
    /// The pattern leaves column `column` without a possible pivot.
    StructurallySingular {
        /// The column (coordinate) with no pivot.
        column: usize,
    },
    /// faer could not allocate.
    OutOfMemory,
}

/// Largest order of a matrix [`SparseLu`] factors densely: 48. Below about order 70 faer's
/// sparse LU spends more on its bookkeeping (supernode and permutation structures, work-array
/// sizing) than a dense elimination spends on its zeros (`cargo run --release -p linkwork
/// --example lu_orders`; docs/performance.md has the timings); 48 leaves room for patterns
/// denser than a chain's. The kept pivot order (`small.rs`) would win at larger orders too, but
/// its first factorization is dense (`n^3 / 3`) and its buffers grow as `n^2` and `n^3 / 3`
/// (286 kB at 48), so the bound stays until the scale benchmarks say otherwise.
pub const DENSE_LU_MAX_ORDER: usize = 48;

/// The factors of a [`SparseLu`]: sparse (faer), or dense for small orders.
enum Factors {
    Sparse {
        symbolic: Box<SymbolicLu<usize>>,
        numeric: Box<NumericLu<usize, f64>>,
        stack: MemBuffer,
    },
    /// Dense storage, the pivot order kept from one factorization to the next (`small.rs`).
    Dense {
        lu: Box<small::DenseLu>,
        /// A column no pivot can reach whatever the values (the pattern's structural rank is
        /// short): every factorization fails there, as faer's sparse one does.
        unreachable: Option<usize>,
    },
}

/// A square sparse matrix with a fixed pattern, its LU factors and every work buffer.
pub struct SparseLu {
    pattern: Pattern,
    /// (nnz) current values.
    values: Vec<f64>,
    factors: Factors,
    factored: bool,
    /// (n) work vectors of the condition estimate.
    work: [Vec<f64>; 2],
}

impl std::fmt::Debug for SparseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu").field("n", &self.pattern.nrows).field("nnz", &self.values.len()).finish()
    }
}

impl SparseLu {
    /// Symbolic analysis of a square pattern (dense factors up to [`DENSE_LU_MAX_ORDER`]).
    pub fn new(pattern: Pattern) -> Result<SparseLu, FactorError> {
        let dense = pattern.nrows <= DENSE_LU_MAX_ORDER;
        SparseLu::with_factors(pattern, dense)
    }

    /// As [`SparseLu::new`], with dense or sparse factors as asked (for comparisons; `new`
    /// chooses by the order).
    pub fn with_factors(pattern: Pattern, dense: bool) -> Result<SparseLu, FactorError> {
        let n = pattern.nrows;
        let factors = if dense {
            Factors::Dense { lu: Box::new(small::DenseLu::new(n)), unreachable: unmatched_column(&pattern) }
        } else {
            let sym = SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
            let symbolic = factorize_symbolic_lu(sym, Default::default()).map_err(|_| FactorError::OutOfMemory)?;
            let req = StackReq::any_of(&[
                symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Spec::<PartialPivLuParams, f64>::default()),
                symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
            ]);
            Factors::Sparse {
                symbolic: Box::new(symbolic),
                numeric: Box::new(NumericLu::new()),
                stack: MemBuffer::new(req),
            }
        };
        let nnz = pattern.row_idx.len();
        Ok(SparseLu { pattern, values: vec![0.0; nnz], factors, factored: false, work: [vec![0.0; n], vec![0.0; n]] })
    }

    /// The pattern and the values to fill before [`SparseLu::factor`].
    pub fn pattern_and_values(&mut self) -> (&Pattern, &mut [f64]) {
        (&self.pattern, &mut self.values)
    }

    /// Numeric factorization of the current `values`.
    pub fn factor(&mut self) -> Result<(), FactorError> {
        let n = self.pattern.nrows;
        self.factored = false;
        match &mut self.factors {
            Factors::Sparse { symbolic, numeric, stack } => {
                let sym =
                    SymbolicSparseColMatRef::new_checked(n, n, &self.pattern.col_ptr, None, &self.pattern.row_idx);
                let a = SparseColMatRef::new(sym, &self.values);
                let stack = MemStack::new(stack);
                match symbolic.factorize_numeric_lu(numeric, a, Par::Seq, stack, Default::default()) {
                    Ok(_) => {}
                    Err(LuError::SymbolicSingular { index }) => {
                        return Err(FactorError::StructurallySingular { column: index })
                    }
                    Err(LuError::Generic(_)) => return Err(FactorError::OutOfMemory),
                }
            }
            Factors::Dense { lu, unreachable } => {
                if let Some(column) = *unreachable {
                    return Err(FactorError::StructurallySingular { column });
                }
                lu.factor(&self.pattern.col_ptr, &self.pattern.row_idx, &self.values);
            }
        }
        self.factored = true;
        Ok(())
    }

    /// Solve `A x = b` in place (`rhs: (n)`), with the last successful factorization.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        self.solve_with(rhs, false);
    }

    /// Solve `A^T x = b` in place (`rhs: (n)`), with the last successful factorization.
    pub fn solve_transpose(&mut self, rhs: &mut [f64]) {
        self.solve_with(rhs, true);
    }

    fn solve_with(&mut self, rhs: &mut [f64], transpose: bool) {
        debug_assert!(self.factored, "solve before a successful factorization");
        let n = rhs.len();
        match &mut self.factors {
            Factors::Sparse { symbolic, numeric, stack } => {
                let lu = faer::sparse::linalg::lu::LuRef::new_unchecked(symbolic, numeric);
                let rhs = MatMut::from_column_major_slice_mut(rhs, n, 1);
                let stack = MemStack::new(stack);
                if transpose {
                    lu.solve_transpose_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
                } else {
                    lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
                }
            }
            Factors::Dense { lu, .. } => {
                if transpose {
                    lu.solve_transpose(rhs)
                } else {
                    lu.solve(rhs)
                }
            }
        }
    }

    /// Estimate of the 1-norm condition number `||A||_1 ||A^-1||_1` from the factors, by Hager's
    /// method as refined by Higham (at most 5 pairs of solves; a lower bound, usually within a
    /// factor 3 of the true value). Infinite when a solve overflows.
    pub fn condition_estimate(&mut self) -> f64 {
        self.scaled_condition_estimate(None)
    }

    /// [`SparseLu::condition_estimate`] of `R A C`, `scales = (R, C)` the diagonals of the row and
    /// column scalings (`(n)` each): `||R A C||_1 ||C^-1 A^-1 R^-1||_1`, from the same factors.
    /// The condition of a matrix depends on the units of its rows and columns; scaled to be free
    /// of them ([`rows::Scaled`]), it is the mechanism's own.
    pub fn scaled_condition_estimate(&mut self, scales: Option<(&[f64], &[f64])>) -> f64 {
        let n = self.pattern.nrows;
        if n == 0 {
            return 1.0;
        }
        let row = |i: usize| scales.map_or(1.0, |(r, _)| r[i]);
        let col = |j: usize| scales.map_or(1.0, |(_, c)| c[j]);
        let mut norm_a = 0.0f64;
        for c in 0..n {
            let range = self.pattern.col_ptr[c]..self.pattern.col_ptr[c + 1];
            let s: f64 = self.pattern.row_idx[range.clone()]
                .iter()
                .zip(&self.values[range])
                .map(|(&i, v)| (row(i) * v).abs())
                .sum();
            norm_a = norm_a.max(col(c) * s);
        }
        let [mut x, mut z] = std::mem::take(&mut self.work);
        x.fill(1.0 / n as f64);
        let mut est = 0.0f64;
        let mut last = usize::MAX;
        for _ in 0..5 {
            // x <- C^-1 A^-1 R^-1 x.
            x.iter_mut().enumerate().for_each(|(i, v)| *v /= row(i));
            self.solve_with(&mut x, false);
            x.iter_mut().enumerate().for_each(|(j, v)| *v /= col(j));
            let y_norm: f64 = x.iter().map(|v| v.abs()).sum();
            if !y_norm.is_finite() {
                est = f64::INFINITY;
                break;
            }
            if y_norm <= est {
                break;
            }
            est = y_norm;
            for (zi, yi) in z.iter_mut().zip(&x) {
                *zi = if *yi >= 0.0 { 1.0 } else { -1.0 };
            }
            // z <- R^-1 A^-T C^-1 z.
            z.iter_mut().enumerate().for_each(|(j, v)| *v /= col(j));
            self.solve_with(&mut z, true);
            z.iter_mut().enumerate().for_each(|(i, v)| *v /= row(i));
            let (j, zmax) = z
                .iter()
                .enumerate()
                .fold((0, 0.0f64), |(bj, bz), (j, v)| if v.abs() > bz { (j, v.abs()) } else { (bj, bz) });
            if j == last {
                break;
            }
            last = j;
            x.fill(0.0);
            x[j] = 1.0;
            if !zmax.is_finite() {
                est = f64::INFINITY;
                break;
            }
        }
        self.work = [x, z];
        norm_a * est
    }
}

/// A column of a square pattern that no perfect matching of rows to columns covers (the
/// pattern's structural rank is short of its order), by augmenting paths (Kuhn 1955); `None`
/// when every column can have a pivot.
fn unmatched_column(pattern: &Pattern) -> Option<usize> {
    let n = pattern.nrows;
    let mut row_of = vec![usize::MAX; n];
    let mut col_of = vec![usize::MAX; n];
    let mut seen = vec![usize::MAX; n];
    for c in 0..n {
        // Depth-first search for an augmenting path from column c: (column, next entry).
        let mut path: Vec<(usize, usize)> = vec![(c, pattern.col_ptr[c])];
        let mut found = None;
        while let Some(&mut (col, ref mut next)) = path.last_mut() {
            if *next == pattern.col_ptr[col + 1] {
                path.pop();
                continue;
            }
            let r = pattern.row_idx[*next];
            *next += 1;
            if seen[r] == c {
                continue;
            }
            seen[r] = c;
            if col_of[r] == usize::MAX {
                found = Some(r);
                break;
            }
            path.push((col_of[r], pattern.col_ptr[col_of[r]]));
        }
        let Some(mut r) = found else { return Some(c) };
        while let Some((col, _)) = path.pop() {
            let previous = row_of[col];
            row_of[col] = r;
            col_of[r] = col;
            r = previous;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lu(col_ptr: Vec<usize>, row_idx: Vec<usize>, values: &[f64], dense: bool) -> SparseLu {
        let n = col_ptr.len() - 1;
        let mut lu = SparseLu::with_factors(Pattern { col_ptr, row_idx, map: vec![], nrows: n }, dense).unwrap();
        lu.pattern_and_values().1.copy_from_slice(values);
        lu
    }

    /// `A = [[4, 1, 0], [1, 3, 0], [0, 0, 2]]`: `A [1, 1, 1] = [5, 4, 2]`, `||A||_1 = 5` and
    /// `A^-1 = [[3, -1, 0], [-1, 4, 0], [0, 0, 5.5]] / 11`, so `||A^-1||_1 = 0.5` and the
    /// 1-norm condition number is exactly 2.5 (Hager's estimate is exact on this matrix).
    #[test]
    fn solves_and_estimates_the_condition() {
        for dense in [false, true] {
            let mut a = lu(vec![0, 2, 4, 5], vec![0, 1, 0, 1, 2], &[4.0, 1.0, 1.0, 3.0, 2.0], dense);
            a.factor().unwrap();
            let mut b = [5.0, 4.0, 2.0];
            a.solve(&mut b);
            assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-15), "dense {dense}: {b:?}");
            let k = a.condition_estimate();
            assert!((k - 2.5).abs() < 1e-12, "dense {dense}: condition {k}");
        }
    }

    /// A saddle-point matrix `[D, J^T; J, -1e-10 I]` of order 29 (a chain's Newton matrix: `J`
    /// couples neighbouring triples of columns) whose pivots need row interchanges: both
    /// factorizations solve `A x = b` and `A^T x = b` to a residual of `1e-13` (rounding times
    /// the matrix's size and condition, about `1e3`) and give the same condition estimate (the
    /// same sequence of solves on the same matrix, to rounding).
    #[test]
    fn dense_and_sparse_factors_agree() {
        let (n, m) = (15, 14);
        let mut seed = 7u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let mut entries: Vec<((usize, usize), f64)> =
            (0..n + m).map(|i| ((i, i), if i < n { 1e-3 * (1.0 + random()) } else { -1e-10 })).collect();
        for r in 0..m {
            let body = (r / 3).min(3);
            for c in 3 * body..3 * body + 6 {
                let v = random();
                entries.push(((n + r, c), v));
                entries.push(((c, n + r), v));
            }
        }
        let pattern = Pattern::new(n + m, n + m, entries.iter().map(|&(e, _)| Some(e)));
        let matrix = ColMatrix::from_entries(&pattern, &entries.iter().map(|&(_, v)| v).collect::<Vec<_>>());
        let b: Vec<f64> = (0..n + m).map(|_| random()).collect();
        let mut estimates = vec![];
        for dense in [false, true] {
            let mut a = SparseLu::with_factors(pattern.clone(), dense).unwrap();
            a.pattern_and_values().1.copy_from_slice(&matrix.values);
            a.factor().unwrap();
            let mut x = b.clone();
            a.solve(&mut x);
            let residual = matrix.times(&x).iter().zip(&b).map(|(ax, bi)| (ax - bi).abs()).fold(0.0, f64::max);
            assert!(residual < 1e-13, "dense {dense}: residual {residual:e}");
            let mut x = b.clone();
            a.solve_with(&mut x, true);
            let residual =
                matrix.transpose_times(&x).iter().zip(&b).map(|(ax, bi)| (ax - bi).abs()).fold(0.0, f64::max);
            assert!(residual < 1e-13, "dense {dense}: transposed residual {residual:e}");
            estimates.push(a.condition_estimate());
        }
        assert!((estimates[0] / estimates[1] - 1.0).abs() < 1e-9, "{estimates:?}");
    }

    /// Entries in any order, repeated or left out: each column's rows ascend, a repeat shares its
    /// first's value, and a left-out entry has none.
    #[test]
    fn pattern_from_entries() {
        let entries = [Some((2, 0)), Some((0, 1)), None, Some((0, 0)), Some((2, 0)), Some((1, 1))];
        let p = Pattern::new(3, 2, entries);
        assert_eq!(p.col_ptr, [0, 2, 4]);
        assert_eq!(p.row_idx, [0, 2, 0, 1]);
        assert_eq!(p.map, [1, 2, usize::MAX, 0, 1, 3]);
        assert_eq!(p.nrows, 3);
    }

    /// Random sparse matrices of order 12 whose pivots come from all over (a permuted diagonal of
    /// 1 under random entries in [-2, 2], a third of them nonzero), so that later row
    /// interchanges move entries of `L` columns already eliminated: the dense solves reach a
    /// residual of `1e-11` (rounding times a condition of up to `1e4` for such matrices) in
    /// both directions, as the sparse ones do.
    #[test]
    fn dense_factors_of_scattered_sparse_matrices_solve() {
        let n = 12;
        let mut seed = 11u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let shift = (random() * n as f64) as usize;
            let mut entries = vec![];
            for c in 0..n {
                for r in 0..n {
                    let v = if r == (c + shift) % n {
                        1.0
                    } else if random() < 0.33 {
                        4.0 * random() - 2.0
                    } else {
                        0.0
                    };
                    if v != 0.0 {
                        entries.push(((r, c), v));
                    }
                }
            }
            let pattern = Pattern::new(n, n, entries.iter().map(|&(e, _)| Some(e)));
            let matrix = ColMatrix::from_entries(&pattern, &entries.iter().map(|&(_, v)| v).collect::<Vec<_>>());
            let b: Vec<f64> = (0..n).map(|_| random() - 0.5).collect();
            for dense in [false, true] {
                let mut a = SparseLu::with_factors(pattern.clone(), dense).unwrap();
                a.pattern_and_values().1.copy_from_slice(&matrix.values);
                a.factor().unwrap();
                if a.condition_estimate() > 1e4 {
                    continue;
                }
                let (mut x, mut y) = (b.clone(), b.clone());
                a.solve(&mut x);
                a.solve_with(&mut y, true);
                let r1 = matrix.times(&x).iter().zip(&b).map(|(ax, bi)| (ax - bi).abs()).fold(0.0, f64::max);
                let r2 = matrix.transpose_times(&y).iter().zip(&b).map(|(ax, bi)| (ax - bi).abs()).fold(0.0, f64::max);
                assert!(r1.max(r2) < 1e-11, "dense {dense}: residuals {r1:e} {r2:e}");
            }
        }
    }

    /// A numerically singular matrix is flagged, whether faer refuses it or factors it, and a
    /// structurally singular one is refused naming a column no pivot can reach.
    #[test]
    fn singular_matrix_is_flagged() {
        for dense in [false, true] {
            let mut a = lu(vec![0, 2, 4], vec![0, 1, 0, 1], &[1.0, 2.0, 2.0, 4.0], dense);
            if a.factor().is_ok() {
                assert!(a.condition_estimate() > 1e15, "dense {dense}");
            }
            let mut b = lu(vec![0, 1, 1], vec![0], &[1.0], dense);
            assert_eq!(b.factor(), Err(FactorError::StructurallySingular { column: 1 }), "dense {dense}");
        }
        // Columns 0 and 1 reach only row 0, column 2 reaches every row: column 1 is left over.
        let p = Pattern { col_ptr: vec![0, 1, 2, 5], row_idx: vec![0, 0, 0, 1, 2], map: vec![], nrows: 3 };
        assert_eq!(unmatched_column(&p), Some(1));
        // A permutation needing an augmenting path: column 0 takes row 0 first, column 1 can
        // only have row 0, so column 0 moves to row 1.
        let p = Pattern { col_ptr: vec![0, 2, 3], row_idx: vec![0, 1, 0], map: vec![], nrows: 2 };
        assert_eq!(unmatched_column(&p), None);
    }
}
