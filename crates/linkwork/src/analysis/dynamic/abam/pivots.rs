//! The partition's choice of pivots: a Gaussian elimination of the constraint Jacobian `Phi_q`
//! with threshold pivoting and Markowitz's count ([`PivotWork::run`]), whose pivot rows are the
//! independent rows and whose pivot columns are the dependent coordinates of a partition.

use crate::linalg::dense::RANK_TOLERANCE;

/// A pivot may be at most this many times smaller than the largest entry of its row: the
/// threshold of the partition's elimination (partial pivoting by rows is 1). Among the entries
/// above it the sparsest pivot (Markowitz's count) is taken, so that the elimination keeps
/// `Phi_q`'s sparsity.
const PIVOT_THRESHOLD: f64 = 0.9;

/// Rows searched for the pivot at each elimination step: those with the fewest entries.
const PIVOT_ROWS: usize = 4;

/// Up to this many rows the partition's elimination runs on a dense copy of `Phi_q`
/// ([`PivotWork::run_dense`]), above it on sparse rows ([`PivotWork::run_sparse`]); both choose
/// the same pivots. The dense scans cost `m n` a step, `m^2 n` in all; the sparse path's heaps
/// and merges cost more per entry but grow with the entries alone. Measured on the N-four-bar's
/// `Phi_q` (one choice, dense against sparse): 4.3 against 6.5 us at 14 rows (the quick-return's
/// size), 7.8 against 10.3 at 20, 12.5 against 14.6 at 26; 18.2 against 16.6 at 32, 28.5
/// against 24.2 at 50. The crossover is between 26 and 32. Those matrices have one column more
/// than rows; the dense path's scans grow with the columns and the sparse path's work does not,
/// so a matrix of more than `28 x 29` entries (few constraints on many coordinates) goes sparse.
const DENSE_PIVOT_MAX_ROWS: usize = 28;

/// The partition's elimination ([`PivotWork::run`]) and its buffers, kept from one partition
/// to the next so that a choice allocates nothing once they have grown (allocation was a third
/// of the choice's cost on the quick-return).
#[derive(Debug, Default)]
pub(super) struct PivotWork {
    /// Rows as sorted (column, value) lists, columns as the rows they hold entries in.
    rows: Vec<Vec<(usize, f64)>>,
    col_rows: Vec<Vec<usize>>,
    col_count: Vec<usize>,
    version: Vec<usize>,
    active: Vec<bool>,
    heap: std::collections::BinaryHeap<std::cmp::Reverse<(usize, usize, usize)>>,
    large: std::collections::BinaryHeap<(u64, usize, usize)>,
    skipped: Vec<std::cmp::Reverse<(usize, usize, usize)>>,
    top: Vec<std::cmp::Reverse<(usize, usize, usize)>>,
    merged: Vec<(usize, f64)>,
    /// The dense path's matrix (row-major, `m x n`), which of its entries are structural, each
    /// row's entry count and largest entry.
    dense: Vec<f64>,
    structural: Vec<bool>,
    row_len: Vec<usize>,
    row_big: Vec<f64>,
    /// The result: pivot rows and columns, ascending.
    pub(super) prow: Vec<usize>,
    pub(super) pcol: Vec<usize>,
}

impl PivotWork {
    /// The partition from the sparse `Phi_q` (`m x n`, entries `(row, column)` with values `jac`):
    /// Gaussian elimination with threshold pivoting, a structural choice with a numerical test as
    /// sparse LU codes make it (Duff, Erisman and Reid, "Direct Methods for Sparse Matrices",
    /// chapter 7). At each step the [`PIVOT_ROWS`] rows with the fewest entries are searched; the
    /// pivot is, among their entries of at least [`PIVOT_THRESHOLD`] times their row's largest, the
    /// one of least Markowitz count `(row entries - 1)(column entries - 1)`, ties to the larger
    /// relative to its row. A row whose entries have all fallen below [`RANK_TOLERANCE`] times the
    /// largest entry of `Phi_q` is numerically zero: redundant, it is left out. The pivots are the
    /// numerical rank. The pivot rows and columns, ascending, go to `prow` and `pcol`. Dense up
    /// to [`DENSE_PIVOT_MAX_ROWS`] rows (and `28 x 29` entries), sparse above (whose work grows
    /// with the fill, linearly in the length of a chain of bodies).
    pub(super) fn run(&mut self, m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) {
        if m <= DENSE_PIVOT_MAX_ROWS && m * n <= DENSE_PIVOT_MAX_ROWS * (DENSE_PIVOT_MAX_ROWS + 1) {
            self.run_dense(m, n, entries, jac);
        } else {
            self.run_sparse(m, n, entries, jac);
        }
    }

