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

#[test]
fn readme_examples_run_as_written() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("repository root");
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
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
