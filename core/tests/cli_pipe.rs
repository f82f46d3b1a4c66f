//! The command line tool in a pipeline whose reader stops early (`trailprint ... | head`):
//! it must end as Unix tools do, killed by SIGPIPE, not with a Rust panic message.

#![cfg(unix)]

use std::io::Read;
use std::os::unix::process::ExitStatusExt;
use std::process::{Command, Stdio};

#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    let dir = tempfile::tempdir().expect("tempdir");
    // 5,000 walks give about 400 kB of JSON lines: far more than a pipe buffers, so the
    // tool is still writing when the reader goes away.
    let walks = dir.path().join("walks.txt");
    std::fs::write(&walks, "r0c0,r0c1\n".repeat(5000)).expect("walks");
    let building = format!(
        "{}/tests/fixtures/area-one.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut child = Command::new(env!("CARGO_BIN_EXE_trailprint"))
        .args([
            "utility",
            "--building",
            &building,
            "--kernel",
            "62.58,7.93,4.22",
        ])
        .arg("--walks-file")
        .arg(&walks)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // Read the first line, like `head -1`, then close the pipe.
    let mut stdout = child.stdout.take().expect("stdout");
    let mut first = [0u8; 64];
    let got = stdout.read(&mut first).expect("read");
    assert!(got > 0, "the tool printed nothing");
    drop(stdout);
    let stderr = crate::store_common::read_stderr(&mut child);
    let status = child.wait().expect("wait");
    assert!(!stderr.contains("panicked"), "panicked: {stderr}");
    assert_eq!(
        status.signal(),
        Some(libc::SIGPIPE),
        "status {status:?}, stderr {stderr}"
    );
}
