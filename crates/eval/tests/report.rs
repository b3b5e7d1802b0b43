//! The report is reproducible: two `--quick` runs with the same seed write
//! byte-identical CSV, every listed file exists, and the PNGs decode.

use std::path::{Path, PathBuf};

use shadowmap_eval::report::{self, Options};
use shadowmap_eval::technique::TechniqueKind;

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "shadowmap-eval-report-{}-{tag}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn decode_png(path: &Path) -> (u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert!(info.width > 0 && info.height > 0);
    (info.width, info.height)
}

#[test]
fn quick_runs_are_byte_identical_and_complete() {
    let (a, b) = (temp_dir("a"), temp_dir("b"));
    // One run on two threads, one on a single thread: the merge is deterministic.
    let ra = report::run(
        &Options::default()
            .with_quick(true)
            .with_out(&a)
            .with_threads(2),
    )
    .unwrap();
    let rb = report::run(
        &Options::default()
            .with_quick(true)
            .with_out(&b)
            .with_threads(1),
    )
    .unwrap();

    let csv_a = std::fs::read(a.join("metrics.csv")).unwrap();
    let csv_b = std::fs::read(b.join("metrics.csv")).unwrap();
    assert!(csv_a == csv_b, "metrics.csv differs between two runs");
    assert_eq!(ra.files, rb.files);

    // One CSV row per configuration and applicable technique, plus the header.
    let text = String::from_utf8(csv_a).unwrap();
    assert_eq!(text.lines().count(), ra.rows.len() + 1);
    assert!(ra.rows.len() >= 20);
    assert!(!text.contains(&*a.to_string_lossy()), "no paths in the CSV");
    // Every configuration name and every technique of its light appear.
    for c in &ra.configs {
        assert!(text.lines().any(|l| l.starts_with(&format!("{},", c.name))));
    }
    for kind in TechniqueKind::ALL {
        let (rows, references) = if kind.is_reference() {
            (&ra.references, &ra.rows)
        } else {
            (&ra.rows, &ra.references)
        };
        assert!(
            rows.iter().any(|r| r.technique == kind),
            "{} never evaluated",
            kind.name()
        );
        assert!(references.iter().all(|r| r.technique != kind));
    }
    // The references have a CSV of their own, in the same columns; the technique
    // tables do not list them.
    let references = std::fs::read_to_string(a.join("references.csv")).unwrap();
    assert_eq!(references.lines().count(), ra.references.len() + 1);
    assert_eq!(references.lines().next(), text.lines().next());
    assert!(references.contains(",cube_unfocused,") && !text.contains(",cube_unfocused,"));
    // The overhead configuration: every directional technique measured.
    assert!(
        ra.rows
            .iter()
            .filter(|r| r.config == "overhead")
            .all(|r| r.outcome.is_ok())
    );

    let mut pngs = 0;
    for f in &ra.files {
        let path = a.join(f);
        assert!(path.is_file(), "{} listed but missing", f.display());
        if f.extension().is_some_and(|e| e == "png") {
            decode_png(&path);
            pngs += 1;
        }
    }
    assert!(pngs > 2 * ra.configs.len());
    for name in ["report.md", "metrics.csv", "legend.png"] {
        assert!(
            ra.files.iter().any(|f| f == Path::new(name)),
            "{name} missing"
        );
    }
    let md = std::fs::read_to_string(a.join("report.md")).unwrap();
    assert!(md.contains("## overhead") && md.contains("log bound"));

    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn sweep_counts_every_technique_against_its_baseline() {
    use shadowmap_eval::report::TIE_BAND;
    let dir = temp_dir("sweep");
    let r = report::run(
        &Options::default()
            .with_quick(true)
            .with_out(&dir)
            .with_sweep(3),
    )
    .unwrap();
    let sweep = r.sweep.as_ref().expect("a sweep summary");
    // Three cases per scene (directional, spot, point), four scenes.
    assert_eq!(sweep.cases, 12);
    assert_eq!(r.sweep_configs.len(), 12);
    let kinds = |kind: &str| {
        r.sweep_configs
            .iter()
            .filter(|c| c.light_kind == kind)
            .count()
    };
    assert_eq!(
        (kinds("directional"), kinds("spot"), kinds("point")),
        (4, 4, 4)
    );
    for t in &sweep.tallies {
        // Every case of the technique's light is counted once.
        let cases = r
            .rows
            .iter()
            .filter(|row| row.technique == t.technique && row.config.starts_with("random_"))
            .count();
        assert_eq!(t.wins + t.ties + t.losses + t.unmeasured, cases);
        if let Some(w) = &t.worst {
            assert!(w.config.starts_with("random_") && !w.description.is_empty());
            assert!(w.ratio().is_finite() && w.ratio() > 0.0);
            if t.losses > 0 {
                assert!(w.ratio() > TIE_BAND);
            }
        }
    }
    // The baselines are not counted against themselves; the warps are.
    assert!(
        sweep
            .tallies
            .iter()
            .all(|t| t.technique != TechniqueKind::UniformFocused)
    );
    assert!(
        sweep
            .tallies
            .iter()
            .any(|t| t.technique == TechniqueKind::Lispsm)
    );
    assert!(
        sweep
            .tallies
            .iter()
            .any(|t| t.technique == TechniqueKind::IpsmExact)
    );
    // The rows are in the CSV, named by the case; no pictures for them.
    let csv = std::fs::read_to_string(dir.join("metrics.csv")).unwrap();
    assert_eq!(
        csv.lines().filter(|l| l.starts_with("random_")).count(),
        r.rows
            .iter()
            .filter(|row| row.config.starts_with("random_"))
            .count()
    );
    assert!(
        !r.files
            .iter()
            .any(|f| f.to_string_lossy().contains("random_"))
    );
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("## Robustness sweep") && md.contains("| lispsm |"));
    let table = report::summary_table(&r);
    assert!(table.contains("sweep: 12 random cases"));
    assert!(
        !table.lines().any(|l| l.starts_with("random_")),
        "cases not listed one by one"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