    /// [`PivotWork::run`]'s choice on a dense copy of `Phi_q` that keeps which entries are
    /// structural (an entry made by fill stays one when it cancels, as in the sparse rows), with
    /// the same arithmetic and the same ties, so the same pivots: each step scans the active rows
    /// for the largest entry and the candidate rows, where the sparse path keeps heaps.
    fn run_dense(&mut self, m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) {
        let PivotWork { dense, structural, row_len, row_big, col_count, active, merged, prow, pcol, .. } = self;
        dense.clear();
        dense.resize(m * n, 0.0);
        structural.clear();
        structural.resize(m * n, false);
        row_len.clear();
        row_len.resize(m, 0);
        col_count.clear();
        col_count.resize(n, 0);
        for (&(r, c), &v) in entries.iter().zip(jac) {
            dense[r * n + c] += v;
            if !structural[r * n + c] {
                structural[r * n + c] = true;
                row_len[r] += 1;
                col_count[c] += 1;
            }
        }
        let big_of =
            |a: &[f64], s: &[bool]| a.iter().zip(s).fold(0.0f64, |x, (v, &e)| if e { x.max(v.abs()) } else { x });
        row_big.clear();
        row_big.extend(dense.chunks_exact(n.max(1)).zip(structural.chunks_exact(n.max(1))).map(|(a, s)| big_of(a, s)));
        row_big.resize(m, 0.0);
        let zero = RANK_TOLERANCE * row_big.iter().fold(0.0f64, |a, &x| a.max(x));
        active.clear();
        active.resize(m, true);
        prow.clear();
        pcol.clear();
        loop {
            let largest = (0..m).filter(|&r| active[r]).fold(0.0f64, |a, r| a.max(row_big[r]));
            if largest <= zero || largest.is_nan() {
                break;
            }
            // The PIVOT_ROWS active rows of fewest entries (ties to the lower row) whose largest
            // entry passes the threshold, by the test each entry then meets (so that each of them
            // holds an entry that passes it).
            let mut top = [(usize::MAX, usize::MAX); PIVOT_ROWS];
            for r in (0..m).filter(|&r| active[r] && row_big[r] / largest >= PIVOT_THRESHOLD) {
                let key = (row_len[r], r);
                if key < top[PIVOT_ROWS - 1] {
                    let at = top.iter().position(|&t| key < t).unwrap_or(PIVOT_ROWS - 1);
                    top.copy_within(at..PIVOT_ROWS - 1, at + 1);
                    top[at] = key;
                }
            }
            let mut best: Option<(usize, usize, usize, f64)> = None;
            for &(len, r) in top.iter().take_while(|t| t.1 != usize::MAX) {
                for c in (0..n).filter(|&c| structural[r * n + c]) {
                    let rel = dense[r * n + c].abs() / largest;
                    if rel < PIVOT_THRESHOLD {
                        continue;
                    }
                    let cost = (len - 1) * (col_count[c] - 1);
                    if best.is_none_or(|(_, _, bc, brel)| cost < bc || (cost == bc && rel > brel)) {
                        best = Some((r, c, cost, rel));
                    }
                }
            }
            let (pr, pc, _, _) = best.expect("the largest entry's row passes the threshold");
            active[pr] = false;
            prow.push(pr);
            pcol.push(pc);
            // The pivot row's entries, then each active row holding column pc less its multiple.
            merged.clear();
            let at = pr * n..(pr + 1) * n;
            merged
                .extend((0..n).zip(&dense[at.clone()]).zip(&structural[at]).filter(|e| *e.1).map(|(e, _)| (e.0, *e.1)));
            for &(c, _) in merged.iter() {
                col_count[c] -= 1;
            }
            let pv = dense[pr * n + pc];
            for r in 0..m {
                if !active[r] || !structural[r * n + pc] {
                    continue;
                }
                let (values, flags) = (&mut dense[r * n..(r + 1) * n], &mut structural[r * n..(r + 1) * n]);
                let l = values[pc] / pv;
                for &(c, b) in merged.iter() {
                    if flags[c] {
                        values[c] -= l * b;
                    } else {
                        (values[c], flags[c]) = (-l * b, true);
                        row_len[r] += 1;
                        col_count[c] += 1;
                    }
                }
                (values[pc], flags[pc]) = (0.0, false);
                row_len[r] -= 1;
                col_count[pc] -= 1;
                row_big[r] = big_of(values, flags);
            }
        }
        prow.sort_unstable();
        pcol.sort_unstable();
    }

