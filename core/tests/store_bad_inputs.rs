//! Bad inputs through the real binary: each gives one clear `error:` line, exit code 1, and
//! leaves the database exactly as it was (compared by a full dump).

#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use store_common::{
    BIN, SIMULATE_DEMO_ROBOT, dump_file, fixtures, run, run_ok, shared_instance, temp_db,
};

/// A database holding Area One, in a fresh temp dir.
fn seeded_db() -> (tempfile::TempDir, PathBuf) {
    let (dir, db) = temp_db();
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

/// Runs `buildings` and `import` of the shared instance `instance` on `db`: each must be
/// refused with one error line naming every one of `needles`, and leave the file's bytes
/// as they were.
fn assert_refused_untouched(db: &Path, instance: &str, needles: &[&str]) {
    let before = std::fs::read(db).expect("read");
    let building = shared_instance(instance);
    for args in [
        vec!["buildings"],
        vec!["import", building.to_str().expect("utf-8")],
    ] {
        let out = run(db, &args);
        assert_one_error(&out, needles);
        assert_eq!(
            std::fs::read(db).expect("read"),
            before,
            "{args:?} changed the file"
        );
    }
}

#[test]
fn a_file_that_is_not_sqlite_is_refused_untouched() {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("notes.db");
    let content = b"These are my notes, not a database. ".repeat(200);
    std::fs::write(&db, &content).expect("write");
    assert_refused_untouched(
        &db,
        "area-one.json",
        &[db.to_str().expect("utf-8"), "not an SQLite database"],
    );
    assert_eq!(std::fs::read(&db).expect("read"), content);
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
    let up_to = format!("up to {}", trailprint::store::SCHEMA_VERSION);
    assert_refused_untouched(
        &db,
        "area-two.json",
        &[
            db.to_str().expect("utf-8"),
            "schema version 99",
            "newer",
            &up_to,
        ],
    );
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
    // What `nobody` runs and reads is copied into this test's own directory (mode 0755):
    // the checkout itself may sit where `nobody` cannot enter (a clone under `mktemp -d`,
    // mode 0700), and then running the binary from there fails with `Permission denied`.
    let bin = dir.path().join("trailprint");
    std::fs::copy(BIN, &bin).expect("copy the binary");
    std::fs::set_permissions(&bin, std::fs::Permissions::from_mode(0o755)).expect("chmod");
    let a1_copy = dir.path().join("area-one.json");
    std::fs::copy(a1, &a1_copy).expect("copy the building");
    std::fs::set_permissions(&a1_copy, std::fs::Permissions::from_mode(0o644)).expect("chmod");
    let a1 = a1_copy.to_str().expect("utf-8");
    // The temporary directory's own ancestors must let `nobody` through; where they do not
    // (TMPDIR inside a private directory), this part cannot apply and is skipped, saying so.
    let reachable = dir
        .path()
        .ancestors()
        .skip(1)
        .all(|d| std::fs::metadata(d).is_ok_and(|m| m.permissions().mode() & 0o001 != 0));
    if as_root && !reachable {
        eprintln!(
            "skipped the read-only database case: user nobody cannot reach {} \
             (a parent directory has no search permission for others)",
            dir.path().display()
        );
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).expect("chmod");
        return;
    }
    let run_limited = |db: &Path, args: &[&str]| {
        let mut cmd = Command::new(&bin);
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

/// The simulate command the issue found writing into damaged databases: it plans (a plan
/// row), then records a session.
fn simulate_args() -> Vec<String> {
    SIMULATE_DEMO_ROBOT.iter().map(|s| s.to_string()).collect()
}

/// Runs every store command of `commands` on `db`; each must fail with one error line
/// holding all of `needles`, and leave the file byte for byte as it was, with no `-wal` or
/// `-shm` file beside it.
fn refused_untouched(db: &Path, needles: &[&str]) {
    refused_untouched_when(db, needles, true);
}

/// [`refused_untouched`]; `reads_too`: `buildings`, which only reads, is refused as well
/// (else it may succeed, and must leave the file untouched too).
fn refused_untouched_when(db: &Path, needles: &[&str], reads_too: bool) {
    let bytes = std::fs::read(db).expect("read");
    let a1 = shared_instance("area-one.json");
    let sim = simulate_args();
    let commands: Vec<Vec<&str>> = vec![
        vec!["buildings"],
        vec!["import", a1.to_str().expect("utf-8")],
        sim.iter().map(String::as_str).collect(),
    ];
    for args in commands {
        let out = run(db, &args);
        if reads_too || args[0] != "buildings" {
            assert_one_error(&out, needles);
        }
        assert!(
            std::fs::read(db).expect("read") == bytes,
            "{args:?} changed the file"
        );
        for ext in ["-wal", "-shm", "-journal"] {
            let mut side = db.as_os_str().to_owned();
            side.push(ext);
            assert!(
                !Path::new(&side).exists(),
                "{args:?} left {}",
                Path::new(&side).display()
            );
        }
    }
}

#[test]
fn another_programs_database_is_refused_byte_for_byte() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Version 0 (the header's user_version) with a table of its own, in the default
    // rollback-journal mode: before issue 14, opening it switched it to WAL and gave it our
    // tables next to its own.
    let db = dir.path().join("notes.db");
    {
        let c = rusqlite::Connection::open(&db).expect("open");
        c.execute_batch(
            "CREATE TABLE notes (id INTEGER PRIMARY KEY, body TEXT);
             INSERT INTO notes (body) VALUES ('buy milk'), ('call Ann');",
        )
        .expect("notes");
    }
    refused_untouched(
        &db,
        &[
            db.to_str().expect("utf-8"),
            "not a trailprint database",
            "\"notes\"",
            "left untouched",
        ],
    );
    // Another program that numbers its own schema (user_version 1, our first version).
    let db = dir.path().join("other.db");
    {
        let c = rusqlite::Connection::open(&db).expect("open");
        c.execute_batch("CREATE TABLE buildings (id INTEGER PRIMARY KEY, address TEXT);")
            .expect("table");
        c.pragma_update(None, "user_version", 1).expect("version");
    }
    refused_untouched(
        &db,
        &[
            db.to_str().expect("utf-8"),
            "schema version 1",
            "damaged or not trailprint's",
        ],
    );
}

#[test]
fn a_database_missing_a_table_is_refused_before_anything_is_written() {
    let (_dir, db) = seeded_db();
    {
        let c = rusqlite::Connection::open(&db).expect("open");
        c.execute_batch("DROP TABLE bundle_imports;").expect("drop");
    }
    refused_untouched(
        &db,
        &[
            db.to_str().expect("utf-8"),
            &format!(
                "schema version {} needs table \"bundle_imports\", which is missing",
                trailprint::store::SCHEMA_VERSION
            ),
        ],
    );
}

#[test]
fn a_database_failing_quick_check_is_refused_before_anything_is_written() {
    let (_dir, db) = seeded_db();
    // Break the b-tree page of a table that planning and sessions never read (the bundle
    // imports, empty here): its page-type byte becomes invalid. The header and the schema
    // still read, so only `PRAGMA quick_check` sees it.
    let (page_size, root): (i64, i64) = {
        let c = rusqlite::Connection::open(&db).expect("open");
        let page_size = c
            .pragma_query_value(None, "page_size", |r| r.get(0))
            .expect("page size");
        let root = c
            .query_row(
                "SELECT rootpage FROM sqlite_master WHERE name = 'bundle_imports'",
                [],
                |r| r.get(0),
            )
            .expect("root page");
        (page_size, root)
    };
    let mut bytes = std::fs::read(&db).expect("read");
    let at = ((root - 1) * page_size) as usize;
    assert!(
        [0x0a, 0x0d].contains(&bytes[at]),
        "a b-tree leaf page, got {:#x}",
        bytes[at]
    );
    bytes[at] = 0xff;
    std::fs::write(&db, &bytes).expect("write");
    // Commands that write are refused; listing (which does not read that page) may run.
    refused_untouched_when(
        &db,
        &[
            db.to_str().expect("utf-8"),
            "corrupt",
            "nothing was written",
        ],
        false,
    );
}

#[test]
fn a_slow_writer_makes_a_second_command_wait_instead_of_failing() {
    let (_dir, db) = seeded_db();
    // Another connection holds the write lock for 7 s, longer than the 5 s the store used
    // to wait: as a 60 MB import does (6.8 s on the reference machine).
    let hold = std::time::Duration::from_secs(7);
    let (locked_tx, locked_rx) = std::sync::mpsc::channel();
    let holder = {
        let db = db.clone();
        std::thread::spawn(move || {
            let mut c = rusqlite::Connection::open(&db).expect("open");
            let tx = c
                .transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)
                .expect("lock");
            tx.execute("UPDATE buildings SET source = source", [])
                .expect("write");
            locked_tx.send(()).expect("send");
            std::thread::sleep(hold);
            tx.commit().expect("commit");
        })
    };
    locked_rx.recv().expect("locked");
    let t = std::time::Instant::now();
    // A command that only reads does not wait for the writer at all (WAL; opening an up to
    // date database takes no write lock).
    let list = run_ok(&db, &["buildings"]);
    assert!(list.contains("Area One"), "{list}");
    assert!(
        t.elapsed() < std::time::Duration::from_secs(3),
        "buildings waited {:?}",
        t.elapsed()
    );
    // A command that writes waits for the lock, then succeeds.
    let a2 = shared_instance("area-two.json");
    let msg = run_ok(&db, &["import", a2.to_str().expect("utf-8")]);
    assert!(msg.starts_with("imported building 2"), "{msg}");
    assert!(
        t.elapsed() >= hold - std::time::Duration::from_secs(1),
        "it cannot have written while the lock was held: {:?}",
        t.elapsed()
    );
    holder.join().expect("holder");
}
