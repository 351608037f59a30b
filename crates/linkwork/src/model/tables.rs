//! A model's `tables:`: each entry's points, inline or read from a CSV file, made into a
//! [`Spline`] for `spline(name, x)`.

use super::spec::{SplineMethod, TableColumn, TableSpec};
use crate::error::Problem;
use crate::expr::spline::{Method, Spline};
use std::path::Path;

/// The largest table file read: 64 MiB, some two million rows of a few columns, far beyond a
/// test rig's or a CAD export's table; anything larger (or a device such as `/dev/zero`) would
/// take the memory rather than be a table.
const MAX_TABLE_BYTES: u64 = 64 << 20;

/// The table at `path` (`tables.<name>`), a file named relative to `folder`; every problem with
/// the path of its field.
pub(super) fn table(path: &str, spec: &TableSpec, folder: &Path) -> Result<Spline, Vec<Problem>> {
    // With a file, the file's line of each point, for the messages.
    let (x, y, lines) = match (&spec.file, &spec.x, &spec.y) {
        (None, TableColumn::Values(x), TableColumn::Values(y)) => (x.clone(), y.clone(), None),
        (Some(file), TableColumn::Column(x), TableColumn::Column(y)) => {
            let (x, y, lines) = columns(path, &folder.join(file), x, y)?;
            (x, y, Some((file, lines)))
        }
        (None, _, _) => {
            let problems = [("x", &spec.x), ("y", &spec.y)]
                .into_iter()
                .filter(|(_, c)| matches!(c, TableColumn::Column(_)))
                .map(|(f, _)| {
                    Problem::new(format!("{path}.{f}"), "expected a list of numbers (a column name needs `file:`)")
                })
                .collect();
            return Err(problems);
        }
        (Some(_), _, _) => {
            let problems = [("x", &spec.x), ("y", &spec.y)]
                .into_iter()
                .filter(|(_, c)| matches!(c, TableColumn::Values(_)))
                .map(|(f, _)| Problem::new(format!("{path}.{f}"), "expected the name of a column of the file"))
                .collect();
            return Err(problems);
        }
    };
    let method = match spec.method {
        SplineMethod::NotAKnot => Method::NotAKnot,
        SplineMethod::Periodic => Method::Periodic,
        SplineMethod::Akima => Method::Akima,
    };
    Spline::new(x, y, method).map_err(|e| {
        let at = if e.column.is_empty() { path.to_string() } else { format!("{path}.{}", e.column) };
        let line = match (lines, e.index) {
            (Some((file, lines)), Some(i)) => format!(" ('{file}' line {})", lines[i]),
            _ => String::new(),
        };
        vec![Problem::new(at, format!("{}{line}", e.message))]
    })
}

/// Columns `x` and `y` of the CSV file `file` (its first row names the columns), as numbers, and
/// the file's line of each row.
pub(super) type Columns = (Vec<f64>, Vec<f64>, Vec<u64>);

pub(super) fn columns(path: &str, file: &Path, x: &str, y: &str) -> Result<Columns, Vec<Problem>> {
    let at = |field: &str, message: String| vec![Problem::new(format!("{path}.{field}"), message)];
    let shown = file.display();
    match std::fs::metadata(file) {
        Ok(m) if !m.is_file() => return Err(at("file", format!("'{shown}' is not a file"))),
        Ok(m) if m.len() > MAX_TABLE_BYTES => {
            let message = format!("'{shown}' has {} bytes; a table file may have at most {MAX_TABLE_BYTES}", m.len());
            return Err(at("file", message));
        }
        Ok(_) => {}
        Err(e) => return Err(at("file", format!("cannot read '{shown}': {e}"))),
    }
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(file)
        .map_err(|e| at("file", format!("cannot read '{shown}': {e}")))?;
    let headers = reader.headers().map_err(|e| at("file", format!("cannot read '{shown}': {e}")))?.clone();
    let names: Vec<&str> = headers.iter().collect();
    let index = |field: &str, name: &str| {
        names
            .iter()
            .position(|n| *n == name)
            .ok_or_else(|| at(field, format!("'{shown}' has no column '{name}'; its columns are {}", names.join(", "))))
    };
    let (ix, iy) = (index("x", x)?, index("y", y)?);
    let (mut xs, mut ys, mut lines) = (Vec::new(), Vec::new(), Vec::new());
    for record in reader.records() {
        let record = record.map_err(|e| at("file", format!("cannot read '{shown}': {e}")))?;
        let line = record.position().map_or(0, csv::Position::line);
        let number = |field: &str, i: usize, out: &mut Vec<f64>| match record.get(i).map(str::parse::<f64>) {
            Some(Ok(v)) => {
                out.push(v);
                Ok(())
            }
            _ => Err(at(
                field,
                format!("'{shown}' line {line}, column '{}': expected a number, found '{}'", names[i], {
                    record.get(i).unwrap_or("")
                }),
            )),
        };
        number("x", ix, &mut xs)?;
        number("y", iy, &mut ys)?;
        lines.push(line);
    }
    Ok((xs, ys, lines))
}
