//! The layers of the engine (the module doc of `lib.rs`), checked on the source: every `use`
//! line (`crate::` and `super::` paths) and every `crate::` path in code of every file under
//! `src/` imports only what its module may, and a planted import against the order is found.

use std::path::{Path, PathBuf};

/// The layers in the order of `lib.rs`: a module may import those of earlier layers, not one
/// of its own layer but itself (`constraints` and `forces` are peers).
const LAYERS: [&[&str]; 8] = [
    &["expr"],
    &["element"],
    &["constraints", "forces"],
    &["model"],
    &["system"],
    &["analysis"],
    &["results"],
    &["sweep"],
];

/// Modules below every layer and knowing none: imported from anywhere, importing only each
/// other (errors; a run's progress and stop token; linear algebra, which knows no mechanics).
const BASE: [&str; 3] = ["error", "progress", "linalg"];

/// The one pair of layers whose import goes against the order, and only one way: an analysis
/// writes its `Results`, and `results` imports nothing of `analysis`.
const REVERSED: (&str, &str) = ("analysis", "results");

/// The unit tests' harnesses (`#[cfg(test)] mod testing`, not built into the engine), which
/// share one random generator across peers: not checked.
const HARNESS: &str = "testing.rs";

/// The layer of the top-level module `m`: `Some(None)` for a base module, `None` for a name
/// that is not a module of the crate (a function or type of `lib.rs`, `*`).
fn layer(m: &str) -> Option<Option<usize>> {
    if BASE.contains(&m) {
        return Some(None);
    }
    LAYERS.iter().position(|l| l.contains(&m)).map(Some)
}

/// Whether the top-level module `from` may import the top-level module `to`.
fn allowed(from: &str, to: &str) -> bool {
    if from == to || (from, to) == REVERSED {
        return true;
    }
    if (to, from) == REVERSED {
        return false;
    }
    match (layer(from), layer(to)) {
        (_, None) | (None, _) => true,
        (_, Some(None)) => true,
        (Some(None), Some(Some(_))) => false,
        (Some(Some(a)), Some(Some(b))) => b < a,
    }
}

/// The module path of the source file `relative` (to `src/`): `analysis/dynamic/output.rs` is
/// `[analysis, dynamic, output]`, a `mod.rs` its folder's, `lib.rs` the crate root.
fn module_path(relative: &str) -> Vec<String> {
    let mut parts: Vec<String> = relative.trim_end_matches(".rs").split('/').map(String::from).collect();
    if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
        parts.pop();
    }
    parts
}

/// The code of `line`, without a comment (`//`, `///`, `//!`) after it.
fn code(line: &str) -> &str {
    line.find("//").map_or(line, |k| &line[..k])
}

/// The top-level modules the path `path` (of a `use`, after `use `) names, read from a file of
/// the module `module`; `nested`: the `use` is inside an inline module of the file (a `mod
/// tests`), whose `super` is the file's own module.
fn targets(path: &str, module: &[String], nested: bool) -> Vec<String> {
    let path = path.trim().trim_start_matches("::");
    let (mut base, mut rest): (Vec<String>, &str) = if let Some(rest) = path.strip_prefix("crate::") {
        (Vec::new(), rest)
    } else if path.starts_with("super::") {
        let mut base = module.to_vec();
        if nested {
            base.push("<inline>".into());
        }
        let mut rest = path;
        while let Some(r) = rest.strip_prefix("super::") {
            base.pop();
            rest = r;
        }
        (base, rest)
    } else {
        return Vec::new();
    };
    if !base.is_empty() {
        return vec![base.swap_remove(0)];
    }
    rest = rest.trim();
    // `crate::{a::b, c}`: the first name of each part.
    let parts: Vec<&str> = match rest.strip_prefix('{') {
        Some(inner) => split_top(inner.trim_end_matches('}')),
        None => vec![rest],
    };
    parts
        .iter()
        .filter_map(|p| p.trim().split("::").next())
        .map(|m| m.split_whitespace().next().unwrap_or("").to_string())
        .filter(|m| !m.is_empty())
        .collect()
}

