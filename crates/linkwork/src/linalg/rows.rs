//! The row space of a sparse matrix `A (m x n)`, knowing no mechanics: which rows are
//! independent of the rows before them, which take part in a linear dependence, the
//! minimum-norm solutions of `A x = b` and of `A^T y = g`, and the smallest singular value with
//! its rows.
//!
//! Two ways, chosen by size ([`DENSE_MAX_ENTRIES`]):
//!
//! - a small matrix goes to the dense SVD and Gram-Schmidt of [`super::dense`];
//! - a large one to the Cholesky factorization `L L^T` of its Gram matrix `G = A A^T` in row
//!   order (faer's simplicial sparse Cholesky, no reordering). Its `k`-th pivot is the squared
//!   remainder of row `k` after its components along the rows before it are taken out, which
//!   is the Gram-Schmidt remainder of [`super::dense::independent_rows`]; a pivot at or below
//!   [`INDEPENDENCE_TOLERANCE`]`^2` times the largest squared row norm marks the row dependent,
//!   and faer's dynamic regularization replaces it by `1e40` times that, so that the
//!   row drops out of every later row's elimination and of every solve. The cost is that of a
//!   sparse factorization: linear in the rows for a chain of bodies, where the SVD is cubic.
//!
//! Squaring the matrix squares its condition, but the decision compares a pivot with
//! `1e-9` of the largest squared row norm, while the pivots' rounding is `~1e-16` of it: seven
//! orders of magnitude apart.

use super::dense::{self, DEPENDENCE_COMPONENT, INDEPENDENCE_TOLERANCE, SMALLEST_ROW_SHARE};
use super::{ColMatrix, FactorError, Pattern};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, MatRef, Par, Side};

/// Entries `m n` of a matrix up to which the dense SVD is used: `40,000` (a mechanism of about
/// 60 bodies). The Gram factorization is the faster from a few bodies on (`linkwork check` of the
/// N-four-bar, docs/performance.md, "Scale": 0.11 against 0.53 ms at N = 5, 0.9 against 26 ms at
/// N = 30), but it is not the SVD where rows conflict or nearly depend: its solution drops a
/// row whose remainder is below `3.2e-5`, where the SVD keeps singular values to `1e-9` and
/// gives the least-squares answer. Used for every size, it changes two diagnoses the tests hold
/// (a start at a dead centre, drivers that conflict at assembly). The SVD stays where its cost,
/// once per analysis, is small: up to 26 ms at this bound.
pub const DENSE_MAX_ENTRIES: usize = 40_000;

/// A dependent row's pivot is replaced by this many times the largest squared row norm: its
/// entries of `L` below the diagonal are then `1e-20` of what they would be, so the row takes
/// no part in the elimination of the rows after it nor in a solve, and a genuine pivot (at most
/// the largest squared row norm) can never be taken for it.
const DROPPED_PIVOT: f64 = 1e40;

/// Power and inverse iterations of [`RowSpace::smallest_singular`]: at most `200`, ending
/// earlier when the Rayleigh quotient changes by less than `1e-10` of itself. Used only to
/// explain a failure, where the ratio is compared with thresholds orders of magnitude apart.
const ITERATIONS: usize = 200;
const ITERATION_CHANGE: f64 = 1e-10;

/// The row space of `A`, by the dense SVD or by the Cholesky factorization of `A A^T`.
#[derive(Debug)]
pub enum RowSpace {
    /// A small matrix, dense.
    Dense(Mat<f64>),
    /// A large one, factored.
    Gram(Box<Gram>),
}

impl RowSpace {
    /// The row space of `a (m x n)`: dense when `m n <=` [`DENSE_MAX_ENTRIES`].
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Result<RowSpace, FactorError> {
        if a.nrows() * a.ncols() <= DENSE_MAX_ENTRIES {
            Ok(RowSpace::Dense(a.to_dense()))
        } else {
            Ok(RowSpace::Gram(Box::new(Gram::new(a)?)))
        }
    }

    /// The rows independent of the rows before them, and the others, in order
    /// ([`dense::independent_rows`]).
    pub fn independent_rows(&self) -> (Vec<usize>, Vec<usize>) {
        match self {
            RowSpace::Dense(a) => dense::independent_rows(a.as_ref()),
            RowSpace::Gram(g) => {
                let mut independent = vec![true; g.a.nrows];
                g.dependent.iter().for_each(|&k| independent[k] = false);
                ((0..independent.len()).filter(|&r| independent[r]).collect(), g.dependent.clone())
            }
        }
    }

