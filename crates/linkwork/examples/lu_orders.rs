//! The cost of one factorization and two solves of a chain's Newton matrix, with dense and with
//! sparse factors, at each order: the measurement behind `linalg::DENSE_LU_MAX_ORDER`.
//!
//! ```sh
//! cargo run --release -p linkwork --example lu_orders
//! ```
//!
//! The matrix is `[D, J^T; J, -1e-10 I]` for a chain of `b` bodies (`3 b` coordinates, `3 b - 1`
//! constraint rows, each touching two neighbouring bodies), as the integrators factor it.

use linkwork::linalg::{Pattern, SparseLu};
use std::time::Instant;

fn main() {
    println!("| order | dense us | sparse us |\n| --- | --- | --- |");
    for bodies in [3usize, 5, 8, 12, 16, 24, 32] {
        let n = 3 * bodies;
        let dim = 2 * n - 1;
        let mut entries: Vec<(usize, usize)> = (0..dim).map(|i| (i, i)).collect();
        for r in 0..n - 1 {
            let body = (r / 3).min(bodies - 2);
            for c in 3 * body..3 * body + 6 {
                entries.push((n + r, c));
                entries.push((c, n + r));
            }
        }
        let mut seed = 1u64;
        let values: Vec<f64> = entries
            .iter()
            .map(|&(i, j)| {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                match (i == j, i < n) {
                    (true, true) => 2.0,
                    (true, false) => -1e-10,
                    _ => (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5,
                }
            })
            .collect();
        let pattern = Pattern::new(dim, dim, entries.iter().map(|&e| Some(e)));
        let repeats = 400_000 / (bodies * bodies);
        let mut cost = [0.0; 2];
        for (k, dense) in [true, false].into_iter().enumerate() {
            let mut lu = SparseLu::with_factors(pattern.clone(), dense).expect("symbolic LU");
            let mut b = vec![0.0; dim];
            let start = Instant::now();
            for _ in 0..repeats {
                let (p, v) = lu.pattern_and_values();
                v.fill(0.0);
                for (&pos, x) in p.map.iter().zip(&values) {
                    v[pos] += x;
                }
                lu.factor().expect("regular");
                for _ in 0..2 {
                    b.fill(1.0);
                    lu.solve(&mut b);
                }
            }
            cost[k] = start.elapsed().as_secs_f64() * 1e6 / repeats as f64;
        }
        println!("| {dim} | {:.1} | {:.1} |", cost[0], cost[1]);
    }
}
