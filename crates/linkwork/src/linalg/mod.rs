//! Linear algebra, knowing no mechanics: compressed-column patterns built from lists of
//! entries ([`Pattern`]), and sparse LU for square systems: symbolic factorization once per
//! analysis (faer's COLAMD ordering and elimination structure), numeric factorization per
//! matrix, and a 1-norm condition estimate from the factors (Hager 1984, Higham 1988) to detect
//! singular positions. [`dense`]: rank, null space, minimum-norm solutions and the smallest
//! singular value of small dense matrices by the SVD. [`rows`]: the same questions of the rows
//! of a sparse matrix of any size (the SVD when small, the Cholesky factorization of `A A^T`
//! when large). [`ColMatrix`]: an owned compressed-column matrix.

pub mod dense;
pub mod rows;

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

/// A square sparse matrix with a fixed pattern, its LU factors and every work buffer.
pub struct SparseLu {
    pattern: Pattern,
    /// (nnz) current values.
    values: Vec<f64>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factored: bool,
    stack: MemBuffer,
    /// (n) work vectors of the condition estimate.
    work: [Vec<f64>; 2],
}

impl std::fmt::Debug for SparseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu").field("n", &self.pattern.nrows).field("nnz", &self.values.len()).finish()
    }
}

impl SparseLu {
    /// Symbolic analysis of a square pattern.
    pub fn new(pattern: Pattern) -> Result<SparseLu, FactorError> {
        let n = pattern.nrows;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &pattern.col_ptr, None, &pattern.row_idx);
        let symbolic = factorize_symbolic_lu(sym, Default::default()).map_err(|_| FactorError::OutOfMemory)?;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Spec::<PartialPivLuParams, f64>::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let nnz = pattern.row_idx.len();
        Ok(SparseLu {
            pattern,
            values: vec![0.0; nnz],
            symbolic,
            numeric: NumericLu::new(),
            factored: false,
            stack: MemBuffer::new(req),
            work: [vec![0.0; n], vec![0.0; n]],
        })
    }

    /// The pattern and the values to fill before [`SparseLu::factor`].
    pub fn pattern_and_values(&mut self) -> (&Pattern, &mut [f64]) {
        (&self.pattern, &mut self.values)
    }

    /// Numeric factorization of the current `values`.
    pub fn factor(&mut self) -> Result<(), FactorError> {
        let n = self.pattern.nrows;
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.pattern.col_ptr, None, &self.pattern.row_idx);
        let a = SparseColMatRef::new(sym, &self.values);
        self.factored = false;
        let stack = MemStack::new(&mut self.stack);
        match self.symbolic.factorize_numeric_lu(&mut self.numeric, a, Par::Seq, stack, Default::default()) {
            Ok(_) => {
                self.factored = true;
                Ok(())
            }
            Err(LuError::SymbolicSingular { index }) => Err(FactorError::StructurallySingular { column: index }),
            Err(LuError::Generic(_)) => Err(FactorError::OutOfMemory),
        }
    }

    /// Solve `A x = b` in place (`rhs: (n)`), with the last successful factorization.
    pub fn solve(&mut self, rhs: &mut [f64]) {
        self.solve_with(rhs, false);
    }

    fn solve_with(&mut self, rhs: &mut [f64], transpose: bool) {
        debug_assert!(self.factored, "solve before a successful factorization");
        let n = rhs.len();
        let lu = faer::sparse::linalg::lu::LuRef::new_unchecked(&self.symbolic, &self.numeric);
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, 1);
        let stack = MemStack::new(&mut self.stack);
        if transpose {
            lu.solve_transpose_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
        } else {
            lu.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
        }
    }

    /// Estimate of the 1-norm condition number `||A||_1 ||A^-1||_1` from the factors, by Hager's
    /// method as refined by Higham (at most 5 pairs of solves; a lower bound, usually within a
    /// factor 3 of the true value). Infinite when a solve overflows.
    pub fn condition_estimate(&mut self) -> f64 {
        let n = self.pattern.nrows;
        if n == 0 {
            return 1.0;
        }
        let mut norm_a = 0.0f64;
        for c in 0..n {
            let s: f64 =
                self.values[self.pattern.col_ptr[c]..self.pattern.col_ptr[c + 1]].iter().map(|v| v.abs()).sum();
            norm_a = norm_a.max(s);
        }
        let [mut x, mut z] = std::mem::take(&mut self.work);
        x.fill(1.0 / n as f64);
        let mut est = 0.0f64;
        let mut last = usize::MAX;
        for _ in 0..5 {
            self.solve_with(&mut x, false);
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
            self.solve_with(&mut z, true);
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

#[cfg(test)]
mod tests {
    use super::*;

    fn lu(col_ptr: Vec<usize>, row_idx: Vec<usize>, values: &[f64]) -> SparseLu {
        let n = col_ptr.len() - 1;
        let mut lu = SparseLu::new(Pattern { col_ptr, row_idx, map: vec![], nrows: n }).unwrap();
        lu.pattern_and_values().1.copy_from_slice(values);
        lu
    }

    /// `A = [[4, 1, 0], [1, 3, 0], [0, 0, 2]]`: `A [1, 1, 1] = [5, 4, 2]`, `||A||_1 = 5` and
    /// `A^-1 = [[3, -1, 0], [-1, 4, 0], [0, 0, 5.5]] / 11`, so `||A^-1||_1 = 0.5` and the
    /// 1-norm condition number is exactly 2.5 (Hager's estimate is exact on this matrix).
    #[test]
    fn solves_and_estimates_the_condition() {
        let mut a = lu(vec![0, 2, 4, 5], vec![0, 1, 0, 1, 2], &[4.0, 1.0, 1.0, 3.0, 2.0]);
        a.factor().unwrap();
        let mut b = [5.0, 4.0, 2.0];
        a.solve(&mut b);
        assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-15), "{b:?}");
        let k = a.condition_estimate();
        assert!((k - 2.5).abs() < 1e-12, "condition {k}");
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

    /// A numerically singular matrix is flagged, whether faer refuses it or factors it.
    #[test]
    fn singular_matrix_is_flagged() {
        let mut a = lu(vec![0, 2, 4], vec![0, 1, 0, 1], &[1.0, 2.0, 2.0, 4.0]);
        if a.factor().is_ok() {
            assert!(a.condition_estimate() > 1e15);
        }
        let mut b = lu(vec![0, 1, 1], vec![0], &[1.0]);
        assert_eq!(b.factor(), Err(FactorError::StructurallySingular { column: 1 }));
    }
}
