//! What the force elements' compile steps ask beyond the [`Context`] every element shares: the
//! expressions of time and the state their loads may be ([`ForceContext`]), and a load's schema
//! ([`Quantity`]).

use super::{Load, StateExpr};
use crate::element::Context;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A number, or an expression of time `t` and the state (`crank.phi`, `crank.omega`,
/// `slider_d.vx`: `<body>.x, .y, .phi, .vx, .vy, .omega`).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Quantity {
    /// A constant.
    Number(f64),
    /// An expression such as `"-20*crank.omega + 100*sin(t)"`.
    Expression(String),
}

impl Default for Quantity {
    fn default() -> Self {
        Quantity::Number(0.0)
    }
}

/// Read by hand: an untagged enum's error would lose the field's path.
impl<'de> Deserialize<'de> for Quantity {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Quantity;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a number or an expression of t and the state, such as \"-20*crank.omega\"")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Quantity, E> {
                Ok(Quantity::Expression(v.to_string()))
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Quantity, E> {
                Ok(Quantity::Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Quantity, E> {
                Ok(Quantity::Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Quantity, E> {
                Ok(Quantity::Number(v as f64))
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// The [`Context`] of a force element: it also compiles expressions of time and the state.
pub(crate) trait ForceContext: Context {
    /// An expression at `path` of time `t` and the state: `<body>.x, .y, .phi, .vx, .vy, .omega`.
    fn force_expr(&mut self, path: &str, src: &str) -> Option<StateExpr>;

    /// A force's number or expression of time and state at `path`.
    fn load(&mut self, path: &str, q: &Quantity) -> Option<Load> {
        match q {
            Quantity::Number(v) => self.finite(path, *v).map(Load::Constant),
            Quantity::Expression(src) => self.force_expr(path, src).map(Load::Expression),
        }
    }
}
