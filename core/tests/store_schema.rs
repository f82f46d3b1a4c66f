//! `schema/building.schema.json` against the shared instances and the importer's fixtures:
//! everything the importer accepts is valid, and the bad corpus is classified as
//! `fixtures/store/bad/expected.tsv` says (the `jsonschema` crate does the validating).

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use serde_json::Value;
use store_common::{fixtures, shared_instance};
use trailprint::Building;

fn schema() -> Value {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../schema/building.schema.json"
    ))
    .expect("schema/building.schema.json");
    serde_json::from_str(&text).expect("the schema is JSON")
}

fn validator() -> jsonschema::Validator {
    let schema = schema();
    jsonschema::meta::validate(&schema).expect("the schema is a valid draft 2020-12 schema");
    jsonschema::validator_for(&schema).expect("compile schema")
}

fn errors(v: &jsonschema::Validator, instance: &Value) -> Vec<String> {
    v.iter_errors(instance)
        .map(|e| format!("{}: {e}", e.instance_path()))
        .collect()
}

#[test]
fn shared_instances_and_good_fixtures_are_valid() {
    let v = validator();
    let mut files = vec![
        shared_instance("area-one.json"),
        shared_instance("area-two.json"),
    ];
    for e in std::fs::read_dir(fixtures().join("good")).expect("good/") {
        files.push(e.expect("entry").path());
    }
    for path in files {
        let text = std::fs::read_to_string(&path).expect("read");
        let instance: Value = serde_json::from_str(&text).expect("json");
        let errs = errors(&v, &instance);
        assert!(errs.is_empty(), "{}: {errs:#?}", path.display());
        // And the importer agrees.
        Building::from_json(&text, &path.display().to_string()).expect("importer accepts it");
    }
}

#[test]
fn exports_are_valid() {
    let v = validator();
    let store = trailprint::Store::open_in_memory().expect("store");
    let path = fixtures().join("good/two_floors.json");
    let text = std::fs::read_to_string(&path).expect("read");
    let id = store
        .import_json(&text, "two_floors", &Default::default())
        .expect("import")
        .id;
    let json = store.export_building(id).expect("export").to_json();
    let instance: Value = serde_json::from_str(&json).expect("json");
    assert!(errors(&v, &instance).is_empty());
}

#[test]
fn bad_fixtures_are_classified_as_expected() {
    let v = validator();
    let expected = std::fs::read_to_string(fixtures().join("bad/expected.tsv")).expect("tsv");
    let mut checked = 0;
    for line in expected
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let mut cols = line.split('\t');
        let (file, class) = (cols.next().expect("file"), cols.next().expect("class"));
        let bytes = std::fs::read(fixtures().join("bad").join(file)).expect("fixture");
        let parsed = std::str::from_utf8(&bytes)
            .ok()
            .and_then(|t| serde_json::from_str::<Value>(t).ok());
        match (class, parsed) {
            ("not-json", None) => {}
            ("not-json", Some(_)) => panic!("{file}: parses as JSON"),
            (_, None) => panic!("{file}: does not parse as JSON"),
            ("invalid", Some(instance)) => {
                assert!(
                    !errors(&v, &instance).is_empty(),
                    "{file}: the schema accepts it"
                );
            }
            ("valid", Some(instance)) => {
                let errs = errors(&v, &instance);
                assert!(errs.is_empty(), "{file}: {errs:#?}");
            }
            (other, _) => panic!("{file}: unknown class {other:?}"),
        }
        checked += 1;
    }
    assert!(checked >= 15, "only {checked} bad fixtures");
}
