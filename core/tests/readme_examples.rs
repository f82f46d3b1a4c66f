//! The README's examples run as written (issue 18): every line of its ```` ```sh ````
//! blocks that starts with `trailprint ` is run, in order, with the binary built for the
//! tests, on a fresh default database (a private `XDG_DATA_HOME`), from a directory where
//! the README's relative paths (`core/tests/fixtures/...`) resolve. Each must succeed, and
//! each `-o FILE` must be written.

#![cfg(unix)]
#![allow(clippy::expect_used)] // tests may expect

use std::path::Path;
use std::process::Command;

use crate::store_common::{BIN, shell_words};

/// The `trailprint ...` lines of the ```` ```sh ```` blocks of `text`, in order.
fn examples(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_sh = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with("```") {
            in_sh = !in_sh && t == "```sh";
            continue;
        }
        if in_sh && let Some(cmd) = t.strip_prefix("trailprint ") {
            out.push(cmd.to_string());
        }
    }
    out
}

/// The repository's root, and its README.
fn root_and_readme() -> (&'static Path, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("repository root");
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    (root, readme)
}

#[test]
fn readme_examples_run_as_written() {
    let (root, readme) = root_and_readme();
    let list = examples(&readme);
    assert!(list.len() >= 15, "the README's examples: {list:?}");
    for cmd in [
        "demo",
        "plans show",
        "render --plan",
        "render --session",
        "render --team",
        "vertices",
    ] {
        assert!(
            list.iter().any(|l| l.starts_with(cmd)),
            "no `trailprint {cmd}` example"
        );
    }

    // A working directory where `core/...` is the repository's, and outputs stay private.
    let dir = tempfile::tempdir().expect("tempdir");
    std::os::unix::fs::symlink(root.join("core"), dir.path().join("core")).expect("symlink");
    let data = dir.path().join("xdg");
    for line in &list {
        let args = shell_words(line);
        let out = Command::new(BIN)
            .args(&args)
            .current_dir(dir.path())
            .env("XDG_DATA_HOME", &data)
            .env("HOME", dir.path())
            .output()
            .expect("run trailprint");
        assert!(
            out.status.success(),
            "README example `trailprint {line}` failed:\n{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        if let Some(i) = args.iter().position(|a| a == "-o") {
            let file = dir.path().join(&args[i + 1]);
            let text = std::fs::read_to_string(&file).expect("output written");
            assert!(text.starts_with("<svg"), "{line}");
            // The plan ids the README names are the ones the commands before made.
            let expect = match args[i + 1].as_str() {
                "office.svg" => "<title>Office</title>",
                "team.svg" => "surveyor 2: plan 4",
                "plan.svg" => "plan 2: b00 -&gt; t29",
                "session.svg" => "session 1 (",
                _ => "<svg",
            };
            assert!(text.contains(expect), "{line}: no {expect:?}");
        }
    }
    // They used the default database, which now holds what the README says.
    assert!(data.join("trailprint/trailprint.db").is_file());
}

/// The backquoted words of `text` that are written like vertex ids (letters, digits and
/// dashes, with a digit; a trailing dash makes it a prefix of ids). Fenced blocks are left
/// out (their fences would upset the pairing of backquotes).
fn id_like(text: &str) -> Vec<String> {
    let prose: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("```"))
        .collect();
    prose
        .join("\n")
        .split('`')
        .skip(1)
        .step_by(2)
        .filter(|w| {
            !w.is_empty()
                && w.chars().all(|c| c.is_ascii_alphanumeric() || c == '-')
                && w.chars().any(|c| c.is_ascii_digit())
        })
        .map(str::to_string)
        .collect()
}

/// Each id-like word of `words` is an id of `b`, or (ending in `-`) starts some of its ids.
fn assert_ids_exist(words: &[String], b: &trailprint::Building, context: &str) {
    assert!(!words.is_empty(), "{context}: no ids named");
    for w in words {
        let found = if w.ends_with('-') {
            b.vertices.iter().any(|v| v.id.starts_with(w.as_str()))
        } else {
            b.vertices.iter().any(|v| v.id == *w)
        };
        assert!(
            found,
            "{context}: the README names `{w}`, not an id of {}",
            b.name
        );
    }
}

/// The vertex ids the README gives, for the bundled buildings (its table) and for an
/// imported floor plan (its floor-plan section), are ids those buildings have, so a
/// newcomer can type them.
#[test]
fn readme_vertex_ids_exist() {
    let (root, readme) = root_and_readme();
    let section = |title: &str| -> String {
        let start = readme.find(title).unwrap_or_else(|| panic!("no {title:?}"));
        let rest = &readme[start + title.len()..];
        rest[..rest.find("\n## ").unwrap_or(rest.len())].to_string()
    };
    // The table: building | file | ids.
    let table = section("## The bundled buildings and their vertex ids");
    let mut rows = 0;
    for row in table
        .lines()
        .filter(|l| l.starts_with("| ") && l.contains(".json`"))
    {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let file = cells[2].split('`').nth(1).expect("a file in backquotes");
        let b = trailprint::Building::from_file(
            serde_json::from_str(&std::fs::read_to_string(root.join(file)).expect(file))
                .expect(file),
            file,
        )
        .expect(file);
        assert_ids_exist(&id_like(cells[3]), &b, cells[1]);
        rows += 1;
    }
    assert_eq!(rows, 3, "the table's rows");
    // The floor-plan section: ids of the office it imports.
    let floor = section("## From a floor plan to a plan");
    let office = trailprint::floorplan::import_path(
        &root.join("core/tests/fixtures/floorplans/office-l.geojson"),
        &trailprint::floorplan::ImportOptions::default(),
    )
    .expect("office imports");
    let b = trailprint::Building::from_file(office.file, "Office").expect("valid");
    let words = id_like(&floor);
    assert!(
        ["-s", "-d", "-e"]
            .iter()
            .all(|k| words.iter().any(|w| w.contains(k))),
        "the floor-plan section explains grid, door and elevator ids: {words:?}"
    );
    assert_ids_exist(&words, &b, "From a floor plan to a plan");
}
