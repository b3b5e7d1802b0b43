//! The `compare` binary on bad input and faults, run on files and directories the
//! tests make: every input problem is a clear non-zero exit before the run starts,
//! a failed write leaves the previous report intact and nothing half-written, and a
//! rerun leaves no stale files.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const COMPARE: &str = env!("CARGO_BIN_EXE_compare");

/// A fresh, empty directory for one test.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("shadowmap-cli-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn compare(args: &[&str]) -> Output {
    Command::new(COMPARE).args(args).output().unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The names in `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A previous report: two files with known contents.
fn previous_report(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("report.md"), "previous report\n").unwrap();
    std::fs::write(dir.join("metrics.csv"), "previous,csv\n").unwrap();
}

fn assert_previous_intact(dir: &Path) {
    assert_eq!(entries(dir), ["metrics.csv", "report.md"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("report.md")).unwrap(),
        "previous report\n"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("metrics.csv")).unwrap(),
        "previous,csv\n"
    );
}

/// Whether file permissions stop this process (they do not for root).
fn permissions_enforced(scratch: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt as _;
    let probe = scratch.join("probe");
    std::fs::create_dir_all(&probe).unwrap();
    std::fs::set_permissions(&probe, std::fs::Permissions::from_mode(0o555)).unwrap();
    let enforced = std::fs::write(probe.join("x"), b"").is_err();
    std::fs::set_permissions(&probe, std::fs::Permissions::from_mode(0o755)).unwrap();
    let _ = std::fs::remove_dir_all(&probe);
    enforced
}

#[test]
fn zero_threads_is_a_usage_error() {
    let dir = scratch("threads");
    let out_dir = dir.join("out");
    let out = compare(&["--quick", "--threads", "0", "--out", s(&out_dir)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--threads"), "{}", stderr(&out));
    assert!(!out_dir.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn out_that_is_a_file_fails_before_the_run() {
    let dir = scratch("file-out");
    let file = dir.join("report");
    std::fs::write(&file, "keep me").unwrap();
    let out = compare(&["--quick", "--out", s(&file)]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains(s(&file)) && err.contains("not a directory"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep me");
    assert_eq!(entries(&dir), ["report"], "nothing else left behind");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn parent_that_cannot_hold_a_directory_fails_before_the_run() {
    let dir = scratch("bad-parent");
    let file = dir.join("plain-file");
    std::fs::write(&file, "x").unwrap();
    let target = file.join("report");
    let out = compare(&["--quick", "--out", s(&target)]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("cannot write") && err.contains(s(&file)),
        "{err}"
    );
    assert_eq!(entries(&dir), ["plain-file"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn directory_of_other_files_is_refused_not_emptied() {
    let dir = scratch("foreign");
    let target = dir.join("out");
    std::fs::create_dir_all(&target).unwrap();
    std::fs::write(target.join("notes.txt"), "mine").unwrap();
    std::fs::write(target.join("report.md"), "mine too").unwrap();
    let out = compare(&["--quick", "--out", s(&target)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("notes.txt"), "{}", stderr(&out));
    assert_eq!(entries(&target), ["notes.txt", "report.md"]);
    assert_eq!(entries(&dir), ["out"], "no staging directory left");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn read_only_locations_fail_before_the_run() {
    use std::os::unix::fs::PermissionsExt as _;
    let dir = scratch("read-only");
    if !permissions_enforced(&dir) {
        // Running as root: modes do not stop writes, so there is nothing to refuse.
        eprintln!("skipped: file permissions are not enforced for this user");
        let _ = std::fs::remove_dir_all(&dir);
        return;
    }
    // A read-only previous report.
    let target = dir.join("out");
    previous_report(&target);
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o555)).unwrap();
    let out = compare(&["--quick", "--out", s(&target)]);
    std::fs::set_permissions(&target, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains(s(&target)), "{}", stderr(&out));
    assert_previous_intact(&target);
    // A read-only parent.
    let parent = dir.join("locked");
    std::fs::create_dir_all(&parent).unwrap();
    std::fs::set_permissions(&parent, std::fs::Permissions::from_mode(0o555)).unwrap();
    let out = compare(&["--quick", "--out", s(&parent.join("out"))]);
    std::fs::set_permissions(&parent, std::fs::Permissions::from_mode(0o755)).unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains(s(&parent)), "{}", stderr(&out));
    assert!(entries(&parent).is_empty());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A write that fails mid-run (here: a file-size limit of one block, which no
/// permission bit can bypass) exits non-zero naming the file, keeps the previous
/// report and leaves no partial output.
#[test]
fn failed_write_keeps_the_previous_report() {
    let dir = scratch("fsize");
    let target = dir.join("out");
    previous_report(&target);
    let out = Command::new("sh")
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 1; exec \"$0\" \"$@\"")
        .arg(COMPARE)
        .args(["--quick", "--out", s(&target)])
        .output()
        .unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot write") && err.contains(".png"),
        "{err}"
    );
    assert_previous_intact(&target);
    assert_eq!(entries(&dir), ["out"], "no staging directory left");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn rerun_replaces_the_report_without_stale_files() {
    let dir = scratch("rerun");
    let target = dir.join("out");
    std::fs::create_dir_all(&target).unwrap();
    // A picture of a configuration that no longer exists, from an earlier run.
    std::fs::write(target.join("heatmap_retired_lispsm.png"), b"old").unwrap();
    let out = compare(&["--quick", "--out", s(&target)]);
    assert!(out.status.success(), "{}", stderr(&out));
    let names = entries(&target);
    assert!(
        !names.iter().any(|n| n.contains("retired")),
        "stale file kept"
    );
    for name in ["report.md", "metrics.csv", "legend.png"] {
        assert!(names.iter().any(|n| n == name), "{name} missing");
    }
    assert!(names.iter().any(|n| n.starts_with("heatmap_overhead_")));
    assert_eq!(entries(&dir), ["out"], "no staging directory left");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn only_measures_the_configurations_named() {
    let dir = scratch("only");
    let target = dir.join("out");
    let out = compare(&[
        "--quick",
        "--only",
        "top_down",
        "--only",
        "facing_spot",
        "--out",
        s(&target),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let csv = std::fs::read_to_string(target.join("metrics.csv")).unwrap();
    let mut configs: Vec<&str> = csv
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next())
        .collect();
    configs.dedup();
    assert_eq!(configs, ["facing_spot", "top_down"]);
    // A name that matches nothing is a usage error, before anything is written.
    let none = dir.join("none");
    let out = compare(&[
        "--quick",
        "--only",
        "no_such_configuration",
        "--out",
        s(&none),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        stderr(&out).contains("no_such_configuration"),
        "{}",
        stderr(&out)
    );
    assert!(!none.exists(), "nothing written");
    let _ = std::fs::remove_dir_all(&dir);
}

// ------------------------------------------------------------- mesh input

fn mesh_error(tag: &str, file: &str, bytes: &[u8]) -> (PathBuf, String) {
    let dir = scratch(tag);
    let mesh = dir.join(file);
    std::fs::write(&mesh, bytes).unwrap();
    let target = dir.join("out");
    let out = compare(&["--quick", "--mesh", s(&mesh), "--out", s(&target)]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains(s(&mesh)), "the message names the file: {err}");
    assert!(!target.exists(), "nothing written for a bad mesh");
    assert_eq!(entries(&dir), [file], "nothing left behind");
    let _ = std::fs::remove_dir_all(&dir);
    (mesh, err)
}

/// One OBJ triangle scaled by `scale`.
fn obj_triangle(scale: f64) -> String {
    format!("v 0 0 0\nv {scale:e} 0 0\nv 0 0 {scale:e}\nf 1 2 3\n")
}

#[test]
fn gltf_position_naming_a_missing_accessor_is_an_error_not_a_panic() {
    let json = r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#;
    let (_, err) = mesh_error("gltf-index", "bad.gltf", json.as_bytes());
    assert!(err.contains("accessor 7"), "{err}");
}

#[test]
fn random_bytes_as_glb_say_it_is_not_a_glb() {
    let bytes: Vec<u8> = (0..200u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    let (_, err) = mesh_error("glb-noise", "noise.glb", &bytes);
    assert!(err.contains("magic"), "{err}");
    assert!(!err.contains("JSON"), "{err}");
}

#[test]
fn binary_obj_names_the_line() {
    let mut bytes = b"v 0 0 0\nv 1 0 0\n".to_vec();
    bytes.extend_from_slice(&[0xff, 0xfe, 0x00, 0x80, b'\n']);
    let (_, err) = mesh_error("obj-binary", "junk.obj", &bytes);
    assert!(err.contains("line 3") && err.contains("UTF-8"), "{err}");
}

#[test]
fn zero_area_mesh_is_an_error() {
    let obj = "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 3 2\n";
    let (_, err) = mesh_error("flat", "line.obj", obj.as_bytes());
    assert!(err.contains("zero area"), "{err}");
}

#[test]
fn huge_meshes_name_the_file_and_the_reason() {
    let (_, err) = mesh_error("huge30", "huge30.obj", obj_triangle(1e30).as_bytes());
    assert!(err.contains("camera") && err.contains("bounds"), "{err}");
    let (_, err) = mesh_error("huge38", "huge38.obj", obj_triangle(1e38).as_bytes());
    assert!(err.contains("f32 range"), "{err}");
    assert!(!err.contains("NaN"), "{err}");
}

#[test]
fn missing_mesh_file_is_an_error_before_the_run() {
    let dir = scratch("no-mesh");
    let mesh = dir.join("absent.obj");
    let target = dir.join("out");
    let out = compare(&["--quick", "--mesh", s(&mesh), "--out", s(&target)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains(s(&mesh)), "{}", stderr(&out));
    assert!(!target.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
