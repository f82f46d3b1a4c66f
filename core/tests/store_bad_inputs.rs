//! Bad inputs through the real binary: each gives one clear `error:` line, exit code 1, and
//! leaves the database exactly as it was (compared by a full dump).

#![allow(clippy::expect_used)] // tests and their helpers may expect

mod store_common;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use store_common::{BIN, dump_file, fixtures, run, run_ok, shared_instance};

/// A database holding Area One, in a fresh temp dir.
fn seeded_db() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("t.db");
    run_ok(
        &db,
        &[
            "import",
            shared_instance("area-one.json").to_str().expect("utf-8"),
        ],
    );
    (dir, db)
}

/// Asserts exit code 1, nothing on stdout and exactly one stderr line `error: ...` that
/// contains every one of `needles`; returns the line.
fn assert_one_error(out: &std::process::Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "exit code; stderr: {stderr}");
    assert!(
        out.stdout.is_empty(),
        "stdout: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one error line expected: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "{n:?} not in {stderr}");
    }
    lines[0].to_string()
}

#[test]
fn every_bad_building_file_is_refused_and_changes_nothing() {
    let (_dir, db) = seeded_db();
    let before = dump_file(&db);
    let expected = std::fs::read_to_string(fixtures().join("bad/expected.tsv")).expect("tsv");
    let mut listed = Vec::new();
    for line in expected
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let cols: Vec<&str> = line.split('\t').collect();
        let (file, message) = (cols[0], cols[2]);
        listed.push(file.to_string());
        let path = fixtures().join("bad").join(file);
        let out = run(&db, &["import", path.to_str().expect("utf-8")]);
        assert_one_error(&out, &[file, message]);
        // Also with --replace, which must not delete anything on the way to the error.
        let out = run(&db, &["import", "--replace", path.to_str().expect("utf-8")]);
        assert_one_error(&out, &[file, message]);
        assert_eq!(dump_file(&db), before, "{file} changed the database");
    }
    // Every file of the corpus has its expectation.
    let mut files: Vec<String> = std::fs::read_dir(fixtures().join("bad"))
        .expect("bad/")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".json"))
        .collect();
    files.sort();
    listed.sort();
    assert_eq!(files, listed, "bad/*.json and bad/expected.tsv disagree");
}

#[test]
fn duplicate_name_is_one_error_and_replace_works() {
    let (_dir, db) = seeded_db();
    let before = dump_file(&db);
    let a1 = shared_instance("area-one.json");
    let out = run(&db, &["import", a1.to_str().expect("utf-8")]);
    assert_one_error(&out, &["Area One (synthetic)", "already", "--replace"]);
    assert_eq!(dump_file(&db), before);
    let msg = run_ok(&db, &["import", "--replace", a1.to_str().expect("utf-8")]);
    assert!(
        msg.starts_with("replaced building 1 by building 2"),
        "{msg}"
    );
}

/// Writes a syntactically plausible building file of `bytes` bytes.
fn write_huge(path: &Path, bytes: usize) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    let head = r#"{"format":"survey-building/1","name":"Huge","vertices":[{"id":"a","x":0,"y":0}],"edges":[],"dense_survey":["#;
    f.write_all(head.as_bytes()).expect("write");
    let item = r#"{"x":1.0,"y":2.0,"rss":{"ap-01":-60.0,"ap-02":-70.0,"ap-03":-80.0}},"#;
    let chunk = item.repeat(1 << 14);
    let mut written = head.len();
    while written < bytes {
        f.write_all(chunk.as_bytes()).expect("write");
        written += chunk.len();
    }
    f.write_all(br#"{"x":1.0,"y":2.0}]}"#).expect("write");
    f.flush().expect("flush");
}

#[test]
fn a_100_mib_file_is_refused_before_it_is_read() {
    let (dir, db) = seeded_db();
    let before = dump_file(&db);
    let huge = dir.path().join("huge.json");
    write_huge(&huge, 100 << 20);
    assert!(std::fs::metadata(&huge).expect("meta").len() >= 100 << 20);
    let t = std::time::Instant::now();
    let out = run(&db, &["import", huge.to_str().expect("utf-8")]);
    assert_one_error(
        &out,
        &[
            "huge.json",
            "the file is 10",
            "over the import limit of 64 MiB",
        ],
    );
    // Refused by its size, not after parsing 100 MiB.
    assert!(t.elapsed().as_secs_f64() < 5.0);
    assert_eq!(dump_file(&db), before);

    // The same through standard input, where the size is unknown until read: the importer
    // stops after 64 MiB + 1 byte.
    let mut child = Command::new(BIN)
        .arg("--db")
        .arg(&db)
        .args(["import", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let mut stdin = child.stdin.take().expect("stdin");
    let feeder = std::thread::spawn(move || {
        let mut f = std::fs::File::open(&huge).expect("open");
        // The child stops reading at the limit: a broken pipe here is expected.
        let _ = std::io::copy(&mut f, &mut stdin);
    });
    let out = child.wait_with_output().expect("wait");
    feeder.join().expect("feeder");
    assert_one_error(&out, &["<stdin>", "64 MiB"]);
    assert_eq!(dump_file(&db), before);
}

#[test]
fn a_file_that_is_not_sqlite_is_refused_untouched() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("notes.db");
    let content = b"These are my notes, not a database. ".repeat(200);
    std::fs::write(&db, &content).expect("write");
    let a1 = shared_instance("area-one.json");
    for args in [
        vec!["buildings"],
        vec!["import", a1.to_str().expect("utf-8")],
    ] {
        let out = run(&db, &args);
        assert_one_error(
            &out,
            &[db.to_str().expect("utf-8"), "not an SQLite database"],
        );
        assert_eq!(
            std::fs::read(&db).expect("read"),
            content,
            "{args:?} changed the file"
        );
    }
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        vec!["notes.db".to_string()],
        "no -wal/-shm files left behind"
    );
}