    /// The rows that take part in a linear dependence among the rows ([`dense::dependent_rows`]).
    pub fn dependent_rows(&mut self) -> Vec<usize> {
        match self {
            RowSpace::Dense(a) => dense::dependent_rows(a.as_ref()),
            RowSpace::Gram(g) => {
                let mut rows: Vec<usize> = g
                    .dependences()
                    .iter()
                    .flat_map(|w| {
                        let norm = w.iter().map(|x| x * x).sum::<f64>().sqrt();
                        w.iter().enumerate().filter(move |(_, x)| x.abs() > DEPENDENCE_COMPONENT * norm).map(|(i, _)| i)
                    })
                    .collect();
                rows.sort_unstable();
                rows.dedup();
                rows
            }
        }
    }

    /// A minimum-norm solution `x (n)` of `A x = b`: by the SVD ([`dense::min_norm_solve`]),
    /// or `A^T G^-1 b` over the independent rows (the minimum-norm solution when the dependent
    /// rows agree with them, as those of a consistent system do). `None` when the dense SVD
    /// fails on a non-finite entry.
    pub fn min_norm_solve(&mut self, b: &[f64]) -> Option<Vec<f64>> {
        match self {
            RowSpace::Dense(a) => dense::min_norm_solve(a.as_ref(), b),
            RowSpace::Gram(g) => {
                let mut y = b.to_vec();
                g.solve(&mut y);
                Some(g.transpose_times(&y))
            }
        }
    }

    /// [`RowSpace::min_norm_transpose_solve`] for each column of `g (n x k)`: `y (m x k)`, the
    /// dense SVD computed once for all of them. `None` when it fails on a non-finite entry.
    pub fn min_norm_transpose_solve_columns(&mut self, g: MatRef<'_, f64>) -> Option<Mat<f64>> {
        match self {
            RowSpace::Dense(a) => dense::min_norm_solve_columns(a.transpose(), g),
            RowSpace::Gram(gram) => {
                let mut y = Mat::<f64>::zeros(gram.a.nrows, g.ncols());
                for col in 0..g.ncols() {
                    let column: Vec<f64> = g.col(col).iter().copied().collect();
                    let solved = self.min_norm_transpose_solve(&column)?;
                    y.col_mut(col).iter_mut().zip(solved).for_each(|(a, b)| *a = b);
                }
                Some(y)
            }
        }
    }

    /// The minimum-norm least-squares solution `y (m)` of `A^T y = g (n)`. By the Gram matrix:
    /// `G y0 = A g` over the independent rows (zero on the others) is a least-squares solution;
    /// the dependences among the rows span the rest, and taking `y0`'s component along them out
    /// leaves the one of least norm. `None` when the dense SVD fails on a non-finite entry.
    pub fn min_norm_transpose_solve(&mut self, g: &[f64]) -> Option<Vec<f64>> {
        match self {
            RowSpace::Dense(a) => dense::min_norm_solve(a.transpose(), g),
            RowSpace::Gram(gram) => {
                let mut y = gram.times(g);
                gram.solve(&mut y);
                let w = gram.dependences();
                if !w.is_empty() {
                    // y -= W (W^T W)^-1 W^T y.
                    let r = w.len();
                    let wtw = Mat::<f64>::from_fn(r, r, |i, j| dot(&w[i], &w[j]));
                    let wty = Mat::<f64>::from_fn(r, 1, |i, _| dot(&w[i], &y));
                    let c = wtw.partial_piv_lu().solve(&wty);
                    for (k, wk) in w.iter().enumerate() {
                        y.iter_mut().zip(wk).for_each(|(yi, wi)| *yi -= c[(k, 0)] * wi);
                    }
                }
                Some(y)
            }
        }
    }

    /// The ratio of the smallest singular value to the largest, and the rows of the smallest
    /// ([`dense::smallest_singular`]). By the Gram matrix: the largest by power iteration on
    /// `G`; the smallest, when a row is dependent, from the combination of rows that nearly
    /// vanishes (`|A^T w| / |w|`, an upper bound), and otherwise by inverse iteration with the
    /// factor.
    pub fn smallest_singular(&mut self) -> (f64, Vec<usize>) {
        match self {
            RowSpace::Dense(a) => dense::smallest_singular(a.as_ref()),
            RowSpace::Gram(g) => g.smallest_singular(),
        }
    }
}

