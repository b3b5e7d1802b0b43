//! `index.html` in a real browser: a quick report (with a sweep and a `rendered/`
//! image, so every kind of picture is on the page) is opened from disk in headless
//! Chromium; every `<img>` must have loaded (`naturalWidth > 0`), no error may be
//! reported (failed loads, script errors, `console.error`), and a click on a column
//! header must sort the table. A screenshot of the first screen is saved as
//! `browser/index_first_screen.png` under the test's output directory
//! (`CARGO_TARGET_TMPDIR`).
//!
//! Chromium is found as `$SHADOWMAP_CHROMIUM`, `chromium`, `chromium-browser` or
//! `google-chrome` on `PATH`. Without one the test is skipped with a notice, unless
//! `SHADOWMAP_REQUIRE_BROWSER=1`, which makes a missing browser a failure.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use shadowmap_eval::report::{self, Options};

/// Checks run in the page: error hooks installed before anything loads.
const HOOKS: &str = "<script>window.__errors=[];\
window.addEventListener('error',function(e){var t=e.target;\
window.__errors.push(t&&t!==window&&(t.src||t.href)?'failed to load '+(t.src||t.href)\
:'script error: '+e.message);},true);\
window.addEventListener('unhandledrejection',function(e){window.__errors.push('rejection: '+e.reason);});\
document.addEventListener('securitypolicyviolation',function(e){window.__errors.push('csp: '+e.blockedURI);});\
var ce=console.error;console.error=function(){\
window.__errors.push('console.error: '+Array.prototype.join.call(arguments,' '));\
ce.apply(console,arguments);};</script>";

/// After `load`: the images, the errors and a sort by the first table's `p95 m`
/// column, written into the DOM for `--dump-dom`.
const CHECK: &str = "<script>window.addEventListener('load',function(){\
var bad=[];Array.prototype.forEach.call(document.images,function(i){\
if(!(i.complete&&i.naturalWidth>0)){bad.push(i.getAttribute('src'));}});\
var sorted='no table with a p95 m column';var t=null,k=-1,hs=[];\
Array.prototype.some.call(document.querySelectorAll('table.sortable'),function(x){\
hs=Array.prototype.slice.call(x.tHead.rows[0].cells);\
k=hs.findIndex(function(h){return h.textContent==='p95 m';});t=x;return k>=0;});\
if(t&&k>=0){hs[k].click();\
var v=Array.prototype.map.call(t.tBodies[0].rows,function(r){return r.cells[k].dataset.v;})\
.filter(function(x){return x!=='';}).map(parseFloat);\
sorted=v.length>1&&v.every(function(x,i){return i===0||v[i-1]<=x;})?'yes':'no: '+v.join(' ');}\
var p=document.createElement('pre');p.id='browser-check';\
p.textContent='images='+document.images.length+'\\nbroken='+bad.join(' ')+\
'\\nerrors='+window.__errors.join(' | ')+'\\nsorted='+sorted+'\\n';\
document.body.appendChild(p);});</script>";

fn find_browser() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SHADOWMAP_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .flat_map(|name| std::env::split_paths(&path).map(move |dir| dir.join(name)))
        .find(|p| p.is_file())
}

/// Runs the browser headless on `url` with `args`; its stdout. Killed after a minute.
fn browser(exe: &Path, profile: &Path, args: &[String], url: &str) -> String {
    let mut child = Command::new(exe)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(args)
        .arg(url)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start {}: {e}", exe.display()));
    // Read stdout while waiting: a page larger than the pipe would block it.
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = std::io::Read::read_to_string(&mut stdout, &mut text);
        text
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(90) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{} did not finish in 90 s", exe.display());
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(status.success(), "{} failed: {status:?}", exe.display());
    reader.join().unwrap()
}

/// The value of `key=` in the check block.
fn field<'a>(check: &'a str, key: &str) -> &'a str {
    check
        .lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix('='))
        .unwrap_or_else(|| panic!("no {key} in {check}"))
}

/// A small valid PNG for `rendered/`.
fn write_png(path: &Path) {
    let mut bytes = Vec::new();
    {
        let mut e = png::Encoder::new(&mut bytes, 4, 2);
        e.set_color(png::ColorType::Rgb);
        let mut w = e.write_header().unwrap();
        w.write_image_data(&[200u8; 4 * 2 * 3]).unwrap();
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn index_html_loads_in_a_browser_without_errors() {
    let Some(exe) = find_browser() else {
        assert!(
            std::env::var("SHADOWMAP_REQUIRE_BROWSER").as_deref() != Ok("1"),
            "SHADOWMAP_REQUIRE_BROWSER=1 but no chromium found (install Debian's chromium)"
        );
        eprintln!("skipped: no chromium on PATH (set SHADOWMAP_REQUIRE_BROWSER=1 to require it)");
        return;
    };
    let base = Path::new(env!("CARGO_TARGET_TMPDIR")).join("browser");
    let _ = std::fs::remove_dir_all(&base);
    let out = base.join("report");
    std::fs::create_dir_all(out.join("rendered")).unwrap();
    write_png(&out.join("rendered/uniform.png"));
    let r = report::run(
        &Options::default()
            .with_out(&out)
            .with_quick(true)
            .with_sweep(1),
    )
    .unwrap();
    assert!(r.files.iter().any(|f| f == Path::new("index.html")));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    for needle in [
        "rendered/uniform.png",
        "sweep.svg",
        "colorbar.svg",
        "aliasing_overhead.svg",
    ] {
        assert!(html.contains(needle), "index.html lacks {needle}");
    }
    assert!(
        !html.contains("http://") && !html.contains("https://"),
        "the page must not need the network"
    );

    // The page with the checks, beside it so that relative paths resolve alike.
    let check_page = base.join("report/check.html");
    let instrumented = html.replacen("<head>", &format!("<head>{HOOKS}{CHECK}"), 1);
    assert_ne!(instrumented, html, "no <head> to instrument");
    std::fs::write(&check_page, instrumented).unwrap();
    let url = |p: &Path| format!("file://{}", p.canonicalize().unwrap().display());
    let profile = base.join("profile");
    let dom = browser(
        &exe,
        &profile,
        &["--virtual-time-budget=10000".into(), "--dump-dom".into()],
        &url(&check_page),
    );
    std::fs::remove_file(&check_page).unwrap();
    let check = dom
        .split("<pre id=\"browser-check\">")
        .nth(1)
        .and_then(|s| s.split("</pre>").next())
        .unwrap_or_else(|| panic!("the checks did not run; page:\n{dom:.2000}"));
    let images: usize = field(check, "images").parse().unwrap();
    let expected = html.matches("<img ").count();
    assert!(expected > 10, "only {expected} images on the page");
    assert_eq!(images, expected, "{check}");
    assert_eq!(field(check, "broken"), "", "images that did not load");
    assert_eq!(field(check, "errors"), "", "errors in the page");
    assert_eq!(field(check, "sorted"), "yes", "sorting by p95 m");

    let shot = base.join("index_first_screen.png");
    browser(
        &exe,
        &profile,
        &[
            "--window-size=1280,900".into(),
            format!("--screenshot={}", shot.display()),
        ],
        &url(&out.join("index.html")),
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&shot).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (1280, 900));
    let pixels = &buf[..info.buffer_size()];
    let first = &pixels[..3];
    assert!(
        pixels.chunks(3).any(|p| p != first),
        "the screenshot is blank"
    );
    eprintln!("screenshot: {}", shot.display());
}