/// `text` split at its commas outside braces.
fn split_top(text: &str) -> Vec<&str> {
    let (mut parts, mut depth, mut start) = (Vec::new(), 0, 0);
    for (k, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&text[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// Each import against the layers in the source `text` of the file `relative` (to `src/`), as
/// `file:line: from -> to`.
fn violations(relative: &str, text: &str) -> Vec<String> {
    let module = module_path(relative);
    let Some(from) = module.first().cloned() else { return Vec::new() };
    if relative.ends_with(HARNESS) {
        return Vec::new();
    }
    let mut found = Vec::new();
    let mut check = |line_no: usize, to: String| {
        if !allowed(&from, &to) {
            found.push(format!("{relative}:{line_no}: {from} -> {to}"));
        }
    };
    let lines: Vec<&str> = text.lines().collect();
    let mut k = 0;
    while k < lines.len() {
        let line = code(lines[k]);
        let trimmed = line.trim_start();
        let statement = trimmed.strip_prefix("pub ").or_else(|| trimmed.strip_prefix("pub(crate) ")).unwrap_or(trimmed);
        if let Some(path) = statement.strip_prefix("use ") {
            // A `use` to its `;`, over as many lines as it takes.
            let (first, mut path) = (k, path.to_string());
            while !path.contains(';') && k + 1 < lines.len() {
                k += 1;
                path.push_str(code(lines[k]));
            }
            let nested = line.len() > trimmed.len();
            for to in targets(path.trim_end_matches(';'), &module, nested) {
                check(first + 1, to);
            }
        } else {
            let mut rest = line;
            while let Some(at) = rest.find("crate::") {
                let after = &rest[at + "crate::".len()..];
                let name: String = after.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
                let whole_word = rest[..at].chars().last().is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '_'));
                if whole_word && !name.is_empty() {
                    check(k + 1, name);
                }
                rest = after;
            }
        }
        k += 1;
    }
    found
}

/// Every `.rs` file under `dir`, with its path relative to `root`.
fn sources(root: &Path, dir: &Path, out: &mut Vec<(String, PathBuf)>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let relative = path.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
            out.push((relative, path));
        }
    }
}

#[test]
fn every_import_of_the_engine_follows_the_layers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    sources(&root, &root, &mut files);
    // Every layer and base module is a folder or file of `src/` (a renamed module would leave
    // its name here unchecked).
    for m in LAYERS.iter().flat_map(|l| l.iter()).chain(&BASE) {
        assert!(
            files.iter().any(|(f, _)| module_path(f).first().map(String::as_str) == Some(m)),
            "no module {m} in src/"
        );
    }
    let found: Vec<String> = files
        .iter()
        .flat_map(|(relative, path)| violations(relative, &std::fs::read_to_string(path).unwrap()))
        .collect();
    assert!(found.is_empty(), "imports against the layers of lib.rs:\n{}", found.join("\n"));
    // The check read imports: the files hold hundreds of them.
    let imports: usize = files
        .iter()
        .map(|(_, p)| {
            std::fs::read_to_string(p).unwrap().lines().filter(|l| l.trim_start().starts_with("use crate::")).count()
        })
        .sum();
    assert!(imports > 100, "only {imports} imports read");
}

#[test]
fn an_import_against_the_layers_is_found() {
    // Below its layer, from a peer, into the base, and by a relative path out of the module.
    let text = "use crate::expr::Expr;\nuse crate::{error::Error, results::Results};\n";
    assert_eq!(violations("model/compile.rs", text), ["model/compile.rs:2: model -> results"]);
    assert_eq!(violations("forces/state_expr.rs", "use crate::constraints::MAX_SLOTS;\n").len(), 1);
    assert_eq!(violations("linalg/dense.rs", "use crate::model::Model;\n").len(), 1);
    assert_eq!(violations("results.rs", "use crate::progress::reached;\n").len(), 0, "progress from anywhere");
    let relative = "use super::super::analysis::Overrides;\n";
    assert_eq!(violations("model/parse.rs", relative), ["model/parse.rs:1: model -> analysis"]);
    assert!(violations("model/spec/x.rs", relative).is_empty(), "model::analysis, inside model");
    // Over lines, in code, not in comments; `super` inside an inline module is the file's.
    let multi =
        "use crate::{\n    expr::Expr,\n    sweep::sweep,\n};\n/// [`crate::sweep`]\nlet x = crate::sweep::run();\n";
    assert_eq!(
        violations("system/mod.rs", multi),
        ["system/mod.rs:1: system -> sweep", "system/mod.rs:6: system -> sweep"]
    );
    assert!(violations("analysis.rs", "mod tests {\n    use super::*;\n}\n").is_empty());
    // The one exception, one way.
    assert!(violations("analysis/run.rs", "use crate::results::Results;\n").is_empty());
    assert_eq!(violations("results/stream.rs", "use crate::analysis::Run;\n").len(), 1);
}