/// The row space of `A (m x n)` scaled on both sides, `R A C`, for the questions whose answer
/// must not depend on units: `C` multiplies each column by the scale given for its coordinate
/// (so that columns of lengths and of angles compare), then `R` divides each row by its 2-norm
/// (so that rows of lengths and of angles compare). Every relative threshold of [`RowSpace`]
/// ([`dense::RANK_TOLERANCE`], [`INDEPENDENCE_TOLERANCE`], the singular ratios of the
/// analyses) then reads the same matrix whatever the unit of length: a mechanism scaled by `s`
/// has `A` scaled on the left and right by diagonal matrices, which `R` and `C` undo when the
/// column scales scale with it. Rows and their order are `A`'s, so the rows named are `A`'s.
#[derive(Debug)]
pub struct Scaled {
    space: RowSpace,
    /// (m) `R`'s diagonal.
    rows: Vec<f64>,
    /// (n) `C`'s diagonal.
    cols: Vec<f64>,
}

impl Scaled {
    /// The row space of `R a C`, `cols (n)` the diagonal of `C` ([`dense::equilibrated`] for
    /// a sparse matrix).
    pub fn new(a: &ColMatrix, cols: &[f64]) -> Result<Scaled, FactorError> {
        let mut rows = vec![0.0; a.nrows];
        row_scales(&a.col_ptr, &a.row_idx, &a.values, cols, &mut rows);
        let mut scaled = a.clone();
        for (c, w) in a.col_ptr.windows(2).enumerate() {
            for k in w[0]..w[1] {
                scaled.values[k] *= rows[a.row_idx[k]] * cols[c];
            }
        }
        Ok(Scaled { space: RowSpace::new(scaled.as_ref())?, rows, cols: cols.to_vec() })
    }

    /// [`RowSpace::independent_rows`] of `R A C`.
    pub fn independent_rows(&self) -> (Vec<usize>, Vec<usize>) {
        self.space.independent_rows()
    }

    /// [`RowSpace::dependent_rows`] of `R A C`.
    pub fn dependent_rows(&mut self) -> Vec<usize> {
        self.space.dependent_rows()
    }

    /// [`RowSpace::smallest_singular`] of `R A C`.
    pub fn smallest_singular(&mut self) -> (f64, Vec<usize>) {
        self.space.smallest_singular()
    }

    /// A solution `x (n)` of `A x = b`, of least norm in the scaled coordinates `C^-1 x`:
    /// `x = C y` with `y` the minimum-norm solution of `R A C y = R b`
    /// ([`RowSpace::min_norm_solve`]). `None` as there.
    pub fn min_norm_solve(&mut self, b: &[f64]) -> Option<Vec<f64>> {
        let rb: Vec<f64> = b.iter().zip(&self.rows).map(|(x, r)| x * r).collect();
        let y = self.space.min_norm_solve(&rb)?;
        Some(y.iter().zip(&self.cols).map(|(y, c)| y * c).collect())
    }
}

/// `R`'s diagonal for the compressed-column matrix `(col_ptr, row_idx, values)` whose columns are
/// multiplied by `cols`: one over the 2-norm of each scaled row, 1 for a zero row. `out: (rows)`.
pub fn row_scales(col_ptr: &[usize], row_idx: &[usize], values: &[f64], cols: &[f64], out: &mut [f64]) {
    out.fill(0.0);
    for (c, w) in col_ptr.windows(2).enumerate() {
        for k in w[0]..w[1] {
            out[row_idx[k]] += (values[k] * cols[c]).powi(2);
        }
    }
    out.iter_mut().for_each(|x| *x = if *x > 0.0 { 1.0 / x.sqrt() } else { 1.0 });
}

/// A large matrix `A` with the Cholesky factor of `A A^T` in row order, its dependent rows
/// dropped.
pub struct Gram {
    /// `A`.
    a: ColMatrix,
    symbolic: SymbolicCholesky<usize>,
    /// The values of `L`.
    l: Vec<f64>,
    /// The rows whose pivot was dropped, ascending.
    dependent: Vec<usize>,
    stack: MemBuffer,
}

impl std::fmt::Debug for Gram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gram").field("m", &self.a.nrows).field("dependent", &self.dependent).finish()
    }
}

