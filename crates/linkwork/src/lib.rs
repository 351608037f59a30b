//! Linkwork: a planar multibody kinematics and dynamics engine.
//!
//! Data flows one way: a model file ([`model::spec`]) is read and validated with every problem
//! located ([`model::parse_spec`]), compiled into an immutable [`Model`] (indices, constraints),
//! and an analysis ([`analysis`]) stacks the active constraints into a [`system::System`], solves
//! with sparse factorizations ([`linalg`]) and writes [`Results`].
//!
//! ```no_run
//! let model = linkwork::Model::load("examples/quick_return_a.yaml")?;
//! let results = model.run("kinematics").map_err(|f| f.error)?;
//! println!("{} output points", results.len());
//! # Ok::<(), linkwork::Error>(())
//! ```

pub mod analysis;
pub mod constraints;
pub mod error;
pub mod expr;
pub mod forces;
pub mod linalg;
pub mod model;
pub mod results;
pub mod system;

pub use analysis::Overrides;
pub use error::{Error, Problem, RowName, Unbalanced};
pub use model::Model;
pub use results::{Failure, Results};
