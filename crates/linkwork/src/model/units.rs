//! Units of a model file's numbers: `"40 mm"`, `"30 deg"`, `"100 rpm"`, `"0.02 kg m^2"`,
//! `"3e4 N/m"`, converted to SI on reading.
//!
//! One table ([`UNITS`]) gives each unit its factor to SI and its dimension; a compound unit is
//! a product of table units with integer powers, with at most one `/` (everything after it
//! divides). Dimensions count powers of metre, kilogram, second and radian: the radian is kept
//! as a dimension of its own so that an angle written in millimetres, or a length in degrees,
//! is refused.

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
    /// rad/s^2.
    pub const ANGULAR_ACCELERATION: Dim = Dim([0, 0, -2, 1]);
    /// N = kg m/s^2.
    pub const FORCE: Dim = Dim([1, 1, -2, 0]);
    /// N m, and J: a torque and an energy have the same dimension.
    pub const TORQUE: Dim = Dim([2, 1, -2, 0]);
    /// W = J/s.
    pub const POWER: Dim = Dim([2, 1, -3, 0]);

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
    (Dim::ANGULAR_ACCELERATION, "an angular acceleration"),
    (Dim::FORCE, "a force"),
    (Dim::TORQUE, "a torque or an energy"),
    (Dim::POWER, "a power"),
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
const N: Dim = Dim::FORCE;
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
    ("J", 1.0, Dim::TORQUE),
    ("W", 1.0, Dim::POWER),
    ("kW", 1e3, Dim::POWER),
];

/// The quantities of results, each with its dimension and its SI unit: what a result column
/// holds ([`crate::Model::column_quantity`]) and what a model file's `display:` section may show
/// in other units. A torque and an energy share a dimension and are told apart by the column.
pub const QUANTITIES: &[(&str, Dim, &str)] = &[
    ("length", Dim::LENGTH, "m"),
    ("angle", Dim::ANGLE, "rad"),
    ("time", Dim::TIME, "s"),
    ("velocity", Dim::VELOCITY, "m/s"),
    ("angular_velocity", Dim::ANGULAR_VELOCITY, "rad/s"),
    ("acceleration", Dim::ACCELERATION, "m/s^2"),
    ("angular_acceleration", Dim::ANGULAR_ACCELERATION, "rad/s^2"),
    ("force", Dim::FORCE, "N"),
    ("torque", Dim::TORQUE, "N m"),
    ("energy", Dim::TORQUE, "J"),
    ("power", Dim::POWER, "W"),
    ("mass", Dim::MASS, "kg"),
];

/// Quantities a `display:` section derives from two others when it does not name them: a
/// velocity in the length and time units shown (`mm/s` from `length: mm`), and so on.
const DERIVED: &[(&str, &str, &str)] = &[
    ("velocity", "length", "time"),
    ("angular_velocity", "angle", "time"),
    ("acceleration", "length", "time^2"),
    ("angular_acceleration", "angle", "time^2"),
];

/// The units results are shown in: each of [`QUANTITIES`] with its unit and that unit's factor
/// to SI (a value shown is the SI value divided by the factor). SI unless a model file's
/// `display:` section says otherwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Display {
    /// `(quantity, unit, factor to SI)` in the order of [`QUANTITIES`].
    pub units: Vec<(&'static str, String, f64)>,
}

impl Default for Display {
    fn default() -> Self {
        Display { units: QUANTITIES.iter().map(|&(q, _, si)| (q, si.to_string(), 1.0)).collect() }
    }
}

impl Display {
    /// The units of a `display:` section (a quantity's name to a unit). `Err` lists every entry
    /// that is not a quantity or whose unit cannot be read or is not of the quantity's dimension,
    /// at `display.<quantity>`.
    pub fn read(section: &indexmap::IndexMap<String, String>) -> Result<Display, Vec<crate::error::Problem>> {
        use crate::error::Problem;
        let mut problems = Vec::new();
        let mut display = Display::default();
        for (name, text) in section {
            let path = format!("display.{name}");
            let Some(&(quantity, dim, _)) = QUANTITIES.iter().find(|(q, _, _)| q == name) else {
                let known: Vec<&str> = QUANTITIES.iter().map(|(q, _, _)| *q).collect();
                problems.push(Problem::new(path, format!("unknown quantity; expected one of {}", known.join(", "))));
                continue;
            };
            match unit(text) {
                Ok((factor, d)) if d == dim => display.set(quantity, text.trim(), factor),
                Ok((_, d)) => problems.push(Problem::new(path, format!("'{text}' is {d}, expected {dim}"))),
                Err(e) => problems.push(Problem::new(path, e)),
            }
        }
        // Derived units: `mm/s` read by the same parser as any unit, so its factor is its own.
        for &(quantity, of, per) in DERIVED {
            if section.contains_key(quantity) {
                continue;
            }
            let (top, bottom) = (display.unit(of).to_string(), per.replace("time", display.unit("time")));
            if let Ok((factor, _)) = unit(&format!("{top}/{bottom}")) {
                display.set(quantity, &format!("{top}/{bottom}"), factor);
            }
        }
        if problems.is_empty() {
            Ok(display)
        } else {
            Err(problems)
        }
    }