    /// [`PivotWork::run`] on sparse rows, with heaps of the rows by entry count and by largest
    /// entry: work linear in the entries of a chain. Returns the work (entries merged).
    fn run_sparse(&mut self, m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) -> usize {
        use std::cmp::Reverse;
        let PivotWork {
            rows, col_rows, col_count, version, active, heap, large, skipped, top, merged, prow, pcol, ..
        } = self;
        rows.resize_with(m, Vec::new);
        rows.iter_mut().for_each(Vec::clear);
        for (&(r, c), &v) in entries.iter().zip(jac) {
            rows[r].push((c, v));
        }
        col_rows.resize_with(n, Vec::new);
        col_rows.iter_mut().for_each(Vec::clear);
        for (r, row) in rows.iter_mut().enumerate() {
            row.sort_unstable_by_key(|e| e.0);
            row.dedup_by(|b, a| {
                let same = a.0 == b.0;
                if same {
                    a.1 += b.1;
                }
                same
            });
            for &(c, _) in row.iter() {
                col_rows[c].push(r);
            }
        }
        col_count.clear();
        col_count.extend(col_rows.iter().map(|r| r.len()));
        let row_max = |row: &[(usize, f64)]| row.iter().fold(0.0f64, |a, e| a.max(e.1.abs()));
        let big = rows.iter().fold(0.0f64, |a, row| a.max(row_max(row)));
        let zero = RANK_TOLERANCE * big;
        // Min-heap of (entries, row, version); stale versions are skipped.
        version.clear();
        version.resize(m, 0);
        heap.clear();
        heap.extend(rows.iter().enumerate().map(|(r, row)| Reverse((row.len(), r, 0))));
        // Max-heap of (largest |entry| as ordered bits, row, version): the largest remaining entry.
        large.clear();
        large.extend(rows.iter().enumerate().map(|(r, row)| (row_max(row).to_bits(), r, 0)));
        active.clear();
        active.resize(m, true);
        prow.clear();
        pcol.clear();
        let mut work = 0usize;
        loop {
            // The largest remaining entry; none above the rank tolerance: the rank is reached.
            let largest = loop {
                match large.peek() {
                    Some(&(_, r, v)) if !active[r] || version[r] != v => {
                        large.pop();
                    }
                    Some(&(bits, _, _)) => break f64::from_bits(bits),
                    None => break 0.0,
                }
            };
            if largest <= zero || largest.is_nan() {
                break;
            }
            // The sparsest rows holding an entry above the threshold (fresh heap entries only), by
            // the test each entry then meets.
            top.clear();
            skipped.clear();
            while top.len() < PIVOT_ROWS {
                let Some(e) = heap.pop() else { break };
                let r = e.0 .1;
                if !active[r] || version[r] != e.0 .2 {
                    continue;
                }
                if row_max(&rows[r]) / largest >= PIVOT_THRESHOLD {
                    top.push(e);
                } else {
                    skipped.push(e);
                }
            }
            heap.extend(skipped.iter().copied());
            let mut best: Option<(usize, usize, usize, f64, f64)> = None;
            for &Reverse((_, r, _)) in top.iter() {
                for &(c, v) in &rows[r] {
                    let rel = v.abs() / largest;
                    if rel < PIVOT_THRESHOLD {
                        continue;
                    }
                    let cost = (rows[r].len() - 1) * (col_count[c] - 1);
                    let better = match best {
                        None => true,
                        Some((_, _, bc, _, brel)) => cost < bc || (cost == bc && rel > brel),
                    };
                    if better {
                        best = Some((r, c, cost, v, rel));
                    }
                }
            }
            // The other rows go back on the heap unchanged.
            let (pr, pc, _, pv, _) = best.expect("the largest entry's row passes the threshold");
            for &e in top.iter() {
                if e.0 .1 != pr {
                    heap.push(e);
                }
            }
            active[pr] = false;
            for &(c, _) in &rows[pr] {
                col_count[c] -= 1;
            }
            prow.push(pr);
            pcol.push(pc);
            // Eliminate column pc from the other active rows that hold it.
            let pivot_row = std::mem::take(&mut rows[pr]);
            for k in 0..col_rows[pc].len() {
                let r = col_rows[pc][k];
                if !active[r] {
                    continue;
                }
                let Ok(at) = rows[r].binary_search_by_key(&pc, |e| e.0) else { continue };
                let l = rows[r][at].1 / pv;
                merged.clear();
                let (a, b) = (&rows[r], &pivot_row);
                let (mut i, mut j) = (0, 0);
                while i < a.len() || j < b.len() {
                    let ca = a.get(i).map_or(usize::MAX, |e| e.0);
                    let cb = b.get(j).map_or(usize::MAX, |e| e.0);
                    if ca < cb {
                        merged.push(a[i]);
                        i += 1;
                    } else if cb < ca {
                        // Fill: a new entry of row r in column cb.
                        merged.push((cb, -l * b[j].1));
                        col_rows[cb].push(r);
                        col_count[cb] += 1;
                        j += 1;
                    } else {
                        merged.push((ca, a[i].1 - l * b[j].1));
                        i += 1;
                        j += 1;
                    }
                }
                work += merged.len();
                merged.retain(|e| e.0 != pc);
                col_count[pc] -= 1;
                // Copied, not swapped: each row keeps its own buffer, which stops growing after
                // the first choices (a swap hands buffers round, and a short one grows again).
                rows[r].clear();
                rows[r].extend_from_slice(merged);
                version[r] += 1;
                heap.push(Reverse((rows[r].len(), r, version[r])));
                large.push((row_max(&rows[r]).to_bits(), r, version[r]));
            }
            rows[pr] = pivot_row;
        }
        prow.sort_unstable();
        pcol.sort_unstable();
        work
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`PivotWork::run_sparse`] with fresh buffers: the pivot rows and columns and the work.
    fn pivots(m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) -> (Vec<usize>, Vec<usize>, usize) {
        let mut w = PivotWork::default();
        let work = w.run_sparse(m, n, entries, jac);
        (w.prow, w.pcol, work)
    }

