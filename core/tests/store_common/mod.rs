//! Helpers shared by the store tests (`core/tests/store_*.rs`) and the command-line tests
//! (the binary, the demo building and route, reading a child's output).
#![allow(dead_code)] // each test file uses a different subset
#![allow(clippy::expect_used)] // test helpers may expect

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use rusqlite::Connection;
use rusqlite::types::ValueRef;

/// The `trailprint` binary built for these tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_trailprint");

/// A shared instance, from the repository's copy in `core/tests/fixtures` (byte for byte
/// `shared/instances/NAME`), so a checkout anywhere can run the tests.
pub fn shared_instance(name: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures")).join(name)
}

/// The store fixtures directory (`core/tests/fixtures/store`).
pub fn fixtures() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/store")).to_path_buf()
}

/// The demo building file (`core/data/demo-building.json`).
pub const DEMO_BUILDING: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/data/demo-building.json");

/// The demo route the command-line tests plan: from `f0-c00` to `f0-r5-door` within
/// `budget` metres.
pub fn demo_route(budget: &str) -> [&str; 6] {
    [
        "--start",
        "f0-c00",
        "--end",
        "f0-r5-door",
        "--budget",
        budget,
    ]
}

/// A quick robot survey of the demo building (30 m, 0.2 s of planning): one plan, one
/// session and its collected fingerprints when run with `--db`.
pub const SIMULATE_DEMO_ROBOT: [&str; 13] = [
    "simulate",
    "--building",
    DEMO_BUILDING,
    "--start",
    "f0-c00",
    "--end",
    "f0-r5-door",
    "--budget",
    "30",
    "--time-limit",
    "0.2",
    "--surveyor",
    "robot",
];

/// Everything a spawned child wrote to its (piped) stderr, read to the end.
pub fn read_stderr(child: &mut std::process::Child) -> String {
    use std::io::Read as _;
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut stderr)
        .expect("stderr");
    stderr
}

/// Splits a command line into arguments as a shell does for plain words and double
/// quotes (all the README and the tool's printed next steps use).
pub fn shell_words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let (mut quoted, mut any) = (false, false);
    for c in line.chars() {
        match c {
            '"' => {
                quoted = !quoted;
                any = true;
            }
            ' ' if !quoted => {
                if any || !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
                any = false;
            }
            _ => cur.push(c),
        }
    }
    assert!(!quoted, "unbalanced quotes in {line:?}");
    if any || !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// The words of a literal argument list (`"--seed 4 --json"`): for options whose values
/// hold no white space; paths, which may, are passed as separate elements.
pub fn words(line: &str) -> Vec<&str> {
    line.split_whitespace().collect()
}

/// Runs the binary with `args` (no `--db`).
pub fn trailprint(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .output()
        .expect("run trailprint")
}

/// The name of the demo building (`trailprint::synth::DEMO_BUILDING_JSON`).
pub fn demo_name() -> String {
    trailprint::Building::from_json(trailprint::synth::DEMO_BUILDING_JSON, "demo")
        .expect("demo")
        .name
}

/// A temporary directory and the path of a database file in it (not yet created); the
/// directory and all in it go when the guard drops.
pub fn temp_db() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("tempdir");
    let db = dir.path().join("t.db");
    (dir, db)
}

/// [`temp_db`] with the demo building imported by the command line, and the building's
/// name (what `--building` takes).
pub fn demo_db() -> (tempfile::TempDir, PathBuf, String) {
    let (dir, db) = temp_db();
    run_ok(&db, &["import", DEMO_BUILDING]);
    (dir, db, demo_name())
}

/// Runs the binary with `--db db` and `args`.
pub fn run(db: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .arg("--db")
        .arg(db)
        .args(args)
        .output()
        .expect("run trailprint")
}

