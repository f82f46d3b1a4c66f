//! The store commands of the command line as a user meets them (issue 14): names from the
//! database printed escaped, `delete` refusing to drop survey data without `--force`, and
//! `-o` outputs that neither replace a device or FIFO nor write through a planted link.

#![cfg(unix)]
#![allow(clippy::expect_used)] // tests and their helpers may expect

use crate::store_common;

use std::path::Path;

use store_common::{
    SIMULATE_DEMO_ROBOT, demo_name, dump_file, read_stderr, run, run_ok, shared_instance, temp_db,
};

/// A simulated survey of the demo building, stored in `db`: one plan, one session and its
/// collected fingerprints.
fn simulate(db: &Path) {
    run_ok(db, &[&SIMULATE_DEMO_ROBOT[..], &["--seed", "3"]].concat());
}

#[test]
fn delete_needs_force_when_survey_data_would_go_and_says_how_much() {
    let (_dir, db) = temp_db();
    simulate(&db);
    let name = demo_name();
    let info = trailprint::Store::open(&db)
        .expect("open")
        .building_info(name.as_str())
        .expect("info");
    assert!(info.plans >= 1 && info.sessions == 1 && info.collected > 0);
    let before = dump_file(&db);
    let out = run(&db, &["delete", &name]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let expected = format!(
        "error: building {} {name:?} has {} plan{}, 1 survey session and {} collected \
         fingerprints: deleting it deletes them too; nothing was deleted",
        info.id,
        info.plans,
        if info.plans == 1 { "" } else { "s" },
        info.collected
    );
    assert!(stderr.starts_with(&expected), "{stderr}");
    assert!(stderr.contains("--force"), "{stderr}");
    assert_eq!(
        dump_file(&db),
        before,
        "a refused delete changed the database"
    );

    let msg = run_ok(&db, &["delete", &name, "--force"]);
    assert!(
        msg.starts_with(&format!("deleted building {} {name:?} with its", info.id)),
        "{msg}"
    );
    assert!(
        msg.contains(&format!(
            "1 session and {} collected fingerprints",
            info.collected
        )),
        "{msg}"
    );
    assert!(run_ok(&db, &["buildings"]).starts_with("no buildings"));

    // A building with no survey data goes without --force.
    let a1 = shared_instance("area-one.json");
    run_ok(&db, &["import", a1.to_str().expect("utf-8")]);
    let msg = run_ok(&db, &["delete", "Area One (synthetic)"]);
    assert!(msg.starts_with("deleted building"), "{msg}");
}

#[test]
fn building_names_are_printed_escaped() {
    let (dir, db) = temp_db();
    // Clear the screen, home the cursor, ring the bell, then a right-to-left override.
    let evil = "\u{1b}[2J\u{1b}[HEvil\u{7} \u{202e}gnp.exe";
    let mut v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(shared_instance("area-one.json")).expect("read"),
    )
    .expect("json");
    v["name"] = evil.into();
    let file = dir.path().join("evil.json");
    std::fs::write(&file, v.to_string()).expect("write");
    run_ok(&db, &["import", file.to_str().expect("utf-8")]);
    let list = run_ok(&db, &["buildings"]);
    assert!(
        !list
            .chars()
            .any(|c| c.is_control() && c != '\n' || c == '\u{202e}'),
        "raw control characters printed: {list:?}"
    );
    assert!(
        list.contains(r"\u{1b}[2J\u{1b}[HEvil\u{7} \u{202e}gnp.exe"),
        "{list}"
    );
    // The JSON listing carries the name itself (JSON escapes it).
    let json = run_ok(&db, &["buildings", "--json"]);
    let parsed: serde_json::Value = serde_json::from_str(&json).expect("json");
    assert_eq!(parsed[0]["name"], evil);
}

#[test]
fn output_into_a_fifo_is_written_into_not_replaced() {
    use std::io::Read;
    use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
    let dir = tempfile::tempdir().expect("tempdir");
    let fifo = dir.path().join("out.fifo");
    let c = std::ffi::CString::new(fifo.to_str().expect("utf-8")).expect("cstring");
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
    // The read end is opened without blocking, so that a writer that replaces the FIFO
    // instead of opening it makes the test fail rather than hang.
    let mut reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .expect("open the fifo");
    let a1 = shared_instance("area-one.json");
    let db = dir.path().join("t.db");
    let mut child = std::process::Command::new(store_common::BIN)
        .arg("--db")
        .arg(&db)
        .args(["export", a1.to_str().expect("utf-8"), "-o"])
        .arg(&fifo)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    let mut text = Vec::new();
    let mut buf = [0u8; 1 << 16];
    let status = loop {
        match reader.read(&mut buf) {
            Ok(n) if n > 0 => text.extend_from_slice(&buf[..n]),
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
            Err(e) => panic!("read the fifo: {e}"),
        }
        if let Some(status) = child.try_wait().expect("wait") {
            // Whatever is still in the pipe.
            while let Ok(n) = reader.read(&mut buf) {
                if n == 0 {
                    break;
                }
                text.extend_from_slice(&buf[..n]);
            }
            break status;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    };
    let stderr = read_stderr(&mut child);
    assert!(status.success(), "{stderr}");
    let text = String::from_utf8(text).expect("utf-8");
    let v: serde_json::Value = serde_json::from_str(&text).expect("the export came through");
    assert_eq!(v["name"], "Area One (synthetic)");
    let meta = std::fs::symlink_metadata(&fifo).expect("meta");
    assert!(meta.file_type().is_fifo(), "the FIFO was replaced");
    // Nothing left beside it.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .expect("dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.ends_with(".tmp")), "{names:?}");
}

#[test]
fn output_is_never_written_through_a_planted_temporary_name() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, b"precious").expect("victim");
    // The old writer used `.out.json.<pid>.tmp` through File::create: plant a link under that
    // name for each of the next few hundred process ids (the child's pid is almost surely
    // among them).
    let last: u32 = std::fs::read_to_string("/proc/sys/kernel/ns_last_pid")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(std::process::id());
    for pid in last + 1..last + 400 {
        std::os::unix::fs::symlink(&victim, dir.path().join(format!(".out.json.{pid}.tmp")))
            .expect("plant");
    }
    let target = dir.path().join("out.json");
    std::fs::write(&target, b"old").expect("old");
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o640)).expect("chmod");
    let a1 = shared_instance("area-one.json");
    let db = dir.path().join("t.db");
    let out = run(
        &db,
        &[
            "export",
            a1.to_str().expect("utf-8"),
            "-o",
            target.to_str().expect("utf-8"),
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let victim_now = std::fs::read(&victim).expect("victim");
    assert!(
        victim_now == b"precious",
        "written through a planted link: the victim now starts {:?}",
        String::from_utf8_lossy(&victim_now[..victim_now.len().min(40)])
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&target).expect("target")).expect("json");
    assert_eq!(v["name"], "Area One (synthetic)");
    // The replaced file keeps its permissions, and no temporary file is left.
    let mode = std::fs::metadata(&target)
        .expect("meta")
        .permissions()
        .mode()
        & 0o777;
    assert_eq!(mode, 0o640);
    let tmps = std::fs::read_dir(dir.path())
        .expect("dir")
        .filter(|e| {
            let e = e.as_ref().expect("entry");
            e.file_name().to_string_lossy().ends_with(".tmp")
                && !e.file_type().expect("type").is_symlink()
        })
        .count();
    assert_eq!(tmps, 0, "a temporary file was left behind");
}