impl Gram {
    /// Factor `A A^T`.
    pub fn new(a: SparseColMatRef<'_, usize, f64>) -> Result<Gram, FactorError> {
        let (m, n) = (a.nrows(), a.ncols());
        // The upper triangle of G = sum over columns c of a_c a_c^T.
        let mut entries = Vec::new();
        let mut products = Vec::new();
        for c in 0..n {
            let (rows, values) = (a.row_idx_of_col_raw(c), a.val_of_col(c));
            for (p, &i) in rows.iter().enumerate() {
                for (q, &j) in rows.iter().enumerate().skip(p) {
                    let (i, j) = if i <= j { (i, j) } else { (j, i) };
                    entries.push(Some((i, j)));
                    products.push(values[p] * values[q]);
                }
            }
        }
        // Every diagonal entry, so that a zero row has a pivot to drop.
        entries.extend((0..m).map(|i| Some((i, i))));
        products.extend(std::iter::repeat_n(0.0, m));
        let pattern = Pattern::new(m, m, entries);
        let mut values = vec![0.0; pattern.row_idx.len()];
        for (&pos, v) in pattern.map.iter().zip(&products) {
            values[pos] += v;
        }
        let largest = (0..m).map(|i| diagonal(&pattern, &values, i)).fold(0.0f64, f64::max);
        let sym = SymbolicSparseColMatRef::new_checked(m, m, &pattern.col_ptr, None, &pattern.row_idx);
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(sym, Side::Upper, SymmetricOrdering::Identity, params)
            .map_err(|_| FactorError::OutOfMemory)?;
        let mut l = vec![0.0; symbolic.len_val()];
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        let mut stack = MemBuffer::try_new(req).map_err(|_| FactorError::OutOfMemory)?;
        // A zero matrix has every row dependent: any positive scale drops them all.
        let scale = if largest > 0.0 { largest } else { 1.0 };
        let regularization = LltRegularization {
            dynamic_regularization_delta: DROPPED_PIVOT * scale,
            dynamic_regularization_epsilon: INDEPENDENCE_TOLERANCE * INDEPENDENCE_TOLERANCE * largest,
        };
        let g = SparseColMatRef::new(sym, &values);
        symbolic
            .factorize_numeric_llt(
                &mut l,
                g,
                Side::Upper,
                regularization,
                Par::Seq,
                MemStack::new(&mut stack),
                Default::default(),
            )
            .map_err(|_| FactorError::OutOfMemory)?;
        let SymbolicCholeskyRaw::Simplicial(simplicial) = symbolic.raw() else {
            unreachable!("the factorization was asked to be simplicial")
        };
        // The diagonal of L leads each of its columns; a dropped pivot's square is DROPPED_PIVOT
        // times the scale, far above any genuine one (at most the scale).
        let col_ptr = simplicial.col_ptr();
        let dependent = (0..m).filter(|&k| l[col_ptr[k]].powi(2) > 0.5 * DROPPED_PIVOT * scale).collect();
        // `a` is compact (no column holds unused entries), as every matrix of a Pattern is.
        let a = ColMatrix {
            nrows: m,
            col_ptr: a.symbolic().col_ptr().to_vec(),
            row_idx: a.row_idx().to_vec(),
            values: a.val().to_vec(),
        };
        Ok(Gram { a, symbolic, l, dependent, stack })
    }

