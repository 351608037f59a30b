//! Linkwork: a planar multibody kinematics and dynamics engine.
//!
//! Data flows one way, and the imports follow it: each module imports only the ones above it
//! here, not its peer on the same line ([`error`], [`progress`] and [`linalg`] from anywhere,
//! and they import none of the others), save that an analysis writes its [`Results`], and
//! `results` imports nothing of `analysis` (`tests/layers.rs` reads every import against this).
//!
//! ```text
//! expr                      expressions of time and state, differentiated exactly; tables;
//!                           functionals of sampled columns (integral, mean, max, ...)
//!  -> element               what joints, drivers and force elements share: a body and its
//!                           frame, a body point, the named types and their registries, and the
//!                           context an element is compiled in
//!  -> constraints, forces   joint and driver rows (Phi, Phi_q, nu, gamma); force laws; each
//!                           type's file schema and compile step, in its own module
//!  -> model                 a file's schema (spec), its parameters and units (params, units),
//!                           read with every problem located (parse),
//!                           compiled into an immutable Model (compile) whose analyses carry
//!                           the compiled solver: section (settings); its picture (drawing)
//!  -> system                an analysis' joints and active drivers stacked into one system
//!  -> analysis              the run entry point (Model::run, RunOptions) and every analysis:
//!                           assembly, checks, kinematic, inverse, static, modes, dynamic
//!  -> results               columnar time series, the typed summary (with the model's
//!                           summaries, functionals of the columns), and their files
//!  -> sweep                 an analysis over many parameter values in parallel, reduced to
//!                           outputs (functionals of result columns)
//!
//! linalg                    sparse patterns and LU, dense SVD helpers (rank, null space,
//!                           minimum-norm solve), knowing no mechanics
//! error, progress           errors; a run's progress and its stop token (Ctrl-C)
//! ```
//!
//! A model file ([`model::spec`]) is read and validated with every problem located
//! ([`model::parse_spec`]) and compiled into a [`Model`] (indices, constraints, and
//! [`model::SolverSettings`] and [`model::IntegratorSettings`] per analysis). [`Model::run`]
//! ([`analysis`]) checks the run's [`Overrides`] (in its [`RunOptions`], with its watcher, stop
//! token and [`Sink`]) as the file's own fields, stacks the active
//! constraints into a [`system::System`], solves with sparse factorizations ([`linalg`]) and
//! writes [`Results`].
//!
//! ```no_run
//! let model = linkwork::Model::load("examples/quick_return_a.yaml")?;
//! let results = model.run("kinematics", &linkwork::RunOptions::default()).map_err(|f| f.error)?;
//! println!("{} output points", results.len());
//! # Ok::<(), linkwork::Error>(())
//! ```

pub mod analysis;
pub mod constraints;
mod element;
pub mod error;
pub mod expr;
pub mod forces;
pub mod linalg;
pub mod model;
pub mod progress;
pub mod results;
pub mod sweep;
pub mod system;

pub use analysis::{Overrides, RunOptions, Sink};
pub use error::{Error, Problem, RowName, Unbalanced};
pub use model::Model;
pub use results::{Failure, Results, Sensitivities};