/// Runs the binary and expects success.
pub fn run_ok(db: &Path, args: &[&str]) -> String {
    let out = run(db, args);
    assert!(
        out.status.success(),
        "trailprint {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// One value as text for dumps: exact for numbers (shortest round-trip form), quoted text.
fn value_text(v: ValueRef<'_>) -> String {
    match v {
        ValueRef::Null => "NULL".into(),
        ValueRef::Integer(i) => i.to_string(),
        ValueRef::Real(f) => format!("{f:?}"),
        ValueRef::Text(t) => format!("'{}'", String::from_utf8_lossy(t).replace('\'', "''")),
        ValueRef::Blob(b) => format!(
            "X'{}'",
            b.iter().map(|x| format!("{x:02X}")).collect::<String>()
        ),
    }
}

/// Tables of the database, by name (SQLite's own `sqlite_*` tables included).
pub fn tables(conn: &Connection) -> Vec<String> {
    let mut st = conn
        .prepare("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name")
        .expect("prepare");
    st.query_map([], |r| r.get(0))
        .expect("query")
        .collect::<Result<_, _>>()
        .expect("rows")
}

/// All rows of a table as SQL value lists, sorted (an order-free comparison).
pub fn rows(conn: &Connection, table: &str) -> Vec<String> {
    let mut st = conn
        .prepare(&format!("SELECT * FROM \"{table}\""))
        .expect("prepare");
    let n = st.column_count();
    let mut out: Vec<String> = st
        .query_map([], |r| {
            Ok((0..n)
                .map(|i| r.get_ref(i).map(value_text))
                .collect::<Result<Vec<_>, _>>()?
                .join(", "))
        })
        .expect("query")
        .collect::<Result<_, _>>()
        .expect("rows");
    out.sort();
    out
}

/// A normalised dump: user_version, the schema, and every row of every table.
pub fn dump(conn: &Connection) -> String {
    let version: i64 = conn
        .pragma_query_value(None, "user_version", |r| r.get(0))
        .expect("user_version");
    let mut out = format!("user_version {version}\n");
    for s in schema(conn) {
        out.push_str(&s);
        out.push('\n');
    }
    for t in tables(conn) {
        for r in rows(conn, &t) {
            out.push_str(&format!("{t}: {r}\n"));
        }
    }
    out
}

/// Dump of a database file, opened read-only.
pub fn dump_file(db: &Path) -> String {
    let conn = Connection::open_with_flags(db, rusqlite::OpenFlags::SQLITE_OPEN_READ_ONLY)
        .expect("open db");
    dump(&conn)
}

/// `sqlite_master` normalised: (type, name, table, SQL with whitespace collapsed), sorted.
pub fn schema(conn: &Connection) -> Vec<String> {
    let mut st = conn
        .prepare("SELECT type, name, tbl_name, coalesce(sql, '') FROM sqlite_master")
        .expect("prepare");
    let mut out: Vec<String> = st
        .query_map([], |r| {
            let sql: String = r.get(3)?;
            Ok(format!(
                "{} {} ON {}: {}",
                r.get::<_, String>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, String>(2)?,
                sql.split_whitespace().collect::<Vec<_>>().join(" ")
            ))
        })
        .expect("query")
        .collect::<Result<_, _>>()
        .expect("rows");
    out.sort();
    out
}

/// `PRAGMA integrity_check` and `PRAGMA foreign_key_check` both clean.
pub fn assert_healthy(conn: &Connection) {
    let ok: String = conn
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .expect("integrity_check");
    assert_eq!(ok, "ok", "integrity_check");
    let mut st = conn.prepare("PRAGMA foreign_key_check").expect("fk check");
    let bad: Vec<String> = st
        .query_map([], |r| r.get::<_, String>(0))
        .expect("fk rows")
        .collect::<Result<_, _>>()
        .expect("fk rows");
    assert!(bad.is_empty(), "foreign key violations in {bad:?}");
}

/// SplitMix64: a tiny seeded generator, enough for picking kill moments.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `lo..hi`.
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.next_u64() % (hi - lo).max(1)
    }
}

/// A generated grid building `side` x `side` (3 m lattice) named `name`, with `dense`
/// dense-survey fingerprints of `aps` readings each; `variant` changes the labels and RSS
/// so that two variants of one name can be told apart.
pub fn grid_building(name: &str, side: usize, dense: usize, aps: usize, variant: u32) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    write!(
        s,
        "{{\"format\":\"survey-building/1\",\"name\":{name:?},\"vertices\":["
    )
    .expect("write");
    for r in 0..side {
        for c in 0..side {
            if r + c > 0 {
                s.push(',');
            }
            write!(
                s,
                "{{\"id\":\"r{r}c{c}\",\"x\":{}.0,\"y\":{}.0,\"label\":\"v{variant}\"}}",
                3 * c,
                3 * r
            )
            .expect("write");
        }
    }
    s.push_str("],\"edges\":[");
    let mut first = true;
    for r in 0..side {
        for c in 0..side {
            for (dr, dc) in [(0, 1), (1, 0)] {
                let (r2, c2) = (r + dr, c + dc);
                if r2 < side && c2 < side {
                    if !first {
                        s.push(',');
                    }
                    first = false;
                    write!(s, "{{\"a\":\"r{r}c{c}\",\"b\":\"r{r2}c{c2}\"}}").expect("write");
                }
            }
        }
    }
    s.push_str("],\"dense_survey\":[");
    let extent = (3 * (side - 1)) as f64;
    for i in 0..dense {
        if i > 0 {
            s.push(',');
        }
        let x = (i as f64 * 0.37) % extent.max(1.0);
        let y = (i as f64 * 0.53) % extent.max(1.0);
        write!(s, "{{\"x\":{x},\"y\":{y},\"rss\":{{").expect("write");
        for a in 0..aps {
            if a > 0 {
                s.push(',');
            }
            let rss = -40.0 - ((i * 7 + a * 13 + variant as usize) % 60) as f64;
            write!(s, "\"ap-{a:02}\":{rss}").expect("write");
        }
        s.push_str("}}");
    }
    s.push_str("]}");
    s
}