    /// `G^-1 rhs` in place, with the dependent rows' entries set to zero.
    fn solve(&mut self, rhs: &mut [f64]) {
        let m = rhs.len();
        let llt = LltRef::new(&self.symbolic, &self.l);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, m, 1),
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
        for &k in &self.dependent {
            rhs[k] = 0.0;
        }
    }

    fn times(&self, x: &[f64]) -> Vec<f64> {
        self.a.times(x)
    }

    fn transpose_times(&self, y: &[f64]) -> Vec<f64> {
        self.a.transpose_times(y)
    }

    /// For each dependent row `k`, the combination `w (m)` of rows that vanishes: `w_k = 1` and
    /// `-c` on the independent rows, where `A_I^T c` is row `k` (`G c = A a_k`).
    fn dependences(&mut self) -> Vec<Vec<f64>> {
        let m = self.a.nrows;
        let dependent = self.dependent.clone();
        dependent
            .iter()
            .map(|&k| {
                let mut e = vec![0.0; m];
                e[k] = 1.0;
                let row = self.transpose_times(&e);
                let mut c = self.times(&row);
                self.solve(&mut c);
                let mut w: Vec<f64> = c.iter().map(|x| -x).collect();
                w[k] = 1.0;
                w
            })
            .collect()
    }

    /// [`RowSpace::smallest_singular`] of a large matrix.
    fn smallest_singular(&mut self) -> (f64, Vec<usize>) {
        let m = self.a.nrows;
        if m == 0 || self.a.ncols() == 0 {
            return (1.0, vec![]);
        }
        let gram = |s: &Gram, v: &[f64]| s.times(&s.transpose_times(v));
        // The largest eigenvalue of G by power iteration from the vector of ones.
        let mut v = vec![1.0 / (m as f64).sqrt(); m];
        let mut largest = 0.0;
        for _ in 0..ITERATIONS {
            let gv = gram(self, &v);
            let rayleigh = dot(&v, &gv);
            let norm = dot(&gv, &gv).sqrt();
            if norm == 0.0 || !norm.is_finite() {
                return (0.0, vec![]);
            }
            v = gv.iter().map(|x| x / norm).collect();
            let done = (rayleigh - largest).abs() <= ITERATION_CHANGE * rayleigh;
            largest = rayleigh;
            if done {
                break;
            }
        }
        let sigma_max = f64::sqrt(largest);
        let (sigma_min, u) = if self.dependent.is_empty() {
            // The smallest eigenvalue of G by inverse iteration with its factor.
            let mut u = vec![1.0 / (m as f64).sqrt(); m];
            let mut smallest = f64::INFINITY;
            for _ in 0..ITERATIONS {
                let mut x = u.clone();
                self.solve(&mut x);
                let norm = dot(&x, &x).sqrt();
                if norm == 0.0 || !norm.is_finite() {
                    break;
                }
                u = x.iter().map(|v| v / norm).collect();
                let rayleigh = dot(&u, &gram(self, &u));
                let done = (rayleigh - smallest).abs() <= ITERATION_CHANGE * rayleigh;
                smallest = rayleigh;
                if done {
                    break;
                }
            }
            (smallest.max(0.0).sqrt(), u)
        } else {
            // The dependence that nearly vanishes most: |A^T w| / |w|.
            self.dependences()
                .into_iter()
                .map(|w| {
                    let norm = dot(&w, &w).sqrt();
                    let aw = self.transpose_times(&w);
                    (dot(&aw, &aw).sqrt() / norm, w)
                })
                .fold((f64::INFINITY, vec![]), |best, next| if next.0 < best.0 { next } else { best })
        };
        let ratio = if sigma_max > 0.0 { sigma_min / sigma_max } else { 0.0 };
        let umax = u.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let rows = (0..u.len()).filter(|&i| u[i].abs() >= SMALLEST_ROW_SHARE * umax).collect();
        (ratio, rows)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The diagonal entry `i` of a compressed-column matrix whose columns hold their rows ascending.
fn diagonal(pattern: &Pattern, values: &[f64], i: usize) -> f64 {
    let range = pattern.col_ptr[i]..pattern.col_ptr[i + 1];
    pattern.row_idx[range.clone()].binary_search(&i).map(|k| values[range.start + k]).unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// A sparse `m x n` matrix whose rows are random combinations of a few columns each (as a
    /// joint's rows touch a few coordinates), with rows `dependent` replaced by combinations of
    /// two earlier rows; deterministic (a linear congruential generator).
    fn matrix(m: usize, n: usize, dependent: &[usize], seed: u64) -> SparseColMat<usize, f64> {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut rows: Vec<Vec<f64>> = Vec::new();
        for i in 0..m {
            let mut row = vec![0.0; n];
            if dependent.contains(&i) {
                let (a, b) = ((next() * i as f64) as usize, (next() * i as f64) as usize);
                let (ca, cb) = (next() - 0.5, next() + 0.5);
                for j in 0..n {
                    row[j] = ca * rows[a][j] + cb * rows[b][j];
                }
            } else {
                for _ in 0..4 {
                    row[(next() * n as f64) as usize] += 2.0 * next() - 1.0;
                }
                row[i % n] += 1.0;
            }
            rows.push(row);
        }
        let triplets: Vec<Triplet<usize, usize, f64>> = (0..m)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .filter(|&(i, j)| rows[i][j] != 0.0)
            .map(|(i, j)| Triplet::new(i, j, rows[i][j]))
            .collect();
        SparseColMat::try_new_from_triplets(m, n, &triplets).unwrap()
    }

    fn both(a: &SparseColMat<usize, f64>) -> (RowSpace, RowSpace) {
        (RowSpace::Dense(a.to_dense()), RowSpace::Gram(Box::new(Gram::new(a.as_ref()).unwrap())))
    }

    /// Agreement of two computations of a quantity of size about 1: the Gram matrix squares the
    /// condition (here up to ~1e4), so `1e-9` leaves a margin over `eps cond^2`.
    const AGREE: f64 = 1e-9;

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= AGREE * (1.0 + y.abs()))
    }

    /// The Gram factorization names the same independent, dependent and indeterminate rows as
    /// the dense Gram-Schmidt and SVD, and gives the same minimum-norm solutions, on matrices
    /// with and without dependent rows.
    #[test]
    fn the_gram_factorization_agrees_with_the_dense_svd() {
        for (m, n, dependent, seed) in
            [(12, 15, vec![], 1), (12, 15, vec![5, 9], 2), (30, 33, vec![7, 8, 20], 3), (20, 20, vec![19], 4)]
        {
            let a = matrix(m, n, &dependent, seed);
            let (mut dense, mut gram) = both(&a);
            assert_eq!(gram.independent_rows(), dense.independent_rows(), "seed {seed}");
            assert_eq!(gram.independent_rows().1, dependent, "seed {seed}");
            assert_eq!(gram.dependent_rows(), dense.dependent_rows(), "seed {seed}");
            // A consistent right-hand side: b = A x for some x.
            let x: Vec<f64> = (0..n).map(|j| (j as f64 * 0.37).sin()).collect();
            let full = a.to_dense();
            let b: Vec<f64> = (0..m).map(|i| (0..n).map(|j| full[(i, j)] * x[j]).sum()).collect();
            let (xd, xg) = (dense.min_norm_solve(&b).unwrap(), gram.min_norm_solve(&b).unwrap());
            assert!(close(&xg, &xd), "seed {seed}: {xg:?} against {xd:?}");
            // A^T y = g, in the range of A^T and not.
            let gs = [
                (0..n).map(|j| (0..m).map(|i| full[(i, j)] * (i as f64)).sum()).collect::<Vec<f64>>(),
                (0..n).map(|j| (j as f64).cos()).collect(),
            ];
            for g in &gs {
                let (yd, yg) = (dense.min_norm_transpose_solve(g).unwrap(), gram.min_norm_transpose_solve(g).unwrap());
                assert!(close(&yg, &yd), "seed {seed}: {yg:?} against {yd:?}");
            }
            // Both columns at once, each as alone (the dense SVD shared; the same arithmetic).
            let both_g = Mat::<f64>::from_fn(n, 2, |j, c| gs[c][j]);
            for space in [&mut dense, &mut gram] {
                let y = space.min_norm_transpose_solve_columns(both_g.as_ref()).unwrap();
                for (c, g) in gs.iter().enumerate() {
                    let alone = space.min_norm_transpose_solve(g).unwrap();
                    let column: Vec<f64> = y.col(c).iter().copied().collect();
                    assert_eq!(column, alone, "seed {seed}, column {c}");
                }
            }
            let ((rd, rowsd), (rg, rowsg)) = (dense.smallest_singular(), gram.smallest_singular());
            if dependent.is_empty() {
                assert!((rg - rd).abs() <= 1e-6 * rd, "seed {seed}: ratio {rg} against {rd}");
                assert_eq!(rowsg, rowsd, "seed {seed}");
            } else {
                // Both at rounding: the SVD's ~1e-16, the dependence's remainder ~1e-16 too.
                assert!(rg < 1e-12 && rd < 1e-12, "seed {seed}: {rg} {rd}");
            }
        }
    }

    /// A zero row is dependent (it is the empty combination), and a matrix without columns has
    /// every row dependent, as the dense functions say.
    #[test]
    fn zero_rows_are_dependent() {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(
            3,
            2,
            &[Triplet::new(0, 0, 1.0), Triplet::new(2, 1, 2.0)],
        )
        .unwrap();
        let (dense, gram) = both(&a);
        assert_eq!(gram.independent_rows(), (vec![0, 2], vec![1]));
        assert_eq!(gram.independent_rows(), dense.independent_rows());
        let empty = SparseColMat::<usize, f64>::try_new_from_triplets(2, 0, &[]).unwrap();
        let mut gram = RowSpace::Gram(Box::new(Gram::new(empty.as_ref()).unwrap()));
        assert_eq!(gram.independent_rows(), (vec![], vec![0, 1]));
        assert_eq!(gram.dependent_rows(), [0, 1]);
    }
}
