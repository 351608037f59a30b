//! Units of a model file's numbers: `"40 mm"`, `"30 deg"`, `"100 rpm"`, `"0.02 kg m^2"`,
//! `"3e4 N/m"`, converted to SI on reading.
//!
//! One table ([`UNITS`]) gives each unit its factor to SI and its dimension; a compound unit is
//! a product of table units with integer powers, with at most one `/` (everything after it
//! divides). Dimensions count powers of metre, kilogram, second and radian: the radian is kept
//! as a dimension of its own so that an angle written in millimetres, or a length in degrees,
//! is refused. A unit library was considered: `uom` checks dimensions at compile time and has no
//! run-time parser of unit text, which is what a model file needs, so the table stays here.

use std::fmt;

/// Powers of metre, kilogram, second and radian.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dim(pub [i8; 4]);

impl Dim {
    /// A pure number (a ratio, a direction's component, a tolerance).
    pub const NONE: Dim = Dim([0, 0, 0, 0]);
    pub const LENGTH: Dim = Dim([1, 0, 0, 0]);
    pub const MASS: Dim = Dim([0, 1, 0, 0]);
    pub const TIME: Dim = Dim([0, 0, 1, 0]);
    pub const ANGLE: Dim = Dim([0, 0, 0, 1]);
    /// kg m^2.
    pub const INERTIA: Dim = Dim([2, 1, 0, 0]);
    /// m/s.
    pub const VELOCITY: Dim = Dim([1, 0, -1, 0]);
    /// m/s^2.
    pub const ACCELERATION: Dim = Dim([1, 0, -2, 0]);
    /// rad/s.
    pub const ANGULAR_VELOCITY: Dim = Dim([0, 0, -1, 1]);
    /// N/m = kg/s^2.
    pub const STIFFNESS: Dim = Dim([0, 1, -2, 0]);
    /// N s/m = kg/s.
    pub const DAMPING: Dim = Dim([0, 1, -1, 0]);
    /// N m/rad.
    pub const ROTATIONAL_STIFFNESS: Dim = Dim([2, 1, -2, -1]);
    /// N m s/rad.
    pub const ROTATIONAL_DAMPING: Dim = Dim([2, 1, -1, -1]);

    /// `self` times `other^power`; `None` when an exponent leaves the `i8` range.
    fn times(self, other: Dim, power: i8) -> Option<Dim> {
        let mut d = self.0;
        for (a, b) in d.iter_mut().zip(other.0) {
            *a = a.checked_add(b.checked_mul(power)?)?;
        }
        Some(Dim(d))
    }
}

/// Names of the dimensions that fields have, for messages ("'mm' is a length, expected a mass").
const NAMES: &[(Dim, &str)] = &[
    (Dim::NONE, "a pure number"),
    (Dim::LENGTH, "a length"),
    (Dim::MASS, "a mass"),
    (Dim::TIME, "a time"),
    (Dim::ANGLE, "an angle"),
    (Dim::INERTIA, "a moment of inertia"),
    (Dim::VELOCITY, "a velocity"),
    (Dim::ACCELERATION, "an acceleration"),
    (Dim::ANGULAR_VELOCITY, "an angular velocity"),
    (Dim::STIFFNESS, "a stiffness (force per length)"),
    (Dim::DAMPING, "a damping (force per velocity)"),
    (Dim::ROTATIONAL_STIFFNESS, "a rotational stiffness (torque per angle)"),
    (Dim::ROTATIONAL_DAMPING, "a rotational damping (torque per angular velocity)"),
    (Dim([1, 1, -2, 0]), "a force"),
    (Dim([2, 1, -2, 0]), "a torque or an energy"),
];

impl fmt::Display for Dim {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some((_, name)) = NAMES.iter().find(|(d, _)| d == self) {
            return f.write_str(name);
        }
        let parts: Vec<String> = ["m", "kg", "s", "rad"]
            .iter()
            .zip(self.0)
            .filter(|(_, p)| *p != 0)
            .map(|(u, p)| if p == 1 { u.to_string() } else { format!("{u}^{p}") })
            .collect();
        write!(f, "a quantity in {}", parts.join(" "))
    }
}