    /// `pivots` of a dense matrix given by rows.
    fn dense_pivots(rows: &[&[f64]], n: usize) -> (Vec<usize>, Vec<usize>) {
        let mut entries = vec![];
        let mut values = vec![];
        for (r, row) in rows.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    entries.push((r, c));
                    values.push(v);
                }
            }
        }
        let (m, (rows, cols, _)) = (rows.len(), pivots(rows.len(), n, &entries, &values));
        let mut dense = PivotWork::default();
        dense.run_dense(m, n, &entries, &values);
        assert_eq!((&dense.prow, &dense.pcol), (&rows, &cols), "the dense path chooses as the sparse one");
        (rows, cols)
    }

    /// The pivots skip a redundant row (row 1 = row 0 + row 2 / 2: two of the three rows) and a
    /// column that no constraint touches, and take the large entries: columns 1 (entry 5, not
    /// the 1 beside it) and 2.
    #[test]
    fn pivots_skip_redundant_rows() {
        let (rows, cols) = dense_pivots(&[&[1.0, 5.0, 0.0, 0.0], &[1.0, 5.0, 2.0, 0.0], &[0.0, 0.0, 4.0, 0.0]], 4);
        assert_eq!(cols, vec![1, 2]);
        assert!(rows.len() == 2 && rows.contains(&2), "{rows:?}");
        assert_eq!(dense_pivots(&[&[0.0, 0.0, 4.0]], 3), (vec![0], vec![2]));
        assert_eq!(dense_pivots(&[], 3), (vec![], vec![]));
        // Numerically dependent rows are left out: row 1 is row 0 times 2 up to 1e-12, below
        // RANK_TOLERANCE times the largest entry; the larger row's larger entry is the pivot.
        assert_eq!(dense_pivots(&[&[1.0, 3.0], &[2.0, 6.0 + 1e-12]], 2), (vec![1], vec![1]));
    }

    /// [`PivotWork::run`]'s choice, written densely and by brute force: at each step, of the
    /// active rows whose largest entry is at least [`PIVOT_THRESHOLD`] of the largest remaining,
    /// the [`PIVOT_ROWS`] with the fewest entries (ties to the lower row); among their entries
    /// of at least that fraction of the largest, the least Markowitz count, ties to the larger.
    /// Entries are structural (an entry made by fill stays one when it cancels).
    fn reference_pivots(m: usize, n: usize, entries: &[(usize, usize)], jac: &[f64]) -> (Vec<usize>, Vec<usize>) {
        let mut a = vec![vec![None::<f64>; n]; m];
        for (&(r, c), &v) in entries.iter().zip(jac) {
            a[r][c] = Some(a[r][c].unwrap_or(0.0) + v);
        }
        let row_max = |row: &[Option<f64>]| row.iter().flatten().fold(0.0f64, |x, v| x.max(v.abs()));
        let zero = RANK_TOLERANCE * a.iter().map(|row| row_max(row)).fold(0.0, f64::max);
        let mut active = vec![true; m];
        let (mut prow, mut pcol) = (vec![], vec![]);
        loop {
            let largest = (0..m).filter(|&r| active[r]).map(|r| row_max(&a[r])).fold(0.0, f64::max);
            if largest <= zero || largest.is_nan() {
                break;
            }
            let len = |row: &[Option<f64>]| row.iter().flatten().count();
            let mut candidates: Vec<(usize, usize)> = (0..m)
                .filter(|&r| active[r] && row_max(&a[r]) / largest >= PIVOT_THRESHOLD)
                .map(|r| (len(&a[r]), r))
                .collect();
            candidates.sort_unstable();
            candidates.truncate(PIVOT_ROWS);
            let mut best: Option<(usize, usize, usize, f64)> = None;
            for &(l, r) in &candidates {
                for c in 0..n {
                    let Some(v) = a[r][c] else { continue };
                    let rel = v.abs() / largest;
                    if rel < PIVOT_THRESHOLD {
                        continue;
                    }
                    let count = (0..m).filter(|&k| active[k] && a[k][c].is_some()).count();
                    let cost = (l - 1) * (count - 1);
                    if best.is_none_or(|(_, _, bc, brel)| cost < bc || (cost == bc && rel > brel)) {
                        best = Some((r, c, cost, rel));
                    }
                }
            }
            let (pr, pc, _, _) = best.unwrap();
            active[pr] = false;
            prow.push(pr);
            pcol.push(pc);
            let pivot = a[pr].clone();
            let pv = pivot[pc].unwrap();
            for r in (0..m).filter(|&r| active[r]) {
                let Some(x) = a[r][pc] else { continue };
                let l = x / pv;
                for c in 0..n {
                    if let Some(b) = pivot[c] {
                        a[r][c] = Some(a[r][c].map_or(-l * b, |y| y - l * b));
                    }
                }
                a[r][pc] = None;
            }
        }
        prow.sort_unstable();
        pcol.sort_unstable();
        (prow, pcol)
    }

    /// The partition's elimination, sparse (its heaps, versions and merges) and dense, chooses as
    /// the brute-force reference does, on 600 random sparse matrices of 2 to 24 rows: entries of
    /// one size (most rows pass the threshold), entries over six decades (few pass), a fifth with
    /// entries of 1 and 2 only (exact ties, broken by the rule's order), and a third with a row
    /// repeated as the sum of two others (redundant, left out).
    #[test]
    fn pivots_match_the_dense_reference() {
        let mut seed = 11u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut redundant = 0;
        // One set of buffers for every case, as a partition keeps them.
        let mut dense_work = PivotWork::default();
        for case in 0..600 {
            let m = 2 + (random() * 23.0) as usize;
            let n = m + 1 + (random() * 3.0) as usize;
            let mut dense = vec![vec![None::<f64>; n]; m];
            for (r, row) in dense.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    if random() < 0.25 || c == r {
                        let size = match case % 5 {
                            // Exact ties, as a Jacobian's unit entries make them.
                            4 => 1.0 + (random() * 2.0).floor(),
                            _ if case % 2 == 0 => 0.5 + 0.5 * random(),
                            _ => 10f64.powf(6.0 * random() - 3.0),
                        };
                        *x = Some(if random() < 0.5 { size } else { -size });
                    }
                }
            }
            let repeated = case % 3 == 0 && m >= 3;
            if repeated {
                dense[m - 1] = (0..n)
                    .map(|c| match (dense[0][c], dense[1][c]) {
                        (None, None) => None,
                        (x, y) => Some(x.unwrap_or(0.0) + y.unwrap_or(0.0)),
                    })
                    .collect();
            }
            let (mut entries, mut jac) = (vec![], vec![]);
            for (r, row) in dense.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    if let Some(v) = x {
                        entries.push((r, c));
                        jac.push(*v);
                    }
                }
            }
            let (rows, cols, _) = pivots(m, n, &entries, &jac);
            redundant += usize::from(repeated && rows.len() < m);
            let reference = reference_pivots(m, n, &entries, &jac);
            assert_eq!((rows, cols), reference, "case {case}: {m} x {n}, sparse");
            dense_work.run_dense(m, n, &entries, &jac);
            assert_eq!((&dense_work.prow, &dense_work.pcol), (&reference.0, &reference.1), "case {case}: dense");
        }
        assert!(redundant > 150, "{redundant} repeated rows found redundant");
    }

    /// The IFToMM A02 N-four-bar with `n` loops, as `examples/nfourbar.py` writes it.
    fn nfourbar(n: usize) -> String {
        let mut y = String::from("name: nfourbar\ngravity: [0, -9.81]\nbodies:\n");
        for k in 0..=n {
            y += &format!("  r{k}: {{mass: 1, inertia: 0.0833333333333333, position: [{k}, 0.5], angle: 1.5707963267948966, velocity: [0.5, 0], omega: -1, points: {{A: [-0.5, 0], B: [0.5, 0]}}}}\n");
        }
        for k in 1..=n {
            y += &format!("  c{k}: {{mass: 1, inertia: 0.0833333333333333, position: [{}, 1], angle: 0, velocity: [1, 0], points: {{L: [-0.5, 0], R: [0.5, 0]}}}}\n", k as f64 - 0.5);
        }
        y += "joints:\n";
        for k in 0..=n {
            y += &format!("  A{k}: {{type: revolute, body_i: r{k}, point_i: A, body_j: ground, point_j: [{k}, 0]}}\n");
        }
        for k in 1..=n {
            y += &format!("  L{k}: {{type: revolute, body_i: c{k}, point_i: L, body_j: r{}, point_j: B}}\n", k - 1);
            y += &format!("  R{k}: {{type: revolute, body_i: c{k}, point_i: R, body_j: r{k}, point_j: B}}\n");
        }
        y + "analyses:\n  dynamics: {type: dynamic, t_end: 1, step: 0.01}\n"
    }

    /// The partition's elimination keeps `Phi_q`'s sparsity: on the N-four-bar (`6N + 3`
    /// coordinates, `6N + 2` rows of which `N - 1` are redundant) its work grows linearly with
    /// N, as the number of entries does. Measured: 591 entries merged at N = 10, 4,931 at N = 80
    /// (8.3 times for 8 times the bodies). The dense full-pivoting LU it replaced costs `~m n^2`
    /// (512 times); a first sparse version that took its pivots from the rows with the largest
    /// entries filled in along the chain (0.59 M entries merged at N = 100, 8.5 M at N = 200). The
    /// rank is the mechanism's: one degree of freedom.
    #[test]
    fn partition_work_grows_linearly() {
        let mut work = vec![];
        for n in [10, 80] {
            let model = crate::model::Model::from_yaml(&nfourbar(n)).unwrap();
            let mut dae = crate::analysis::dynamic::Dae::new(&model, &[], &[]).unwrap();
            dae.positions(&model.q0(), 0.0);
            let (entries, jac) = dae.jacobian_entries();
            let (rows, cols, w) = pivots(dae.m, dae.n, entries, jac);
            assert_eq!((rows.len(), cols.len()), (dae.n - 1, dae.n - 1), "N = {n}: one degree of freedom");
            eprintln!("N = {n}: {} coordinates, {} entries, work {w}", dae.n, entries.len());
            work.push(w as f64);
        }
        let growth = work[1] / work[0];
        assert!(growth < 12.0, "work grows {growth} times for 8 times the bodies");
    }
}
