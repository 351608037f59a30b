//! Dense linear algebra, knowing no mechanics: by the singular value decomposition
//! `A = U S V^T`, the null space, the minimum-norm least-squares solution, the rows that take
//! part in a linear dependence, and the rows of the smallest singular value; by Gram-Schmidt,
//! the independent rows in order.
//!
//! One threshold decides the numerical rank of the SVD everywhere: a singular value counts as
//! zero below [`RANK_TOLERANCE`] times the largest. Rows kept in order by Gram-Schmidt have their
//! own, [`INDEPENDENCE_TOLERANCE`], with the reason it is larger. How small the smallest singular value must be for a
//! position to count as singular is not a question of rank but of how close a solver can get
//! to such a position; the analyses that ask it set their own ratio and compare it with the one
//! [`smallest_singular`] returns.

use faer::{Mat, MatRef};

/// Relative size of a singular value (to the largest) below which it counts as zero: `1e-9`.
/// Far above rounding (the SVD gives singular values to `~1e-16` of the largest, so a matrix of
/// rank `r` shows its zero ones at `~1e-16 cond`), and far below the ratios of the well-posed
/// problems solved with it (the smallest measured at a regular position of a mechanism in the
/// tests is `2e-3`).
pub const RANK_TOLERANCE: f64 = 1e-9;

/// A component of a unit left singular vector of a zero singular value above which its row takes
/// part in the combination of rows that vanishes: `1e-8`. Those vectors are accurate to about
/// `eps` times the condition, so a row outside every dependence shows components at rounding
/// (`1e-16` amplified by a few orders of magnitude), eight orders below it; a row inside one
/// shares a unit vector with the few other rows of its dependence, far above it.
pub const DEPENDENCE_COMPONENT: f64 = 1e-8;

/// Share of the largest component of the smallest singular value's left singular vector from
/// which a row counts as taking part in it: a fifth. The rows whose combination nearly vanishes
/// carry comparable components, rows coupled to them only weakly (through a shared body) less,
/// and rows outside it rounding; a fifth keeps the first and leaves out the rest (the
/// slider-crank's lock-up names four of its nine rows, `O.y, A.y, B.y, guide.line`).
pub const SMALLEST_ROW_SHARE: f64 = 0.2;

/// Remainder of a row after its components along the rows before it are taken out, relative to
/// the largest row, below which [`independent_rows`] counts it as depending on them:
/// `sqrt(1e-9) = 3.2e-5`, above [`RANK_TOLERANCE`] because the rows are those of equations solved
/// only to a tolerance. Where rows become dependent at a turning point of the solutions, a point
/// that leaves a residual `tau` lies `~sqrt(tau)` from it, and its rows that far from dependent:
/// measured, a slider-crank assembled at its dead centre to `1e-12` leaves a remainder of
/// `3.2e-7`, which is dependence. Every other remainder in the tests was rounding (below `4e-16`)
/// or above `1e-2`.
pub const INDEPENDENCE_TOLERANCE: f64 = 3.1622776601683795e-5;

/// The numerical rank of singular values `s` in decreasing order: how many are above
/// [`RANK_TOLERANCE`] times the largest.
fn rank(s: faer::ColRef<'_, f64>) -> usize {
    let smax = (0..s.nrows()).map(|k| s[k]).fold(0.0f64, f64::max);
    (0..s.nrows()).filter(|&k| s[k] > RANK_TOLERANCE * smax).count()
}

/// The minimum-norm least-squares solution `x (cols)` of `a x = b`, `V S^+ U^T b` with the
/// singular values below [`RANK_TOLERANCE`] times the largest dropped. `None` when the SVD fails
/// (a non-finite entry).
pub fn min_norm_solve(a: MatRef<'_, f64>, b: &[f64]) -> Option<Vec<f64>> {
    let x = min_norm_solve_columns(a, MatRef::from_column_major_slice(b, b.len(), 1))?;
    Some(x.col(0).iter().copied().collect())
}