    /// The unit `quantity` is shown in (one of [`QUANTITIES`]).
    pub fn unit(&self, quantity: &str) -> &str {
        self.units.iter().find(|(q, _, _)| *q == quantity).map_or("", |(_, u, _)| u.as_str())
    }

    /// `si` (a value of `quantity`, SI) as the display shows it, with its unit and six
    /// significant digits: `75.7105 mm`.
    pub fn show(&self, quantity: &str, si: f64) -> String {
        let (unit, factor) =
            self.units.iter().find(|(q, _, _)| *q == quantity).map_or(("", 1.0), |(_, u, f)| (u.as_str(), *f));
        let value = si / factor;
        let magnitude = if value == 0.0 || !value.is_finite() { 0 } else { value.abs().log10().floor() as i32 };
        let decimals = (5 - magnitude).clamp(0, 12) as usize;
        format!("{value:.decimals$} {unit}")
    }

    fn set(&mut self, quantity: &str, text: &str, factor: f64) {
        if let Some(entry) = self.units.iter_mut().find(|(q, _, _)| *q == quantity) {
            entry.1 = text.to_string();
            entry.2 = factor;
        }
    }
}

/// The SI unit of the dimension `dim` (`m` for a length), if results have a quantity of it.
pub fn si_unit(dim: Dim) -> Option<&'static str> {
    QUANTITIES.iter().find(|(_, d, _)| *d == dim).map(|(_, _, u)| *u)
}

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

/// The unit of a number followed by a unit (`mm` of `"40 mm"`), `None` when `text` is not one
/// that reads.
pub fn unit_text(text: &str) -> Option<&str> {
    let text = text.trim();
    let end = number_end(text)?;
    quantity(text)?.ok()?;
    Some(text[end..].trim())
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
    fn a_display_section_sets_units_and_derives_rates() {
        let section: indexmap::IndexMap<String, String> =
            [("length", "mm"), ("angle", "deg"), ("torque", "N mm")].map(|(a, b)| (a.into(), b.into())).into();
        let d = Display::read(&section).unwrap();
        let factor = |q: &str| d.units.iter().find(|u| u.0 == q).unwrap().2;
        assert_eq!((d.unit("length"), factor("length")), ("mm", 1e-3));
        assert_eq!((d.unit("velocity"), d.unit("angular_acceleration")), ("mm/s", "deg/s^2"));
        // Against the definitions: a degree a second is pi/180 rad/s; a N mm is 1e-3 N m.
        assert!((factor("angular_velocity") - PI / 180.0).abs() < 1e-18);
        assert!((factor("torque") - 1e-3).abs() < 1e-18);
        assert_eq!((d.unit("force"), factor("force"), d.unit("time")), ("N", 1.0, "s"));
        assert_eq!(Display::read(&indexmap::IndexMap::new()).unwrap(), Display::default());
        let bad: indexmap::IndexMap<String, String> =
            [("length", "deg"), ("speed", "mm/s"), ("angle", "furlong")].map(|(a, b)| (a.into(), b.into())).into();
        let problems = Display::read(&bad).unwrap_err();
        let said: Vec<(String, String)> = problems.into_iter().map(|p| (p.path, p.message)).collect();
        assert_eq!(said[0], ("display.length".into(), "'deg' is an angle, expected a length".into()));
        assert!(said[1].0 == "display.speed" && said[1].1.contains("expected one of length, angle"), "{said:?}");
        assert!(said[2].0 == "display.angle" && said[2].1.contains("unknown unit 'furlong'"), "{said:?}");
    }

    #[test]
    fn dimensions_read_as_words() {
        assert_eq!(Dim::LENGTH.to_string(), "a length");
        assert_eq!(Dim::MASS.to_string(), "a mass");
        assert_eq!(Dim([3, 0, 0, 0]).to_string(), "a quantity in m^3");
    }
}