#[test]
fn a_database_from_a_newer_version_is_refused_untouched() {
    let (_dir, db) = seeded_db();
    {
        let conn = rusqlite::Connection::open(&db).expect("open");
        conn.pragma_update(None, "user_version", 99).expect("bump");
    }
    let bytes = std::fs::read(&db).expect("read");
    let a2 = shared_instance("area-two.json");
    let up_to = format!("up to {}", trailprint::store::SCHEMA_VERSION);
    for args in [
        vec!["buildings"],
        vec!["import", a2.to_str().expect("utf-8")],
    ] {
        let out = run(&db, &args);
        assert_one_error(
            &out,
            &[
                db.to_str().expect("utf-8"),
                "schema version 99",
                "newer",
                &up_to,
            ],
        );
        assert_eq!(std::fs::read(&db).expect("read"), bytes);
    }
}

/// Whether this process can write into a directory we made read-only (root can).
fn permissions_bind(dir: &Path) -> bool {
    std::fs::write(dir.join("probe"), b"x").is_err()
}

#[test]
fn read_only_locations_give_one_clear_error() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).expect("chmod");
    let a1 = shared_instance("area-one.json");
    let a1 = a1.to_str().expect("utf-8");

    // A location no one can create a file in, root included: under /proc.
    let proc_db = Path::new("/proc/self/trailprint-test/t.db");
    let out = run(proc_db, &["import", a1]);
    assert_one_error(
        &out,
        &["/proc/self/trailprint-test/t.db", "cannot open or create"],
    );

    // The default location under a data directory that cannot be created (its parent is a
    // regular file): the error names the directory.
    let blocker = dir.path().join("not-a-dir");
    std::fs::write(&blocker, b"").expect("write");
    let out = Command::new(BIN)
        .args(["buildings"])
        .env("XDG_DATA_HOME", blocker.join("data"))
        .output()
        .expect("run");
    assert_one_error(&out, &["not-a-dir/data/trailprint"]);

    // A read-only directory holding a read-only database. As root, permissions do not bind
    // root itself, so the command runs as user `nobody` (65534), for whom they do.
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).expect("mkdir");
    let db = ro.join("t.db");
    run_ok(&db, &["import", a1]);
    let before = dump_file(&db);
    std::fs::set_permissions(&db, std::fs::Permissions::from_mode(0o444)).expect("chmod");
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).expect("chmod");
    let as_root = !permissions_bind(&ro);
    let run_limited = |db: &Path, args: &[&str]| {
        let mut cmd = Command::new(BIN);
        cmd.arg("--db").arg(db).args(args);
        if as_root {
            cmd.uid(65534).gid(65534);
        }
        cmd.output().expect("run")
    };
    let out = run_limited(&db, &["import", "--replace", a1]);
    assert_one_error(&out, &[db.to_str().expect("utf-8")]);
    let out = run_limited(&db, &["buildings"]);
    assert_one_error(&out, &[db.to_str().expect("utf-8")]);
    let out = run_limited(&ro.join("new.db"), &["buildings"]);
    assert_one_error(&out, &["new.db", "cannot open or create"]);
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    assert_eq!(dump_file(&db), before);
    assert!(!ro.join("new.db").exists());
}

#[test]
fn usage_errors_exit_with_2_and_missing_buildings_with_1() {
    let (_dir, db) = seeded_db();
    let out = run(&db, &["import"]);
    assert_eq!(out.status.code(), Some(2));
    let out = run(&db, &["export", "No Such Building", "-o", "-"]);
    assert_one_error(&out, &["No Such Building", "Area One (synthetic)"]);
    let out = run(&db, &["import", "/nonexistent/b.json"]);
    assert_one_error(&out, &["/nonexistent/b.json", "No such file"]);
}
