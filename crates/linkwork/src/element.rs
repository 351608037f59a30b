//! What the joints, drivers and force elements share, below both `constraints` and `forces`:
//! the `named!` enums that model files call by name, the [`Tagged`] sections and their
//! `registry!`, a body ([`BodyIx`]) and its frame ([`Frame`]), a body point ([`PointRef`]), and the
//! [`Context`] an element is compiled in, which the model's compiler implements (the elements
//! stay below the model). Each layer extends the context with what only it needs
//! (`constraints::JointContext`, `forces::ForceContext`).

use crate::error::Problem;
use crate::expr::{Expr, Scalar, TimeFunction};
use schemars::JsonSchema;
use serde::{Deserialize, Deserializer, Serialize};

/// An enum whose variants model files call by name (`integrator: hht`, `type: revolute`), each
/// name written once, as `"name" => Variant`: it is the variant's serde name, the enum's `NAMES`
/// list it, and `name()` returns it. A plain enum also gets `from_name`; the `tagged` form, for a
/// section whose entries name their kind in `type` (each variant holding the struct of its
/// fields), implements [`Tagged`] with the same names.
macro_rules! named {
    (
        tagged $(#[$attr:meta])*
        pub enum $Enum:ident { $( $(#[$vattr:meta])* $name:literal => $Variant:ident($Inner:ty), )* }
    ) => {
        $crate::element::named! { @enum $(#[$attr])* pub enum $Enum { $( $(#[$vattr])* $name => $Variant($Inner), )* } }

        impl $crate::element::Tagged for $Enum {
            const TYPES: &'static [&'static str] = $Enum::NAMES;

            fn read<'de, D: serde::Deserializer<'de>>(kind: &str, d: D) -> Option<Result<Self, D::Error>> {
                Some(match kind {
                    $( $name => <$Inner as serde::Deserialize>::deserialize(d).map($Enum::$Variant), )*
                    _ => return None,
                })
            }
        }
    };
    (
        $(#[$attr:meta])*
        pub enum $Enum:ident { $( $(#[$vattr:meta])* $name:literal => $Variant:ident, )* }
    ) => {
        $crate::element::named! { @enum $(#[$attr])* pub enum $Enum { $( $(#[$vattr])* $name => $Variant, )* } }

        impl $Enum {
            /// The variant called `name` in model files, if there is one.
            pub fn from_name(name: &str) -> Option<Self> {
                match name {
                    $( $name => Some($Enum::$Variant), )*
                    _ => None,
                }
            }
        }
    };
    (
        @enum $(#[$attr:meta])*
        pub enum $Enum:ident { $( $(#[$vattr:meta])* $name:literal => $Variant:ident $(($Inner:ty))?, )* }
    ) => {
        $(#[$attr])*
        pub enum $Enum {
            $( $(#[$vattr])* #[serde(rename = $name)] $Variant $(($Inner))?, )*
        }

        impl $Enum {
            /// Every name, as written in model files.
            pub const NAMES: &'static [&'static str] = &[$($name),*];

            /// Its name in the model file.
            pub fn name(&self) -> &'static str {
                match self {
                    $( $Enum::$Variant { .. } => $name, )*
                }
            }
        }
    };
}
pub(crate) use named;

/// A registry: a [`Tagged`] section (`named!`'s `tagged` form) whose every kind is compiled by a
/// function of its own module, `"name" => Variant(Fields, module::compile)`, into `$Out`, in a
/// context `$Cx` (a [`Context`], or its extension for the section's layer). The enum gets
/// `compile(&self, cx, path)`, which calls that function.
macro_rules! registry {
    (
        $(#[$attr:meta])*
        pub enum $Enum:ident -> $Out:ty, in $Cx:path {
            $( $(#[$vattr:meta])* $name:literal => $Variant:ident($Inner:ty, $compile:path), )*
        }
    ) => {
        $crate::element::named! { tagged $(#[$attr])* pub enum $Enum { $( $(#[$vattr])* $name => $Variant($Inner), )* } }

        impl $Enum {
            /// The entry compiled in `cx`, its problems reported there at `path` (`joints.<name>`,
            /// `drivers.<name>`).
            pub(crate) fn compile(&self, cx: &mut impl $Cx, path: &str) -> Option<$Out> {
                match self {
                    $( $Enum::$Variant(fields) => $compile(fields, cx, path), )*
                }
            }
        }
    };
}
pub(crate) use registry;

/// A model file entry's fields (an element's), its shared ones named once in a list before its
/// own: `[body_i, point_i?, axis_i?, body_j, point_j?, at, axis,]`, in their order in the entry.
/// Each shared field is declared here once, with one description; `?` marks a point or a
/// direction that `at` or `axis` may place instead (optional, default none). The serde names,
/// order and types are what the list says, so a bad entry's errors and their field paths are
/// those of the struct written out (serde's `flatten` would refuse `deny_unknown_fields` and lose
/// the paths).
macro_rules! fields {
    (
        $(#[$attr:meta])*
        pub struct $Name:ident { [$($shared:tt)*] $($own:tt)* }
    ) => {
        $crate::element::fields! { @munch [$(#[$attr])*] $Name [] [$($shared)*] [$($own)*] }
    };
    (@munch [$($attr:tt)*] $Name:ident [$($done:tt)*] [] [$($own:tt)*]) => {
        $($attr)* pub struct $Name { $($done)* $($own)* }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [body_i, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// First body (or `ground`).
            pub body_i: String,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [body_j, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// Second body (or `ground`).
            pub body_j: String,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [point_i, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A point of the first body, in its frame.
            pub point_i: $crate::element::PointRef,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [point_j, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A point of the second body, in its frame.
            pub point_j: $crate::element::PointRef,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [point_i?, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A point of the first body, in its frame (or `at`).
            #[serde(default)]
            pub point_i: Option<$crate::element::PointRef>,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [point_j?, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A point of the second body, in its frame (or `at`).
            #[serde(default)]
            pub point_j: Option<$crate::element::PointRef>,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [axis_i, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A direction of the first body, in its frame, any non-zero length.
            pub axis_i: [f64; 2],
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [axis_i?, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A direction of the first body, in its frame, any non-zero length (or `axis`).
            #[serde(default)]
            pub axis_i: Option<[f64; 2]>,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [axis_j?, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// A direction of the second body, in its frame, any non-zero length (or `axis`).
            #[serde(default)]
            pub axis_j: Option<[f64; 2]>,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [at, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// The global position, m, at the initial position, of the point that `point_i` and
            /// `point_j` give, instead of them.
            #[serde(default)]
            pub at: Option<[f64; 2]>,
        ] [$($more)*] $own }
    };
    (@munch $attr:tt $Name:ident [$($done:tt)*] [axis, $($more:tt)*] $own:tt) => {
        $crate::element::fields! { @munch $attr $Name [$($done)*
            /// The global direction at the initial position, instead of `axis_i` (and `axis_j`).
            #[serde(default)]
            pub axis: Option<[f64; 2]>,
        ] [$($more)*] $own }
    };
}
pub(crate) use fields;

/// The kinds of a section's entries (joints, drivers, forces), which name theirs in `type`.
pub trait Tagged: Sized {
    /// Every `type`, as written in model files (the enum's `NAMES`).
    const TYPES: &'static [&'static str];

    /// The entry of `type: kind` read from `d`, the entry without its `type`; `None` when no
    /// kind has that name. Reading the variant's struct straight from `d` keeps the path of a
    /// bad field (serde's internally tagged enums buffer the entry first, which loses it).
    fn read<'de, D: Deserializer<'de>>(kind: &str, d: D) -> Option<Result<Self, D::Error>>;
}

/// Two numbers of a sequence, `[x, y]`; a sequence of another length is refused as not what
/// `expected` describes.
pub(crate) fn pair<'de, A: serde::de::SeqAccess<'de>>(
    mut seq: A,
    expected: &dyn serde::de::Expected,
) -> Result<[f64; 2], A::Error> {
    use serde::de::Error;
    let x: f64 = seq.next_element()?.ok_or_else(|| A::Error::invalid_length(0, expected))?;
    let y: f64 = seq.next_element()?.ok_or_else(|| A::Error::invalid_length(1, expected))?;
    if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
        return Err(A::Error::invalid_length(3, expected));
    }
    Ok([x, y])
}

/// A point of a body: its coordinates `[x, y]` in the body frame, m, or the name of one of the
/// body's `points`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum PointRef {
    /// Coordinates in the body frame.
    Coords([f64; 2]),
    /// A named point of the body.
    Name(String),
}

/// Read by hand rather than derived: an untagged enum's error ("data did not match any variant")
/// would lose the field's path and say nothing useful.
impl<'de> Deserialize<'de> for PointRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = PointRef;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a point: [x, y] in the body frame, or the name of one of the body's points")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<PointRef, E> {
                Ok(PointRef::Name(v.to_string()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, seq: A) -> Result<PointRef, A::Error> {
                pair(seq, &self).map(PointRef::Coords)
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl Default for PointRef {
    fn default() -> Self {
        PointRef::Coords([0.0, 0.0])
    }
}

/// A body and a point of it, body frame.
pub(crate) type End = (BodyIx, [f64; 2]);

/// `v`, or a problem at `path` when it is not finite.
pub(crate) fn finite(problems: &mut Vec<Problem>, path: &str, v: f64) -> Option<f64> {
    if v.is_finite() {
        Some(v)
    } else {
        problems.push(Problem::new(path, format!("expected a finite number, found {v}")));
        None
    }
}

/// `v`, or a problem at `path` when it is not a finite number above zero.
pub(crate) fn positive(problems: &mut Vec<Problem>, path: &str, v: f64) -> Option<f64> {
    let v = finite(problems, path, v)?;
    if v > 0.0 {
        Some(v)
    } else {
        problems.push(Problem::new(path, format!("expected a positive number, found {v}")));
        None
    }
}

/// Where a body's coordinates sit in `q`: the index of its `x` (`y` and `phi` follow), or `None`
/// for ground, which has no coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BodyIx(pub Option<usize>);

impl BodyIx {
    /// Ground.
    pub const GROUND: BodyIx = BodyIx(None);

    /// `(x, y, phi)` of the body from a coordinate vector (zeros for ground).
    #[inline]
    pub fn coords(self, q: &[f64]) -> [f64; 3] {
        self.pose(q)
    }

    /// `(x, y, phi)` of the body from all coordinates over any [`Scalar`] (ground: the origin at
    /// angle 0, constants), for equations evaluated with derivatives (design sensitivities).
    #[inline]
    pub fn pose<S: Scalar>(self, q: &[S]) -> [S; 3] {
        match self.0 {
            Some(k) => [q[k], q[k + 1], q[k + 2]],
            None => [S::constant(0.0); 3],
        }
    }
}

/// `A(phi) v` from `(cos phi, sin phi)`, over any [`Scalar`]: a body-frame vector in the global
/// frame. [`Frame::rotate`] is this with the frame's cached rotation.
#[inline]
pub(crate) fn rotated<S: Scalar>([c, s]: [S; 2], v: [S; 2]) -> [S; 2] {
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// A body frame over any [`Scalar`]: its origin, angle and rotation, what [`Frame`] is for `f64`,
/// for equations evaluated with derivatives (design sensitivities).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pose<S> {
    /// `(2)` the origin, global frame.
    pub o: [S; 2],
    /// The angle.
    pub phi: S,
    /// `(cos phi, sin phi)`.
    cs: [S; 2],
}

impl<S: Scalar> Pose<S> {
    /// Body `body`'s frame at the coordinates `q (n)` (ground's is the global one).
    #[inline]
    pub fn of(body: BodyIx, q: &[S]) -> Pose<S> {
        let [x, y, phi] = body.pose(q);
        Pose { o: [x, y], phi, cs: [phi.cos(), phi.sin()] }
    }
    /// The frame at `(x, y, phi)` held constant (a body's initial pose).
    #[inline]
    pub fn held([x, y, phi]: [f64; 3]) -> Pose<S> {
        Pose {
            o: [S::constant(x), S::constant(y)],
            phi: S::constant(phi),
            cs: [S::constant(phi.cos()), S::constant(phi.sin())],
        }
    }
    /// The frame `f` held constant, with its cached rotation (no trigonometry): what an equation
    /// written over any [`Scalar`] reads on its value path ([`crate::constraints::Friction::load`]).
    #[inline]
    pub fn frame(f: &Frame) -> Pose<S> {
        Pose {
            o: [S::constant(f.x), S::constant(f.y)],
            phi: S::constant(f.phi),
            cs: [S::constant(f.c), S::constant(f.s)],
        }
    }
    /// `A s'`: a body-frame vector in the global frame.
    #[inline]
    pub fn rotate(&self, v: [S; 2]) -> [S; 2] {
        rotated(self.cs, v)
    }
    /// `A^T (p - r)`: a global point in the body frame ([`Frame::local`]'s arithmetic).
    #[inline]
    pub fn local(&self, p: [S; 2]) -> [S; 2] {
        let (v, [c, s]) = ([p[0] - self.o[0], p[1] - self.o[1]], self.cs);
        [c * v[0] + s * v[1], -s * v[0] + c * v[1]]
    }
}

/// Where a constant of an element comes from (a distance's length, a line's offset, a held
/// coordinate's value, the constants of gears, belts and rolling joints, a spring's free length:
/// which only the initial configuration gives when the file leaves them out).
///
/// Written in the model file, it is one of the element's data (a parameter can move it). Fixed by
/// the initial configuration, it is what the element's rows are at the bodies' initial poses
/// `q0`: those poses are held (a derivative does not move the starting guess), and the constant
/// follows the element's data through them (a distance's default length moves with its points).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Source {
    /// The model file's field: a data slot named after it.
    File,
    /// The initial configuration: `(x, y, phi)` of the element's two bodies there (ground's is
    /// zero).
    Start([[f64; 3]; 2]),
    /// No such field: zero (a pin in a slot has no offset; a driver's coordinate no value).
    Zero,
}

impl Source {
    /// The initial poses of bodies `i` and `j` in `q0`.
    pub(crate) fn start(i: BodyIx, j: BodyIx, q0: &[f64]) -> Source {
        Source::Start([i.coords(q0), j.coords(q0)])
    }
    /// Body i's and body j's poses there, held constant.
    pub(crate) fn poses<S: Scalar>(start: [[f64; 3]; 2]) -> [Pose<S>; 2] {
        start.map(Pose::held)
    }
    /// An element's `data` with its constant `(name, value)` last when the file gives it.
    pub(crate) fn data(
        self,
        mut data: Vec<(&'static str, f64)>,
        name: &'static str,
        value: f64,
    ) -> Vec<(&'static str, f64)> {
        if self == Source::File {
            data.push((name, value));
        }
        data
    }
    /// The constant over any [`Scalar`]: the last of `data` from the file, `at_start` of the held
    /// initial poses (body i's, body j's) from the initial configuration, or zero.
    pub(crate) fn value<S: Scalar>(self, data: &[S], at_start: impl FnOnce([Pose<S>; 2]) -> S) -> S {
        match self {
            Source::File => data[data.len() - 1],
            Source::Start(start) => at_start(Source::poses(start)),
            Source::Zero => S::constant(0.0),
        }
    }
}

/// The data names of a vector field's two components.
pub(crate) type Components = [&'static str; 2];
/// `point`'s components (a single body's point: held coordinates, point drivers).
pub(crate) const POINT: Components = ["point[0]", "point[1]"];
/// `point_i`'s components.
pub(crate) const POINT_I: Components = ["point_i[0]", "point_i[1]"];
/// `point_j`'s components.
pub(crate) const POINT_J: Components = ["point_j[0]", "point_j[1]"];
/// `axis_i`'s components.
pub(crate) const AXIS_I: Components = ["axis_i[0]", "axis_i[1]"];
/// `axis_j`'s components.
pub(crate) const AXIS_J: Components = ["axis_j[0]", "axis_j[1]"];

/// The data entries of a vector `v` named `names` (an element's data: a joint's, a driver's or a force's).
pub(crate) fn vector(names: Components, v: [f64; 2]) -> [(&'static str, f64); 2] {
    [(names[0], v[0]), (names[1], v[1])]
}

/// The pose of a body frame: origin and rotation `A(phi)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    pub x: f64,
    pub y: f64,
    pub phi: f64,
    pub c: f64,
    pub s: f64,
}

impl Frame {
    /// The frame from a bare coordinate vector (computes the rotation), outside the hot loops.
    pub fn of_slice(body: BodyIx, q: &[f64]) -> Frame {
        Frame::at(body.coords(q))
    }
    /// The frame at `(x, y, phi)` (computes the rotation), outside the hot loops.
    pub fn at([x, y, phi]: [f64; 3]) -> Frame {
        let (s, c) = phi.sin_cos();
        Frame { x, y, phi, c, s }
    }
    /// `A s'`: a body-frame vector in the global frame.
    #[inline]
    pub fn rotate(&self, v: [f64; 2]) -> [f64; 2] {
        rotated([self.c, self.s], v)
    }
    /// `B s' = dA/dphi s' = R90 A s'`.
    #[inline]
    pub fn rotate_d(&self, v: [f64; 2]) -> [f64; 2] {
        [-self.s * v[0] - self.c * v[1], self.c * v[0] - self.s * v[1]]
    }
    /// `r + A s'`: a body point in the global frame.
    #[inline]
    pub fn point(&self, v: [f64; 2]) -> [f64; 2] {
        let a = self.rotate(v);
        [self.x + a[0], self.y + a[1]]
    }
    /// `A^T v`: a global vector in the body frame.
    pub fn unrotate(&self, v: [f64; 2]) -> [f64; 2] {
        [self.c * v[0] + self.s * v[1], -self.s * v[0] + self.c * v[1]]
    }
    /// `A^T (p - r)`: a global point in the body frame.
    pub fn local(&self, p: [f64; 2]) -> [f64; 2] {
        self.unrotate([p[0] - self.x, p[1] - self.y])
    }
}

/// The default transition velocity `v_s`, m/s: 1 mm/s. Below the sticking limit the joint creeps
/// at less than `v_s` (see `constraints::friction`), 1 mm/s, a creep of a millimetre a second that a
/// mechanism of a metre hardly shows; the coefficient's slope at rest, `mu N / v_s`, makes the
/// equations stiff with a time constant `m v_s / (mu N)` (`3e-4` s for a block of any mass held
/// by gravity at `mu = 0.3`), which the implicit integrators step over. A smaller `v_s` creeps less
/// and is stiffer: Adams' default is `0.1` length units per second, `1e-4` m/s in its default
/// millimetres.
pub const DEFAULT_TRANSITION_VELOCITY: f64 = 1e-3;

/// What a number an element places in a body frame from the global frame was computed from
/// ([`Context::place`]): a global point or direction, written at `field`, seen in `body`'s frame
/// at the initial position.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Placed<'a> {
    /// A point: `A^T (global - r)`.
    Point { body: &'a str, global: [f64; 2], field: &'a str },
    /// A direction: `A^T global`.
    Direction { body: &'a str, global: [f64; 2], field: &'a str },
}

/// What an element's (a joint's, a driver's, a force's) compile step asks of the model it is
/// compiled in: its bodies and points by name, the initial configuration, expressions of its names, and a
/// list of problems, each at the path of its field. The model's compiler implements the required
/// methods; the provided ones, built on them, check and resolve the fields elements share.
pub(crate) trait Context {
    /// The problems found so far; each step adds its own.
    fn problems(&mut self) -> &mut Vec<Problem>;
    /// The body `name` named at `path`: ground or a moving body; `None`, with a problem at
    /// `path` when no body has that name (none when it exists but could not be read).
    fn body(&mut self, path: &str, name: &str) -> Option<BodyIx>;
    /// The point `p` of body `body` in its frame, named at `path`; `None`, with its problem, when
    /// it is not a point of the body.
    fn point(&mut self, path: &str, body: &str, p: &PointRef) -> Option<[f64; 2]>;
    /// The initial guess of every body's coordinates, `(3 * bodies)`, for constants that default
    /// to their value in the initial configuration.
    fn q0(&self) -> &[f64];
    /// Body `name`'s frame at its initial position (ground's is the global one); `None` for a
    /// body that is not known (reported where it is named).
    fn initial_frame(&self, name: &str) -> Option<Frame>;
    /// Record that the field at `path` was placed from global coordinates, as `value` in its
    /// body's frame, `from` what (for its derivatives with respect to the model's parameters).
    fn place(&mut self, path: String, value: [f64; 2], from: Placed<'_>);
    /// Note that the number `v` at `path` (a field of the file, or one placed there) was handed
    /// to the element being compiled: the model keeps its derivatives with respect to the
    /// parameters under that path, for the element's data (design sensitivities).
    fn hand(&mut self, path: &str, v: f64);
    /// An expression at `path` of the curve parameter `var` (slot 0; `what` it is), parameters
    /// and tables.
    fn curve_expr(&mut self, path: &str, src: &str, var: &str, what: &str) -> Option<Expr>;
    /// The columns `x` and `y` of the CSV file `file` (relative to the model's folder), for the
    /// entry at `path`.
    fn csv_columns(&mut self, path: &str, file: &str, x: &str, y: &str) -> Option<(Vec<f64>, Vec<f64>)>;
    /// A driver's function of time `t` at `path`, of parameters and tables.
    fn time_function(&mut self, path: &str, src: &str) -> Option<TimeFunction>;

    /// Report `msg` at `path`.
    fn problem(&mut self, path: impl Into<String>, msg: impl Into<String>) {
        self.problems().push(Problem::new(path, msg));
    }

    /// `v`, or a problem at `path` when it is not finite.
    fn finite(&mut self, path: &str, v: f64) -> Option<f64> {
        let v = finite(self.problems(), path, v)?;
        self.hand(path, v);
        Some(v)
    }

    /// `v`, or a problem at `path` when it is not a finite number above zero.
    fn positive(&mut self, path: &str, v: f64) -> Option<f64> {
        let v = positive(self.problems(), path, v)?;
        self.hand(path, v);
        Some(v)
    }

    /// `v`, or a problem at `path` when it is not a finite number at or above zero.
    fn non_negative(&mut self, path: &str, v: f64) -> Option<f64> {
        let v = self.finite(path, v)?;
        if v < 0.0 {
            self.problem(path, format!("expected a number >= 0, found {v}"));
            return None;
        }
        Some(v)
    }

    /// `[x, y]` at `path`, both finite.
    fn vec2(&mut self, path: &str, v: [f64; 2]) -> Option<[f64; 2]> {
        let a = self.finite(&format!("{path}[0]"), v[0]);
        let b = self.finite(&format!("{path}[1]"), v[1]);
        Some([a?, b?])
    }

    /// A direction at `path`: finite and not zero.
    fn axis(&mut self, path: &str, v: [f64; 2]) -> Option<[f64; 2]> {
        let v = self.vec2(path, v)?;
        // Below 1e-12 the direction is round-off, not a length a drawing gives.
        if v[0].hypot(v[1]) < 1e-12 {
            self.problem(path, "zero-length axis: expected a non-zero direction [x, y]");
            return None;
        }
        Some(v)
    }

    /// The coordinates' index of the moving body `name` at `path`; ground is refused.
    fn moving(&mut self, path: &str, name: &str) -> Option<usize> {
        let b = self.body(path, name)?;
        if b == BodyIx::GROUND {
            self.problem(path, "ground does not move: name a moving body");
            return None;
        }
        b.0
    }

    /// A body and one of its points, both resolved.
    fn body_point(&mut self, path: &str, bfield: &str, body: &str, pfield: &str, p: &PointRef) -> Option<End> {
        let b = self.body(&format!("{path}.{bfield}"), body);
        let s = self.point(&format!("{path}.{pfield}"), body, p);
        Some((b?, s?))
    }

    /// The two ends of an element between two bodies (`body_i`, `point_i`, `body_j`, `point_j`
    /// at `path`), resolved; a problem at `body_j` when both are the same body. An element between
    /// the bodies themselves (a torque, a relative angle) takes their origins.
    fn ends(
        &mut self,
        path: &str,
        body_i: &str,
        point_i: &PointRef,
        body_j: &str,
        point_j: &PointRef,
    ) -> Option<[End; 2]> {
        let a = self.body_point(path, "body_i", body_i, "point_i", point_i);
        let b = self.body_point(path, "body_j", body_j, "point_j", point_j);
        if body_i == body_j {
            let message = format!("a joint needs two different bodies, found '{body_i}' twice");
            self.problem(format!("{path}.body_j"), message);
            return None;
        }
        Some([a?, b?])
    }

    /// A moving body and one of its points (`body`, `point` at `path`), resolved; ground is
    /// refused, as what cannot be `verb` ("constrained", "driven").
    fn moving_point(&mut self, path: &str, body: &str, point: &PointRef, verb: &str) -> Option<End> {
        let (b, s) = self.body_point(path, "body", body, "point", point)?;
        if b == BodyIx::GROUND {
            self.problem(format!("{path}.body"), format!("ground cannot be {verb}; name a moving body"));
            return None;
        }
        Some((b, s))
    }

    /// The distance between two body points in the initial guess, m.
    fn initial_distance(&self, [(i, sp), (j, sq)]: [End; 2]) -> f64 {
        let (p, r) = (Frame::of_slice(i, self.q0()).point(sp), Frame::of_slice(j, self.q0()).point(sq));
        (r[0] - p[0]).hypot(r[1] - p[1])
    }

    /// The two points of a joint at `path` that coincide at the initial position: `point_i` and
    /// `point_j` as given, or both from `at`, the global point, in each body's frame.
    fn placed_points(
        &mut self,
        path: &str,
        bodies: [&str; 2],
        points: [&Option<PointRef>; 2],
        at: &Option<[f64; 2]>,
    ) -> Option<(PointRef, PointRef)> {
        match (at, points) {
            (Some(_), [Some(_), _] | [_, Some(_)]) => {
                self.problem(format!("{path}.at"), "give at (global) or point_i and point_j (body frames), not both");
                None
            }
            (Some(at), _) => {
                let at = self.vec2(&format!("{path}.at"), *at)?;
                // An unknown body is reported where the joint names it (`ends`).
                let [pi, pj] = bodies.map(|b| self.initial_frame(b).map_or([0.0; 2], |f| f.local(at)));
                let field = format!("{path}.at");
                self.place(format!("{path}.point_i"), pi, Placed::Point { body: bodies[0], global: at, field: &field });
                self.place(format!("{path}.point_j"), pj, Placed::Point { body: bodies[1], global: at, field: &field });
                Some((PointRef::Coords(pi), PointRef::Coords(pj)))
            }
            (None, [Some(pi), Some(pj)]) => Some((pi.clone(), pj.clone())),
            (None, [pi, _]) => {
                let field = if pi.is_none() { "point_i" } else { "point_j" };
                self.problem(
                    format!("{path}.{field}"),
                    "missing: give point_i and point_j (body frames), or at: [x, y] (the global point)",
                );
                None
            }
        }
    }

    /// The directions of a joint at `path`, each `(field, body, value)`: as given, or all from
    /// `axis`, the global direction at the initial position, in each body's frame.
    fn placed_axes<const N: usize>(
        &mut self,
        path: &str,
        fields: [(&str, &str, &Option<[f64; 2]>); N],
        axis: &Option<[f64; 2]>,
    ) -> Option<[[f64; 2]; N]> {
        let names = fields.map(|(f, _, _)| f).join(" and ");
        match axis {
            Some(_) if fields.iter().any(|(_, _, v)| v.is_some()) => {
                self.problem(format!("{path}.axis"), format!("give axis (global) or {names} (body frames), not both"));
                None
            }
            Some(a) => {
                let a = self.axis(&format!("{path}.axis"), *a)?;
                // An unknown body is reported where the joint names it.
                let local = fields.map(|(_, b, _)| self.initial_frame(b).map_or(a, |f| f.unrotate(a)));
                let global = format!("{path}.axis");
                for ((field, body, _), v) in fields.iter().zip(&local) {
                    self.place(format!("{path}.{field}"), *v, Placed::Direction { body, global: a, field: &global });
                }
                Some(local)
            }
            None => {
                if let Some((field, _, _)) = fields.iter().find(|(_, _, v)| v.is_none()) {
                    let message =
                        format!("missing: give {names} (body frames), or axis: [x, y] (the global direction)");
                    self.problem(format!("{path}.{field}"), message);
                    return None;
                }
                Some(fields.map(|(_, _, v)| v.unwrap_or_default()))
            }
        }
    }
}
