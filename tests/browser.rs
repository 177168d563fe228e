//! The HTML report in a real browser: Debian's headless Chromium, started
//! by this test and driven over the DevTools protocol (tests/cdp).
//! It opens the report of the FLADRC comparison and checks that the
//! diagram shows every block, that dragging across a plot zooms every
//! linked panel's time axis, that the cursor shows values, that clicking a
//! block shows its parameters as written, and keeps a screenshot in
//! target/test-artifacts/. Chromium is required, not optional (see
//! [`chromium`]); CHROMIUM names another binary.

#![cfg(unix)]

mod cdp;
mod common;
use cdp::Chromium;
use common::{ctlgraph, text};
use serde_json::Value;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

const GRAPH: &str = "graphs/fladrc/compare.yaml";

/// Debian's Chromium (or CHROMIUM): installed with apt-get when missing
/// and this test may (root on a Debian machine), so that `cargo test` on a
/// fresh machine sets up what it needs; otherwise the test fails saying how.
fn chromium() -> PathBuf {
    if let Some(path) = std::env::var_os("CHROMIUM") {
        return PathBuf::from(path);
    }
    let path = PathBuf::from("/usr/bin/chromium");
    let root = std::process::Command::new("id").arg("-u").output().is_ok_and(|o| o.stdout.starts_with(b"0\n"));
    if !path.is_file() && root && Path::new("/usr/bin/apt-get").is_file() {
        eprintln!("the browser test installs Debian's chromium (apt-get install chromium)");
        for args in [&["update", "-qq"][..], &["install", "-y", "-qq", "chromium"]] {
            let status =
                std::process::Command::new("apt-get").args(args).env("DEBIAN_FRONTEND", "noninteractive").status();
            assert!(status.is_ok_and(|s| s.success()), "apt-get {args:?} failed");
        }
    }
    assert!(
        path.is_file(),
        "the browser test needs Chromium at {}: `apt-get install chromium` (Debian), or set CHROMIUM",
        path.display()
    );
    path
}