const L: Dim = Dim::LENGTH;
const M: Dim = Dim::MASS;
const T: Dim = Dim::TIME;
const A: Dim = Dim::ANGLE;
const N: Dim = Dim([1, 1, -2, 0]);
const PI: f64 = std::f64::consts::PI;

/// Every unit a model file may write: its name, its factor to SI and its dimension. Factors are
/// the definitions (the degree is pi/180 rad, the revolution 2 pi rad, `rpm` a revolution a
/// minute). `g` is the gram (standard gravity is written as a number, 9.80665).
pub const UNITS: &[(&str, f64, Dim)] = &[
    ("m", 1.0, L),
    ("mm", 1e-3, L),
    ("cm", 1e-2, L),
    ("km", 1e3, L),
    ("um", 1e-6, L),
    ("kg", 1.0, M),
    ("g", 1e-3, M),
    ("t", 1e3, M),
    ("s", 1.0, T),
    ("ms", 1e-3, T),
    ("min", 60.0, T),
    ("h", 3600.0, T),
    ("rad", 1.0, A),
    ("deg", PI / 180.0, A),
    ("rev", 2.0 * PI, A),
    ("rpm", 2.0 * PI / 60.0, Dim::ANGULAR_VELOCITY),
    ("Hz", 1.0, Dim([0, 0, -1, 0])),
    ("N", 1.0, N),
    ("kN", 1e3, N),
    ("mN", 1e-3, N),
    ("J", 1.0, Dim([2, 1, -2, 0])),
];

/// The factor to SI and the dimension of a unit such as `kg m^2`, `N/m`, `N*m`, `m/s^2`,
/// `N m s/rad`. `Err` says what is wrong.
pub fn unit(text: &str) -> Result<(f64, Dim), String> {
    let (num, den) = match text.split_once('/') {
        Some((n, d)) => (n, Some(d)),
        None => (text, None),
    };
    let mut factor = 1.0;
    let mut dim = Dim::NONE;
    for (part, sign) in [(num, 1i8), (den.unwrap_or(""), -1)] {
        if sign == -1 && den.is_some() && part.trim().is_empty() {
            return Err(format!("unit '{text}' has nothing after '/'"));
        }
        if part.contains('/') {
            return Err(format!("unit '{text}' has more than one '/'; write the divisors after one"));
        }
        for word in part.split(|c: char| c.is_whitespace() || c == '*').filter(|w| !w.is_empty()) {
            let (name, power) = match word.split_once('^') {
                Some((n, p)) => {
                    // Powers beyond 9 make no physical unit; the bound also keeps the sums in i8.
                    let p: i8 = p
                        .parse()
                        .ok()
                        .filter(|p: &i8| (-9..=9).contains(p))
                        .ok_or_else(|| format!("unit '{text}': '{p}' is not a whole power from -9 to 9"))?;
                    (n, p)
                }
                None => (word, 1),
            };
            let Some(&(_, f, d)) = UNITS.iter().find(|(n, _, _)| *n == name) else {
                let known: Vec<&str> = UNITS.iter().map(|(n, _, _)| *n).collect();
                return Err(format!("unknown unit '{name}' (known: {})", known.join(", ")));
            };
            factor *= f.powi(i32::from(power * sign));
            dim = dim
                .times(d, power * sign)
                .ok_or_else(|| format!("unit '{text}': the powers add up beyond any unit"))?;
        }
    }
    Ok((factor, dim))
}

/// A number followed by a unit (`"40 mm"`, `"3e4 N/m"`), in SI with its dimension; `None` when
/// `text` does not start with a number followed by a letter (an expression, or a bare number,
/// which YAML gives as a number anyway).
pub fn quantity(text: &str) -> Option<Result<(f64, Dim), String>> {
    let text = text.trim();
    let end = number_end(text)?;
    let rest = text[end..].trim_start();
    if !rest.starts_with(|c: char| c.is_ascii_alphabetic()) {
        return None;
    }
    let value: f64 = text[..end].parse().ok()?;
    Some(unit(rest).map(|(f, d)| (value * f, d)))
}

