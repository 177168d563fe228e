//! `ctlgraph watch GRAPH [--out FILE.csv] [--plot FILE.svg] [--html FILE.html [--serve PORT]] [--set …]`:
//! runs the graph as `run` does, then again whenever the graph or a file
//! it reads (subsystem files, tables) is saved, until Ctrl-C.
//!
//! Files are polled (size and modification time, four times a second)
//! rather than watched through the platform's notifications: a graph
//! reads a handful of files, and editors that save by writing a new file
//! and renaming it over the old one are then seen as any other save.
//! A browser does not let a page opened from disk watch its own file, so
//! `--serve PORT` serves the HTML report on 127.0.0.1 with a script that
//! reloads it when the watch has run again.

use crate::interrupt;
use crate::run_cmd::{RunOptions, run};
use ctlgraph::suite::Failure;
use ctlgraph_core::Diagnostic;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, SystemTime};

pub(crate) struct Args<'a> {
    pub graph: &'a Path,
    pub out: Option<&'a Path>,
    pub plot: Option<&'a Path>,
    pub html: Option<&'a Path>,
    pub serve: Option<u16>,
    pub sets: &'a [String],
}

/// How often the files are looked at.
const POLL: Duration = Duration::from_millis(250);

/// What a file looked like: its size and modification time (`None`: gone).
type Stamp = Option<(u64, SystemTime)>;

fn stamp(path: &Path) -> Stamp {
    let meta = std::fs::metadata(path).ok()?;
    Some((meta.len(), meta.modified().ok()?))
}

pub(crate) fn watch(a: Args) -> Result<(), Failure> {
    if a.serve.is_some() && a.html.is_none() {
        return Err(Diagnostic::plain("--serve serves the HTML report: give --html FILE.html too").into());
    }
    let stop = interrupt::flag();
    let runs = Arc::new(AtomicU64::new(0));
    if let (Some(port), Some(html)) = (a.serve, a.html) {
        let listener = TcpListener::bind(("127.0.0.1", port))
            .map_err(|e| Failure::Run(format!("--serve {port}: cannot listen on 127.0.0.1:{port}: {e}")))?;
        let at = listener.local_addr().map_err(|e| Failure::Run(e.to_string()))?;
        println!("watch: serving the report at http://{at}/");
        let (html, runs) = (html.to_path_buf(), Arc::clone(&runs));
        std::thread::spawn(move || serve(listener, &html, &runs));
    }
    loop {
        let (result, files) = ctlgraph_core::files::reading(|| {
            let opts = RunOptions {
                out: a.out,
                plot: a.plot,
                stop_time: None,
                report: None,
                html: a.html,
                seed: None,
                max_steps: None,
                max_wall: None,
                accelerate: None,
            };
            run(a.graph, opts, a.sets)
        });
        runs.fetch_add(1, Ordering::Relaxed);
        match result {
            Ok(()) => {}
            Err(Failure::Interrupted(_)) => break,
            Err(Failure::Invalid(d)) => eprintln!("error: {d}"),
            Err(Failure::Run(message)) if message.is_empty() => {}
            Err(Failure::Run(message)) => eprintln!("error: {message}"),
        }
        // The graph itself, even when it could not be read.
        let mut files: Vec<PathBuf> = files;
        if !files.iter().any(|f| f == a.graph) {
            files.insert(0, a.graph.to_path_buf());
        }
        println!("watch: {} file(s) watched; Ctrl-C to stop", files.len());
        let _ = std::io::stdout().flush();
        let before: Vec<Stamp> = files.iter().map(|f| stamp(f)).collect();
        let changed = loop {
            if stop.load(Ordering::Relaxed) {
                break None;
            }
            std::thread::sleep(POLL);
            if let Some(k) = files.iter().zip(&before).position(|(f, s)| stamp(f) != *s) {
                break Some(k);
            }
        };
        let Some(k) = changed else { break };
        // Let the editor finish writing before reading.
        std::thread::sleep(POLL);
        println!("watch: {} changed, running again", files[k].display());
    }
    println!("watch: stopped");
    Ok(())
}

/// The script that reloads the report when `/runs` is no longer `served`,
/// the count of runs when the page was served.
fn reload_script(served: u64) -> String {
    format!(
        "<script>(function(){{setInterval(function(){{fetch('/runs',{{cache:'no-store'}})\
         .then(function(r){{return r.text();}}).then(function(n){{if(n!=='{served}')location.reload();}})\
         .catch(function(){{}});}},500);}})();</script>"
    )
}

/// Answers `GET /` (the report, made to reload itself) and `GET /runs`
/// (how many runs the watch has made) on `listener`, one request at a time.
fn serve(listener: TcpListener, html: &Path, runs: &AtomicU64) {
    for stream in listener.incoming().flatten() {
        let _ = answer(stream, html, runs);
    }
}

fn answer(mut stream: TcpStream, html: &Path, runs: &AtomicU64) -> std::io::Result<()> {
    stream.set_read_timeout(Some(Duration::from_secs(2)))?;
    let mut request = [0u8; 2048];
    let n = stream.read(&mut request)?;
    let line = String::from_utf8_lossy(&request[..n]);
    let target = line.split_whitespace().nth(1).unwrap_or("/");
    let (status, kind, body) = match target {
        "/runs" => ("200 OK", "text/plain", runs.load(Ordering::Relaxed).to_string().into_bytes()),
        "/" | "/index.html" => match std::fs::read_to_string(html) {
            Ok(text) => {
                let script = reload_script(runs.load(Ordering::Relaxed));
                let page = match text.rfind("</body>") {
                    Some(at) => format!("{}{script}{}", &text[..at], &text[at..]),
                    None => format!("{text}{script}"),
                };
                ("200 OK", "text/html; charset=utf-8", page.into_bytes())
            }
            Err(e) => ("503 Service Unavailable", "text/plain", format!("no report yet: {e}").into_bytes()),
        },
        _ => ("404 Not Found", "text/plain", b"not found".to_vec()),
    };
    write!(
        stream,
        "HTTP/1.1 {status}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    stream.write_all(&body)
}
