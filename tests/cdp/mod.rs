//! A minimal Chrome DevTools Protocol client for the browser test, over
//! Chromium's `--remote-debugging-pipe`: commands go in on the browser's
//! fd 3 and replies come out on its fd 4, each a JSON message ended by a
//! NUL byte. It covers what the test needs — open a page, evaluate
//! JavaScript, send mouse events, take a screenshot. (headless_chrome does
//! all this and more, but its generated protocol types took minutes of
//! every clean CI build, for five commands.)

use base64::Engine;
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Write};
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{Receiver, channel};
use std::time::{Duration, Instant};

const TIMEOUT: Duration = Duration::from_secs(30);

/// A headless Chromium with one page attached.
pub struct Chromium {
    child: Child,
    commands: std::fs::File,
    replies: Receiver<Value>,
    next_id: u64,
    session: String,
}

/// A descriptor copied to a number >= 10 (so that placing it at 3 or 4 in
/// the child cannot overwrite the other one), close-on-exec in the parent.
fn high(fd: &impl AsRawFd) -> OwnedFd {
    let copy = unsafe { libc::fcntl(fd.as_raw_fd(), libc::F_DUPFD_CLOEXEC, 10) };
    assert!(copy >= 10, "fcntl: {}", std::io::Error::last_os_error());
    unsafe { OwnedFd::from_raw_fd(copy) }
}