/// The end of a leading decimal number (sign, digits, point, exponent), if `text` starts with
/// one.
fn number_end(text: &str) -> Option<usize> {
    let b = text.as_bytes();
    let mut i = usize::from(matches!(b.first(), Some(b'+' | b'-')));
    let start = i;
    while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
        i += 1;
    }
    if i == start {
        return None;
    }
    // An exponent only when digits follow it: "3e4 N" is 3e4 newtons, "3 e" is not a number.
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        let digits = j;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
        }
        if j > digits {
            i = j;
        }
    }
    Some(i)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each unit against its definition written out independently, to round-off.
    #[test]
    fn units_convert_by_their_definitions() {
        let cases: &[(&str, f64, Dim)] = &[
            ("40 mm", 0.040, Dim::LENGTH),
            ("30 deg", PI / 6.0, Dim::ANGLE),
            ("100 rpm", 100.0 * 2.0 * PI / 60.0, Dim::ANGULAR_VELOCITY),
            ("2.5 kg", 2.5, Dim::MASS),
            ("0.02 kg m^2", 0.02, Dim::INERTIA),
            ("1.5 kN", 1500.0, Dim([1, 1, -2, 0])),
            ("20 N m", 20.0, Dim([2, 1, -2, 0])),
            ("20 N*m", 20.0, Dim([2, 1, -2, 0])),
            ("3e4 N/m", 3e4, Dim::STIFFNESS),
            ("3 N/mm", 3000.0, Dim::STIFFNESS),
            ("50 N s/m", 50.0, Dim::DAMPING),
            ("2 N m/rad", 2.0, Dim::ROTATIONAL_STIFFNESS),
            ("0.5 N m s/rad", 0.5, Dim::ROTATIONAL_DAMPING),
            ("120 g mm^2", 120e-3 * 1e-6, Dim::INERTIA),
            ("9.81 m/s^2", 9.81, Dim::ACCELERATION),
            ("1.5 rev", 3.0 * PI, Dim::ANGLE),
            ("-2 mm/s", -2e-3, Dim::VELOCITY),
            ("5 ms", 5e-3, Dim::TIME),
            ("1e-3 km", 1.0, Dim::LENGTH),
        ];
        for &(text, si, dim) in cases {
            let (v, d) = quantity(text).expect("a quantity").unwrap_or_else(|e| panic!("{text}: {e}"));
            assert!((v - si).abs() <= 1e-15 * si.abs(), "{text}: {v} against {si}");
            assert_eq!(d, dim, "{text}");
        }
    }

    #[test]
    fn a_bad_unit_is_named() {
        let e = quantity("3 furlongs").unwrap().unwrap_err();
        assert!(e.contains("unknown unit 'furlongs'") && e.contains("mm"), "{e}");
        assert!(quantity("3 N/").unwrap().unwrap_err().contains("nothing after"));
        assert!(quantity("3 m/s/s").unwrap().unwrap_err().contains("more than one '/'"));
        assert!(quantity("3 m^x").unwrap().unwrap_err().contains("whole power"));
        assert!(quantity("3 m^-128").unwrap().unwrap_err().contains("from -9 to 9"));
        let many = format!("3 {}", vec!["m^9"; 20].join(" "));
        assert!(quantity(&many).unwrap().unwrap_err().contains("beyond any unit"));
    }

    #[test]
    fn expressions_and_numbers_are_not_quantities() {
        for text in ["L/2", "2*L", "L", "3", "3e4", "-0.5", "(2) mm", "pi/2"] {
            assert!(quantity(text).is_none(), "{text}");
        }
    }

    #[test]
    fn dimensions_read_as_words() {
        assert_eq!(Dim::LENGTH.to_string(), "a length");
        assert_eq!(Dim::MASS.to_string(), "a mass");
        assert_eq!(Dim([3, 0, 0, 0]).to_string(), "a quantity in m^3");
    }
}
