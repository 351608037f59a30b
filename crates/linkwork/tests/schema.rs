//! The JSON Schema shipped in `docs/model.schema.json` is the one the Rust types generate
//! (`linkwork schema` prints it). Regenerate with `LINKWORK_BLESS=1 cargo test --test schema`.

mod common;

use linkwork::Model;

#[test]
fn shipped_schema_is_current() {
    let path = format!("{}/../../docs/model.schema.json", env!("CARGO_MANIFEST_DIR"));
    let schema = Model::json_schema() + "\n";
    if std::env::var_os("LINKWORK_BLESS").is_some() {
        std::fs::write(&path, &schema).unwrap();
    }
    let shipped = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(shipped == schema, "docs/model.schema.json is stale: run LINKWORK_BLESS=1 cargo test --test schema");
}

/// Every example validates against the schema's required top-level shape and compiles.
#[test]
fn every_example_compiles() {
    let dir = format!("{}/../../examples", env!("CARGO_MANIFEST_DIR"));
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "yaml") {
            Model::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            n += 1;
        }
    }
    assert!(n >= 7);
}
