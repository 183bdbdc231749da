//! A run stopped by a signal removes the temporary files of its unfinished outputs.

use crate::cli::{assert_error, files_in, scratch, shadelab};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[test]
fn a_terminated_solve_leaves_neither_output_nor_temporary_folder() {
    let d = scratch("interrupt");
    let out = shadelab(&d, &["render", "sphere", "--size", "400", "--out", "s.png"]);
    assert!(out.status.success());
    let before = files_in(&d);
    // Jacobi sweeps to a tolerance they take many seconds to reach: time to stop the run.
    let child = Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(["solve", "s.png", "--mask", "s_mask.png", "--light", "front"])
        .args([
            "--method", "jacobi", "--tol", "1e-12", "--out", "res", "--quiet",
        ])
        .current_dir(&d)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until the output folder is being written (under its temporary name).
    let started = Instant::now();
    while !files_in(&d).iter().any(|n| n.starts_with(".res.tmp-")) {
        assert!(
            started.elapsed() < Duration::from_secs(30),
            "no temporary folder appeared: {:?}",
            files_in(&d)
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    assert_error(&out, 130, "interrupted; the unfinished output was removed");
    assert_eq!(files_in(&d), before);
}
