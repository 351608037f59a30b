//! A partition of the coordinates: the independent rows of `Phi_q`, the dependent coordinates
//! `q_D` (the pivots of its elimination, [`super::pivots::PivotWork`]) and the independent ones
//! `q_I`, with how strongly these move the others.

use super::block::Blocks;
use super::pivots::PivotWork;
use super::reduced::REDUCED_MAX;

/// A choice of independent coordinates.
#[derive(Default)]
pub(super) struct Partition {
    /// (r) independent rows of `Phi_q` (the pivot rows), `r` its numerical rank.
    pub(super) rows: Vec<usize>,
    /// (r) dependent coordinates (the pivot columns), ascending.
    pub(super) dep: Vec<usize>,
    /// (n - r) independent coordinates, ascending.
    pub(super) ind: Vec<usize>,
    /// The elimination's buffers, and a scratch for the independent coordinates.
    pivot_work: PivotWork,
    ind_scratch: Vec<usize>,
    /// Whether the accelerations are solved in the independent coordinates
    /// ([`super::Split::reduced_accelerations`]): at most [`REDUCED_MAX`] of them, no redundant
    /// rows (their multipliers are the augmented solve's), no joint friction (its load depends on
    /// the multipliers).
    pub(super) reduced: bool,
    /// `max |dq_D / dq_I|` when the partition was chosen, and at the last accepted step.
    pub(super) influence0: f64,
    pub(super) influence1: f64,
}

impl Partition {
    /// Choose the partition of `Phi_q` (`m x n`, entries `entries` with values `jac`; `friction`:
    /// whether a joint has friction) and select its block in `blocks`; true when the independent
    /// coordinates changed.
    pub(super) fn choose(
        &mut self,
        entries: &[(usize, usize)],
        jac: &[f64],
        (m, n): (usize, usize),
        friction: bool,
        blocks: &mut Blocks,
    ) -> bool {
        let work = &mut self.pivot_work;
        work.run(m, n, entries, jac);
        let (rows, dep) = (&work.prow, &work.pcol);
        let mut ind = std::mem::take(&mut self.ind_scratch);
        ind.clear();
        let mut next = dep.iter().peekable();
        for c in 0..n {
            if next.peek() == Some(&&c) {
                next.next();
            } else {
                ind.push(c);
            }
        }
        let changed = ind != self.ind;
        blocks.select(entries, m, n, rows, dep, &ind);
        let (r, p) = (dep.len(), ind.len());
        self.reduced = r > 0 && r == m && p <= REDUCED_MAX && !friction;
        self.rows.clone_from(rows);
        self.dep.clone_from(dep);
        self.ind_scratch = std::mem::replace(&mut self.ind, ind);
        changed
    }
}