/// [`min_norm_solve`] for each column of `b (rows x k)`, with one SVD: `x (cols x k)`.
pub fn min_norm_solve_columns(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Option<Mat<f64>> {
    let (m, n) = (a.nrows(), a.ncols());
    let mut x = Mat::<f64>::zeros(n, b.ncols());
    if n == 0 || m == 0 {
        return Some(x);
    }
    let svd = a.thin_svd().ok()?;
    let (u, s, v) = (svd.U(), svd.S().column_vector(), svd.V());
    for col in 0..b.ncols() {
        for k in 0..rank(s) {
            let c: f64 = (0..m).map(|i| u[(i, k)] * b[(i, col)]).sum::<f64>() / s[k];
            for j in 0..n {
                x[(j, col)] += v[(j, k)] * c;
            }
        }
    }
    Some(x)
}

/// An orthonormal basis `(cols x f)` of the null space of `a`: the right singular vectors of the
/// singular values below [`RANK_TOLERANCE`] times the largest (every direction when `a` has no
/// rows; none when the SVD fails on a non-finite entry).
pub fn null_space(a: MatRef<'_, f64>) -> Mat<f64> {
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 {
        return Mat::identity(n, n);
    }
    let Ok(svd) = a.svd() else { return Mat::zeros(n, 0) };
    let r = rank(svd.S().column_vector());
    let v = svd.V();
    Mat::from_fn(n, n - r, |i, j| v[(i, r + j)])
}

/// The rows of `a` that take part in a linear dependence among its rows: those with a component
/// above [`DEPENDENCE_COMPONENT`] in the left null space (the combinations of rows that vanish,
/// one per dependent row). Every row when `a` has no columns; none when the rows are
/// independent or the SVD fails on a non-finite entry.
pub fn dependent_rows(a: MatRef<'_, f64>) -> Vec<usize> {
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 || n == 0 {
        return (0..m).collect();
    }
    let Ok(svd) = a.svd() else { return vec![] };
    let r = rank(svd.S().column_vector());
    let u = svd.U();
    (0..m).filter(|&i| (r..m).any(|k| u[(i, k)].abs() > DEPENDENCE_COMPONENT)).collect()
}

/// The ratio of the smallest singular value of `a` to the largest, and the rows of the smallest:
/// those whose component of its left singular vector is at least [`SMALLEST_ROW_SHARE`] of the
/// largest. A ratio of 1 and no rows when `a` is empty; 0 and no rows when the SVD fails on a
/// non-finite entry.
pub fn smallest_singular(a: MatRef<'_, f64>) -> (f64, Vec<usize>) {
    let m = a.nrows();
    if m == 0 || a.ncols() == 0 {
        return (1.0, vec![]);
    }
    let Ok(svd) = a.thin_svd() else { return (0.0, vec![]) };
    let s = svd.S().column_vector();
    // Singular values come in decreasing order.
    let k = s.nrows() - 1;
    let ratio = if s[0] > 0.0 { s[k] / s[0] } else { 0.0 };
    let u = svd.U();
    let umax = (0..m).map(|i| u[(i, k)].abs()).fold(0.0f64, f64::max);
    let rows = (0..m).filter(|&i| u[(i, k)].abs() >= SMALLEST_ROW_SHARE * umax).collect();
    (ratio, rows)
}

/// Greedy independent rows of `jac (m x n)` in order: modified Gram-Schmidt, twice for accuracy;
/// a row whose remainder is below [`INDEPENDENCE_TOLERANCE`] times the largest row norm depends
/// on the rows before it. Returns `(independent, dependent)` row indices.
pub fn independent_rows(jac: MatRef<'_, f64>) -> (Vec<usize>, Vec<usize>) {
    let (m, n) = (jac.nrows(), jac.ncols());
    let scale = (0..m).map(|i| (0..n).map(|j| jac[(i, j)].powi(2)).sum::<f64>().sqrt()).fold(0.0f64, f64::max);
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let (mut keep, mut drop) = (Vec::new(), Vec::new());
    for i in 0..m {
        let mut v: Vec<f64> = (0..n).map(|j| jac[(i, j)]).collect();
        let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for _ in 0..2 {
            for b in &basis {
                let d: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm <= INDEPENDENCE_TOLERANCE * norm0.max(scale) || norm == 0.0 {
            drop.push(i);
        } else {
            v.iter_mut().for_each(|x| *x /= norm);
            basis.push(v);
            keep.push(i);
        }
    }
    (keep, drop)
}

/// `R a C`: the columns of `a (m x n)` multiplied by `cols (n)`, then each row divided by its
/// 2-norm (a zero row stays zero). Rank and singular values of the result do not depend on the
/// units of the rows, nor, when `cols` holds the coordinates' scales, on those of the columns:
/// see [`crate::linalg::rows::Scaled`].
pub fn equilibrated(a: MatRef<'_, f64>, cols: &[f64]) -> Mat<f64> {
    let mut out = Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] * cols[j]);
    for i in 0..out.nrows() {
        let norm = (0..out.ncols()).map(|j| out[(i, j)].powi(2)).sum::<f64>().sqrt();
        if norm > 0.0 {
            (0..out.ncols()).for_each(|j| out[(i, j)] /= norm);
        }
    }
    out
}

/// Solve `a x = b` in place for a small symmetric positive definite `a` (order `n`, row-major,
/// its lower triangle overwritten by the Cholesky factor `L`, `b` by `x`). False, with `a` and
/// `b` partly overwritten, when a pivot is not positive (the matrix is not positive definite to
/// rounding). For the few unknowns of a reduced mass matrix, solved at every evaluation: a dense
/// library call allocates and dispatches for more work than the `n^3 / 6` flops of the
/// factorization.
pub fn cholesky_solve_small(a: &mut [f64], n: usize, b: &mut [f64]) -> bool {
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i * n + k] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k * n + i] * b[k];
        }
        b[i] = s / a[i * n + i];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Differences between two computations of the same quantity of size about 1 in double
    /// precision: a few hundred units of round-off, for the SVD's and the products' rounding on
    /// matrices of a few rows.
    const CLOSE: f64 = 1e-13;

    /// A `4 x 5` matrix of rank 2: rows 2 and 3 are combinations of rows 0 and 1
    /// (`r2 = r0 + 2 r1`, `r3 = 3 r0 - r1`).
    fn rank_two() -> Mat<f64> {
        let r0 = [1.0, 2.0, 0.0, -1.0, 3.0];
        let r1 = [0.0, 1.0, 4.0, 2.0, -2.0];
        Mat::from_fn(4, 5, |i, j| match i {
            0 => r0[j],
            1 => r1[j],
            2 => r0[j] + 2.0 * r1[j],
            _ => 3.0 * r0[j] - r1[j],
        })
    }

    /// `cholesky_solve_small` solves `G x = b` for a Gram matrix `G = A^T A + I` (symmetric
    /// positive definite) to a residual of rounding, and refuses an indefinite matrix.
    #[test]
    fn small_cholesky_solves_and_refuses_indefinite() {
        let a = rank_two();
        let n = 5;
        let g = Mat::from_fn(n, n, |i, j| (0..4).map(|k| a[(k, i)] * a[(k, j)]).sum::<f64>() + f64::from(i == j));
        let mut packed: Vec<f64> = (0..n * n).map(|e| g[(e / n, e % n)]).collect();
        let b = [1.0, -2.0, 0.5, 3.0, 0.25];
        let mut x = b;
        assert!(cholesky_solve_small(&mut packed, n, &mut x));
        for i in 0..n {
            let gx: f64 = (0..n).map(|j| g[(i, j)] * x[j]).sum();
            assert!((gx - b[i]).abs() < CLOSE * 100.0, "row {i}: {gx} against {}", b[i]);
        }
        let mut indefinite = [1.0, 2.0, 2.0, 1.0];
        assert!(!cholesky_solve_small(&mut indefinite, 2, &mut [1.0, 1.0]));
    }

    /// The null space of a rank-2 `4 x 5` matrix has dimension `5 - 2 = 3`; its vectors satisfy
    /// `A v = 0` and are orthonormal.
    #[test]
    fn null_space_has_the_dimension_of_the_rank_and_is_orthonormal() {
        let a = rank_two();
        let basis = null_space(a.as_ref());
        assert_eq!(basis.ncols(), 3);
        let av = &a * &basis;
        let gram = basis.transpose() * &basis;
        for j in 0..3 {
            assert!((0..4).all(|i| av[(i, j)].abs() < CLOSE), "A v = {av:?}");
            for k in 0..3 {
                let expected = if j == k { 1.0 } else { 0.0 };
                assert!((gram[(j, k)] - expected).abs() < CLOSE, "V^T V = {gram:?}");
            }
        }
        // No rows: every direction is free. Full column rank: none.
        assert_eq!(null_space(Mat::<f64>::zeros(0, 3).as_ref()).ncols(), 3);
        assert_eq!(null_space(Mat::<f64>::identity(3, 3).as_ref()).ncols(), 0);
    }

    /// A relative singular value just above the tolerance counts, one just below does not.
    #[test]
    fn the_rank_threshold_is_relative_to_the_largest_singular_value() {
        for (scale, size) in [(1.0, 1e3), (1e6, 1e-3)] {
            let a = |small: f64| Mat::from_fn(2, 2, |i, j| if i == j { scale * [size, size * small][i] } else { 0.0 });
            assert_eq!(null_space(a(10.0 * RANK_TOLERANCE).as_ref()).ncols(), 0);
            assert_eq!(null_space(a(0.1 * RANK_TOLERANCE).as_ref()).ncols(), 1);
        }
    }

    /// The minimum-norm solution of a consistent under-determined system solves it, is
    /// orthogonal to the null space, and equals the pseudo-inverse solution
    /// `A^T (A A^T)^-1 b` of a full-row-rank `A`.
    #[test]
    fn min_norm_solve_is_the_pseudo_inverse_solution() {
        let a = Mat::from_fn(2, 4, |i, j| [[1.0, 2.0, 0.0, -1.0], [0.0, 1.0, 4.0, 2.0]][i][j]);
        let b = [3.0, -1.0];
        let x = min_norm_solve(a.as_ref(), &b).unwrap();
        // A A^T = [[6, 0], [0, 21]], so A^T (A A^T)^-1 b = A^T [1/2, -1/21].
        let y = [0.5, -1.0 / 21.0];
        for (j, xj) in x.iter().enumerate() {
            let expected = a[(0, j)] * y[0] + a[(1, j)] * y[1];
            assert!((xj - expected).abs() < CLOSE, "{x:?}");
        }
        let basis = null_space(a.as_ref());
        for k in 0..basis.ncols() {
            let along: f64 = (0..4).map(|j| basis[(j, k)] * x[j]).sum();
            assert!(along.abs() < CLOSE, "component {along} along the null space");
        }
    }

    /// With dependent rows and an inconsistent right-hand side the solution is the least-squares
    /// one: `A^T (A x - b) = 0`; and it lies in the row space (orthogonal to the null space).
    #[test]
    fn min_norm_solve_is_least_squares_with_dependent_rows() {
        let a = rank_two();
        let b = [1.0, -2.0, 0.5, 4.0];
        let x = min_norm_solve(a.as_ref(), &b).unwrap();
        let residual: Vec<f64> = (0..4).map(|i| (0..5).map(|j| a[(i, j)] * x[j]).sum::<f64>() - b[i]).collect();
        for j in 0..5 {
            let normal: f64 = (0..4).map(|i| a[(i, j)] * residual[i]).sum();
            assert!(normal.abs() < 1e-12, "A^T r = {normal} in column {j}");
        }
        let basis = null_space(a.as_ref());
        for k in 0..basis.ncols() {
            let along: f64 = (0..5).map(|j| basis[(j, k)] * x[j]).sum();
            assert!(along.abs() < CLOSE, "component {along} along the null space");
        }
        assert_eq!(min_norm_solve(Mat::<f64>::zeros(0, 2).as_ref(), &[]), Some(vec![0.0, 0.0]));
        assert_eq!(min_norm_solve(Mat::from_fn(1, 1, |_, _| f64::NAN).as_ref(), &[1.0]), None);
    }

    /// The rank-2 matrix keeps its first two rows and drops the two combinations of them; a
    /// row whose remainder is ten times the tolerance is kept, one a tenth of it dropped.
    #[test]
    fn independent_rows_in_order() {
        assert_eq!(independent_rows(rank_two().as_ref()), (vec![0, 1], vec![2, 3]));
        for (remainder, kept) in [(10.0 * INDEPENDENCE_TOLERANCE, true), (0.1 * INDEPENDENCE_TOLERANCE, false)] {
            let a = Mat::from_fn(2, 2, |i, j| [[1.0, 0.0], [1.0, remainder]][i][j]);
            let expected = if kept { (vec![0, 1], vec![]) } else { (vec![0], vec![1]) };
            assert_eq!(independent_rows(a.as_ref()), expected, "remainder {remainder:e}");
        }
    }

    /// Rows 0 to 3 of the rank-2 matrix all take part in its dependences; a fifth row
    /// independent of them (a unit vector outside their span) does not.
    #[test]
    fn dependent_rows_are_the_rows_of_the_left_null_space() {
        let a = rank_two();
        assert_eq!(dependent_rows(a.as_ref()), [0, 1, 2, 3]);
        let basis = null_space(a.as_ref());
        let extra = Mat::from_fn(5, 5, |i, j| if i < 4 { a[(i, j)] } else { basis[(j, 0)] });
        assert_eq!(dependent_rows(extra.as_ref()), [0, 1, 2, 3]);
        assert!(dependent_rows(Mat::<f64>::identity(3, 3).as_ref()).is_empty());
        assert_eq!(dependent_rows(Mat::<f64>::zeros(2, 0).as_ref()), [0, 1]);
    }

    /// `diag(4, 2, 1e-3)` turned by an orthogonal matrix on each side has the ratio `2.5e-4`,
    /// and the rows of its smallest singular value are those where the third column of the left
    /// rotation is at least a fifth of its largest entry.
    #[test]
    fn smallest_singular_value_and_its_rows() {
        // Left rotation: its third column, (0.8, 0, 0.6) after the permutation, spans rows 0 and 2.
        let u = Mat::from_fn(3, 3, |i, j| [[0.6, 0.0, 0.8], [0.0, 1.0, 0.0], [-0.8, 0.0, 0.6]][i][j]);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let v = Mat::from_fn(3, 3, |i, j| [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]][i][j]);
        let d = Mat::from_fn(3, 3, |i, j| if i == j { [4.0, 2.0, 1e-3][i] } else { 0.0 });
        let a = &u * &d * v.transpose();
        let (ratio, rows) = smallest_singular(a.as_ref());
        assert!((ratio - 2.5e-4).abs() < CLOSE, "{ratio}");
        assert_eq!(rows, [0, 2]);
        assert_eq!(smallest_singular(Mat::<f64>::zeros(0, 3).as_ref()), (1.0, vec![]));
        assert_eq!(smallest_singular(Mat::<f64>::zeros(2, 2).as_ref()).0, 0.0);
    }
}