/// The time view of panel `k`, as the page shows it.
fn view(page: &mut Chromium, k: usize) -> (f64, f64) {
    let v = page.eval(&format!("window.ctlgraphReport.view({k})"));
    (v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

/// Names of the diagram's boxes in one of its two views.
fn boxes(page: &mut Chromium, view: &str) -> BTreeSet<String> {
    let v = page.eval(&format!("[...document.querySelectorAll('#diagram-{view} g.block')].map(g => g.dataset.name)"));
    serde_json::from_value(v).unwrap()
}

#[test]
fn the_report_works_in_a_browser() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("browser");
    std::fs::create_dir_all(&dir).unwrap();
    let report = dir.join("fladrc-compare.html");
    let out = ctlgraph(&["run", GRAPH, "--html", report.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let size = std::fs::metadata(&report).unwrap().len();
    assert!(size < 5 << 20, "the report weighs {size} bytes, over 5 MB");

    let profile = tempfile::tempdir().unwrap();
    let mut page = Chromium::launch(&chromium(), profile.path(), (1400, 1000));
    page.open(&format!("file://{}", report.canonicalize().unwrap().display()), "document.body.dataset.ready");
    // Milliseconds from navigation to plots drawn and handlers attached
    // (reported, not asserted: the machines are shared).
    let ready_ms: f64 = page.eval("document.body.dataset.ready").as_str().unwrap().parse().unwrap();

    // The diagram: every top-level block (subsystems as one box), and
    // expanded every block of the flattened graph, each once.
    let flat = ctlgraph_core::load(Path::new(GRAPH), &[]).unwrap();
    let all: BTreeSet<String> = flat.blocks.iter().map(|b| b.path.clone()).collect();
    let top: BTreeSet<String> = all.iter().map(|p| p.split('/').next().unwrap().to_string()).collect();
    assert_eq!(boxes(&mut page, "collapsed"), top);
    assert_eq!(boxes(&mut page, "expanded"), all);
    page.click("#expand");
    assert_eq!(page.eval("document.getElementById('diagram-expanded').hidden"), Value::Bool(false));
    page.click("#expand");

    // Clicking a block shows its parameters as written.
    page.click("#diagram-collapsed g.block[data-name='d_noise'] rect");
    let shown = page.eval("document.getElementById('block-info').innerText");
    let shown = shown.as_str().unwrap();
    let noise = flat.blocks.iter().find(|b| b.path == "d_noise").unwrap();
    assert!(shown.starts_with("d_noise") && shown.contains("band_limited_white_noise"), "{shown}");
    for (key, _) in noise.spec.params.iter().filter(|(k, _)| k.name != "type") {
        assert!(shown.contains(&key.name), "parameter `{}` not shown: {shown}", key.name);
    }
    assert!(shown.contains("noise_power"), "written as in the file: {shown}");

    // Dragging across the first plot from 25 % to 50 % of its width zooms
    // to that part of the run, on every panel sharing the time axis.
    let rect = page.eval(
        "(() => { const c = document.querySelector('#panel-0 canvas'); c.scrollIntoView(); \
         const r = c.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; })()",
    );
    let r: Vec<f64> = serde_json::from_value(rect).unwrap();
    let (left, width) = (r[0] + 72.0, r[2] - 84.0); // the plot area inside the axes' margins
    let y = r[1] + r[3] / 2.0;
    let before = view(&mut page, 0);
    let at = |f: f64| (left + f * width, y);
    page.mouse("mousePressed", at(0.25), false);
    page.mouse("mouseMoved", at(0.4), false);
    page.mouse("mouseMoved", at(0.5), false);
    page.mouse("mouseReleased", at(0.5), false);
    let after = view(&mut page, 0);
    let span = before.1 - before.0;
    assert!((after.0 - (before.0 + 0.25 * span)).abs() < 0.01 * span, "{before:?} -> {after:?}");
    assert!((after.1 - (before.0 + 0.5 * span)).abs() < 0.01 * span, "{before:?} -> {after:?}");
    assert_eq!(view(&mut page, 1), after, "the second panel's time axis is linked");
    // Shift-drag pans by the distance dragged.
    page.mouse("mousePressed", at(0.5), true);
    page.mouse("mouseMoved", at(0.3), true);
    page.mouse("mouseReleased", at(0.3), true);
    let panned = view(&mut page, 0);
    let zoomed = after.1 - after.0;
    assert!((panned.0 - (after.0 + 0.2 * zoomed)).abs() < 0.01 * zoomed, "{after:?} -> {panned:?}");
    // The cursor shows each signal's value at the time under the mouse.
    page.mouse("mouseMoved", at(0.5), false);
    // (The cursor is drawn at the next animation frame.)
    let values = page.eval(
        "new Promise(done => requestAnimationFrame(() => requestAnimationFrame(() => \
         done([...document.querySelectorAll('#panel-0 .value')].map(v => v.textContent).join(' ')))))",
    );
    assert!(values.as_str().unwrap().matches("= ").count() >= 2, "cursor values: {values}");

    // Clicking a name hides its series.
    page.click("#panel-0 .legend .item");
    assert_eq!(
        page.eval("document.querySelector('#panel-0 .legend .item').classList.contains('off')"),
        Value::Bool(true)
    );

    let artifacts = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/test-artifacts");
    std::fs::create_dir_all(&artifacts).unwrap();
    std::fs::write(artifacts.join("report.png"), page.screenshot()).unwrap();
    println!(
        "report {size} bytes; interactive {ready_ms:.0} ms after navigation; screenshot in {}",
        artifacts.display()
    );

    a_one_sample_spike_survives_the_decimation(&mut page, &dir);
}

/// 100 001 samples on a plot some 1 300 pixels wide, one of them 1 and
/// the rest 0: drawn from min and max per pixel column, the spike reaches
/// the top of the plot at its time, and elsewhere the line stays at 0.
fn a_one_sample_spike_survives_the_decimation(page: &mut Chromium, dir: &Path) {
    let graph = dir.join("spike.yaml");
    std::fs::write(
        &graph,
        "simulation: { stop: 10, solver: { method: rk4, step: 1.0e-4 } }\n\
         blocks:\n  spike: { type: pulse, period: 100, duty: 1.0e-6, delay: 6.12345 }\nrecord: [spike]\n",
    )
    .unwrap();
    let report = dir.join("spike.html");
    let out = ctlgraph(&["run", graph.to_str().unwrap(), "--html", report.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    page.open(&format!("file://{}", report.canonicalize().unwrap().display()), "document.body.dataset.ready");
    // The topmost pixel of the series' colour (#0072b2) in the columns
    // around time `at`, as a fraction of the plot's height from its top.
    let mut topmost = |at: f64| -> f64 {
        let v = page.eval(
            &format!(
                "(() => {{ const c = document.querySelector('#panel-0 canvas'), d = devicePixelRatio || 1; \
                 const [t0, t1] = window.ctlgraphReport.view(0), pw = c.clientWidth - 84, ph = 240 - 40; \
                 const x = Math.round((72 + ({at} - t0) / (t1 - t0) * pw) * d), w = Math.round(4 * d) + 1; \
                 const img = c.getContext('2d').getImageData(x - Math.round(2 * d), Math.round(10 * d), w, Math.round(ph * d)).data; \
                 for (let row = 0; row < Math.round(ph * d); row++) for (let k = 0; k < w; k++) {{ \
                   const i = 4 * (row * w + k); \
                   if (Math.abs(img[i]) < 40 && Math.abs(img[i + 1] - 114) < 40 && Math.abs(img[i + 2] - 178) < 40 && img[i + 3] > 128) \
                     return row / (ph * d); }} \
                 return 1; }})()"
            ),
        );
        v.as_f64().unwrap()
    };
    let at_spike = topmost(6.12345);
    let elsewhere = topmost(3.0);
    assert!(at_spike < 0.1, "the spike reaches {at_spike} of the height from the top");
    assert!(elsewhere > 0.85, "the line elsewhere is at {elsewhere}");
}

/// `ctlgraph watch --html … --serve 0` in the browser: the served report
/// reloads itself when a file the graph reads (here a subsystem file) is
/// saved, showing the new run's numbers; Ctrl-C ends the watch with exit 0.
#[test]
fn the_watched_report_reloads_itself_in_a_browser() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("g.yaml");
    std::fs::write(
        &graph,
        "blocks:\n  u: { type: step }\n  p: { type: subsystem, file: lag.yaml }\nwires:\n  - u -> p\nrecord: [y: p]\n\
         simulation: { stop: 1, solver: { method: rk4, step: 0.01 } }\nchecks:\n  - \"final_value(y) > 1\"\n",
    )
    .unwrap();
    let lag = dir.path().join("lag.yaml");
    let lag_text = |k: u32| {
        format!(
            "blocks:\n  u: {{ type: inport }}\n  g: {{ type: transfer_function, num: [{k}], den: [0.1, 1] }}\n  y: {{ type: outport }}\nwires:\n  - u -> g\n  - g -> y\n"
        )
    };
    std::fs::write(&lag, lag_text(2)).unwrap();
    let mut watch = std::process::Command::new(env!("CARGO_BIN_EXE_ctlgraph"))
        .args(["watch", "g.yaml", "--html", "g.html", "--serve", "0"])
        .current_dir(dir.path())
        .env("CI", "1")
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(watch.stdout.take().unwrap()).lines().map(Result::unwrap);
    let mut wait_for =
        |what: &str| -> String { lines.by_ref().find(|l| l.contains(what)).unwrap_or_else(|| panic!("no `{what}`")) };
    let url = wait_for("serving the report at ").rsplit(' ').next().unwrap().to_string();
    assert!(wait_for("measured").contains("measured 1.99991"));
    wait_for("file(s) watched");

    let profile = tempfile::tempdir().unwrap();
    let mut page = Chromium::launch(&chromium(), profile.path(), (1000, 700));
    page.open(&url, "document.body.dataset.ready");
    // The check's measured value as the report's table prints it (1.999909).
    assert!(page.eval("document.body.innerText").as_str().unwrap().contains("1.99990"));
    // A mark on the page that a reload wipes out.
    page.eval("window.notReloaded = true");
    std::fs::write(&lag, lag_text(4)).unwrap();
    assert!(wait_for("measured").contains("measured 3.99982"));
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    // While the page reloads there is a moment without a body, or without a page to ask.
    let reloaded = "window.notReloaded === undefined && document.readyState === 'complete' && !!(document.body && document.body.dataset.ready)";
    while page.eval_while_loading(reloaded) != Value::Bool(true) {
        assert!(std::time::Instant::now() < deadline, "the page did not reload");
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    assert!(page.eval("document.body.innerText").as_str().unwrap().contains("3.99981"));

    // SAFETY: a signal to the child this test started and still owns.
    unsafe { libc::kill(watch.id() as i32, libc::SIGINT) };
    assert!(wait_for("watch: stopped").contains("stopped"));
    assert!(watch.wait().unwrap().success());
}