impl Chromium {
    /// Starts `binary` headless with a fresh profile in `profile` and a
    /// page of `width` × `height` CSS pixels.
    pub fn launch(binary: &Path, profile: &Path, (width, height): (u32, u32)) -> Chromium {
        let (browser_reads, commands) = std::io::pipe().unwrap();
        let (replies, browser_writes) = std::io::pipe().unwrap();
        let (r, w) = (high(&browser_reads), high(&browser_writes));
        drop((browser_reads, browser_writes));
        let (rfd, wfd) = (r.as_raw_fd(), w.as_raw_fd());
        let mut command = Command::new(binary);
        command
            .args(["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run"])
            .args(["--disable-background-networking", "--disable-component-update", "--disable-sync"])
            .args(["--hide-scrollbars", "--remote-debugging-pipe"])
            .arg(format!("--user-data-dir={}", profile.display()))
            .arg(format!("--window-size={width},{height}"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null());
        // In the child, between fork and exec: the pipe ends at 3 and 4
        // (dup2 clears close-on-exec on the copies).
        unsafe {
            command.pre_exec(move || {
                if libc::dup2(rfd, 3) < 0 || libc::dup2(wfd, 4) < 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
        let child = command.spawn().unwrap_or_else(|e| panic!("{} does not start: {e}", binary.display()));
        drop((r, w));
        let (send, receive) = channel();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(replies);
            let mut message = Vec::new();
            while reader.read_until(0, &mut message).is_ok_and(|n| n > 0) {
                message.pop();
                let Ok(reply) = serde_json::from_slice::<Value>(&message) else { break };
                if send.send(reply).is_err() {
                    break;
                }
                message.clear();
            }
        });
        let mut browser = Chromium {
            child,
            commands: std::fs::File::from(OwnedFd::from(commands)),
            replies: receive,
            next_id: 0,
            session: String::new(),
        };
        let target = browser.send(false, "Target.createTarget", json!({ "url": "about:blank" }));
        let attached =
            browser.send(false, "Target.attachToTarget", json!({ "targetId": target["targetId"], "flatten": true }));
        browser.session = attached["sessionId"].as_str().expect("a session").to_string();
        browser.call(
            "Emulation.setDeviceMetricsOverride",
            json!({ "width": width, "height": height, "deviceScaleFactor": 1, "mobile": false }),
        );
        browser
    }

    /// Sends one command (to the page's session, or to the browser)
    /// and waits for its reply, passing over events; panics on an error.
    fn send(&mut self, to_page: bool, method: &str, params: Value) -> Value {
        let reply = self.send_for_reply(to_page, method, params);
        assert!(reply["error"].is_null(), "{method}: {}", reply["error"]);
        reply["result"].clone()
    }

    /// The whole reply to one command, an error included.
    fn send_for_reply(&mut self, to_page: bool, method: &str, params: Value) -> Value {
        self.next_id += 1;
        let id = self.next_id;
        let mut message = json!({ "id": id, "method": method, "params": params });
        if to_page {
            message["sessionId"] = json!(self.session);
        }
        let mut bytes = serde_json::to_vec(&message).unwrap();
        bytes.push(0);
        self.commands.write_all(&bytes).unwrap();
        let deadline = Instant::now() + TIMEOUT;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            let reply =
                self.replies.recv_timeout(left).unwrap_or_else(|_| panic!("no reply to {method} in {TIMEOUT:?}"));
            if reply["id"] == id {
                return reply;
            }
        }
    }

    /// A command to the page.
    pub fn call(&mut self, method: &str, params: Value) -> Value {
        self.send(true, method, params)
    }

    /// The value of a JavaScript expression (promises awaited); panics on
    /// an exception.
    pub fn eval(&mut self, expression: &str) -> Value {
        let r = self
            .call("Runtime.evaluate", json!({ "expression": expression, "returnByValue": true, "awaitPromise": true }));
        assert!(r["exceptionDetails"].is_null(), "{expression}: {}", r["exceptionDetails"]);
        r["result"]["value"].clone()
    }

    /// The value of a JavaScript expression, or null where it throws or
    /// the page is being replaced (a reload in progress).
    pub fn eval_while_loading(&mut self, expression: &str) -> Value {
        let params = json!({ "expression": expression, "returnByValue": true, "awaitPromise": true });
        let reply = self.send_for_reply(true, "Runtime.evaluate", params);
        let r = &reply["result"];
        if !reply["error"].is_null() || !r["exceptionDetails"].is_null() {
            Value::Null
        } else {
            r["result"]["value"].clone()
        }
    }

    /// Opens `url` and waits until `ready` (a JavaScript condition) holds.
    pub fn open(&mut self, url: &str, ready: &str) {
        self.call("Page.navigate", json!({ "url": url }));
        let deadline = Instant::now() + TIMEOUT;
        while self.eval(&format!("document.readyState === 'complete' && !!({ready})")) != Value::Bool(true) {
            assert!(Instant::now() < deadline, "{url}: not ready ({ready}) in {TIMEOUT:?}");
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// A mouse event (`mousePressed`, `mouseMoved`, `mouseReleased`) with
    /// the left button, at viewport coordinates, with shift held or not.
    pub fn mouse(&mut self, kind: &str, (x, y): (f64, f64), shift: bool) {
        let buttons = u32::from(kind != "mouseReleased");
        self.call(
            "Input.dispatchMouseEvent",
            json!({ "type": kind, "x": x, "y": y, "button": "left", "buttons": buttons, "clickCount": 1,
                    "modifiers": if shift { 8 } else { 0 } }),
        );
    }

    /// A left click at the centre of the first element matching `selector`.
    pub fn click(&mut self, selector: &str) {
        let centre = self.eval(&format!(
            "(() => {{ const e = document.querySelector({selector:?}); e.scrollIntoView({{ block: 'center' }}); \
             const r = e.getBoundingClientRect(); return [r.left + r.width / 2, r.top + r.height / 2]; }})()"
        ));
        let at = (centre[0].as_f64().unwrap(), centre[1].as_f64().unwrap());
        self.mouse("mouseMoved", at, false);
        self.mouse("mousePressed", at, false);
        self.mouse("mouseReleased", at, false);
    }

    /// The page's viewport as PNG.
    pub fn screenshot(&mut self) -> Vec<u8> {
        let r = self.call("Page.captureScreenshot", json!({ "format": "png" }));
        base64::engine::general_purpose::STANDARD.decode(r["data"].as_str().unwrap()).unwrap()
    }
}

impl Drop for Chromium {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
