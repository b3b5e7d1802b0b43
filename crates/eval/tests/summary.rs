//! What a user of `compare` sees when its output goes to a pipe (as in CI): the
//! summary defines `m`, `p95` and `S`, names the best technique of every
//! configuration and points at `index.html`; progress is one line per finished
//! configuration on stderr; a mesh given with `--mesh` keeps its file name.

use std::path::Path;
use std::process::Command;

const COMPARE: &str = env!("CARGO_BIN_EXE_compare");

/// A ground quad with a box on it.
const OBJ: &str = "v -10 0 -10\nv 10 0 -10\nv 10 0 10\nv -10 0 10\n\
v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n\
f 1 3 2\nf 1 4 3\n\
f 9 10 11\nf 9 11 12\nf 5 6 10\nf 5 10 9\nf 6 7 11\nf 6 11 10\n\
f 7 8 12\nf 7 12 11\nf 8 5 9\nf 8 9 12\n";

#[test]
fn piped_run_explains_itself_and_shows_progress() {
    let dir = std::env::temp_dir().join(format!("shadowmap-summary-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("my scene.obj");
    std::fs::write(&mesh, OBJ).unwrap();
    let out_dir = dir.join("out");
    let out = Command::new(COMPARE)
        .args(["--quick", "--mesh"])
        .arg(&mesh)
        .arg("--out")
        .arg(&out_dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");

    // The summary: one line per measure, the best per configuration, the page.
    for prefix in [
        "m    aliasing error",
        "p95  the 95th percentile",
        "S    storage factor",
    ] {
        assert!(
            stdout.lines().any(|l| l.starts_with(prefix)),
            "no line {prefix:?} in\n{stdout}"
        );
    }
    let best: Vec<&str> = stdout
        .split("best (lowest p95 m) per configuration:\n")
        .nth(1)
        .expect("a best-technique list")
        .lines()
        .take_while(|l| l.starts_with("  "))
        .collect();
    let index = out_dir.join("index.html");
    assert!(stdout.contains(&index.display().to_string()), "{stdout}");

    // Progress: one line per configuration, each configuration once.
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("compare: configuration "))
        .collect();
    assert_eq!(lines.len(), best.len(), "{stderr}");
    let total = lines.len();
    for k in 1..=total {
        assert!(
            lines
                .iter()
                .any(|l| l.contains(&format!(" {k}/{total}: ")) && l.contains(" done ")),
            "no line for configuration {k}/{total}:\n{stderr}"
        );
    }

    // The mesh keeps its name: the configuration is named after the file (made
    // safe for file names), the scene is the file's stem.
    let name = "mesh_my_scene";
    assert!(
        best.iter().any(|l| l.trim_start().starts_with(name)),
        "{best:?}"
    );
    assert!(lines.iter().any(|l| l.contains(&format!(": {name} done"))));
    let csv = std::fs::read_to_string(out_dir.join("metrics.csv")).unwrap();
    assert!(csv.lines().any(|l| l.starts_with(&format!("{name},"))));
    let html = std::fs::read_to_string(&index).unwrap();
    assert!(html.contains(&format!("<section id=\"{name}\">")));
    assert!(html.contains("Scene <code>my scene</code>"));
    assert!(Path::new(&out_dir.join(format!("aliasing_{name}.svg"))).is_file());
    let _ = std::fs::remove_dir_all(&dir);
}
