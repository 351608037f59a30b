//! A model's `tables:`: each entry's points, inline or read from a CSV file, made into a
//! [`Spline`] for `spline(name, x)`.

use super::spec::{SplineMethod, TableColumn, TableSpec};
use crate::error::Problem;
use crate::expr::spline::{Method, Spline};
use std::path::Path;

/// The table at `path` (`tables.<name>`), a file named relative to `folder`; every problem with
/// the path of its field.
pub(super) fn table(path: &str, spec: &TableSpec, folder: &Path) -> Result<Spline, Vec<Problem>> {
    let (x, y) = match (&spec.file, &spec.x, &spec.y) {
        (None, TableColumn::Values(x), TableColumn::Values(y)) => (x.clone(), y.clone()),
        (Some(file), TableColumn::Column(x), TableColumn::Column(y)) => columns(path, &folder.join(file), x, y)?,
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
    Spline::new(x, y, method).map_err(|message| vec![Problem::new(path, message)])
}

/// Columns `x` and `y` of the CSV file `file` (its first row names the columns), as numbers.
fn columns(path: &str, file: &Path, x: &str, y: &str) -> Result<(Vec<f64>, Vec<f64>), Vec<Problem>> {
    let at = |field: &str, message: String| vec![Problem::new(format!("{path}.{field}"), message)];
    let shown = file.display();
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
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(|e| at("file", format!("cannot read '{shown}': {e}")))?;
        // Row 1 is the header: data rows count from 2, as a spreadsheet shows them.
        let number = |field: &str, i: usize, out: &mut Vec<f64>| match record.get(i).map(str::parse::<f64>) {
            Some(Ok(v)) => {
                out.push(v);
                Ok(())
            }
            _ => Err(at(
                field,
                format!("'{shown}' row {}, column '{}': expected a number, found '{}'", row + 2, names[i], {
                    record.get(i).unwrap_or("")
                }),
            )),
        };
        number("x", ix, &mut xs)?;
        number("y", iy, &mut ys)?;
    }
    Ok((xs, ys))
}
