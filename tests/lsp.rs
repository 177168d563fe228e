//! `ctlgraph lsp` driven over stdio with JSON-RPC, as an editor drives it:
//! initialize, open a graph with a misspelt block type (the diagnostic at
//! its line and column, with the did-you-mean), fix it, hover, complete,
//! go to a definition, list symbols, shut down.

mod common;
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

struct Client {
    child: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
    next_id: i64,
}

impl Client {
    fn start() -> Client {
        let mut child = Command::new(env!("CARGO_BIN_EXE_ctlgraph"))
            .arg("lsp")
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("ctlgraph lsp starts");
        let input = child.stdin.take().unwrap();
        let output = BufReader::new(child.stdout.take().unwrap());
        Client { child, input, output, next_id: 1 }
    }

    fn send(&mut self, message: Value) {
        let body = message.to_string();
        write!(self.input, "Content-Length: {}\r\n\r\n{body}", body.len()).unwrap();
        self.input.flush().unwrap();
    }

    fn receive(&mut self) -> Value {
        let mut length = 0;
        loop {
            let mut header = String::new();
            self.output.read_line(&mut header).unwrap();
            let header = header.trim_end();
            if header.is_empty() {
                break;
            }
            if let Some(n) = header.strip_prefix("Content-Length: ") {
                length = n.parse().unwrap();
            }
        }
        let mut body = vec![0; length];
        self.output.read_exact(&mut body).unwrap();
        serde_json::from_slice(&body).unwrap()
    }

    /// A request's result (notifications that arrive first are skipped).
    fn request(&mut self, method: &str, params: Value) -> Value {
        let id = self.next_id;
        self.next_id += 1;
        self.send(json!({ "jsonrpc": "2.0", "id": id, "method": method, "params": params }));
        loop {
            let m = self.receive();
            if m["id"] == json!(id) {
                assert!(m.get("error").is_none(), "{method}: {m}");
                return m["result"].clone();
            }
        }
    }

    fn notify(&mut self, method: &str, params: Value) {
        self.send(json!({ "jsonrpc": "2.0", "method": method, "params": params }));
    }

    /// The next diagnostics published for `uri`.
    fn diagnostics(&mut self, uri: &str) -> Vec<Value> {
        loop {
            let m = self.receive();
            if m["method"] == "textDocument/publishDiagnostics" && m["params"]["uri"] == uri {
                return m["params"]["diagnostics"].as_array().unwrap().clone();
            }
        }
    }
}

fn uri(path: &std::path::Path) -> String {
    format!("file://{}", path.display())
}

fn at(uri: &str, line: u32, character: u32) -> Value {
    json!({ "textDocument": { "uri": uri }, "position": { "line": line, "character": character } })
}

#[test]
fn an_editor_session() {
    let dir = tempfile::tempdir().unwrap();
    let lib = dir.path().join("lib.yaml");
    std::fs::write(&lib, "blocks:\n  u: { type: inport }\n  k: { type: gain, k: 2 }\n  y: { type: outport }\nwires:\n  - u -> k\n  - k -> y\n").unwrap();
    let graph = dir.path().join("loop.yaml");
    let good = "parameters:\n  kp: 2\nblocks:\n  r: { type: step }\n  ctrl: { type: pid, kp: kp }\n  sub: { type: subsystem, file: lib.yaml }\n  plant: { type: transfer_function, num: [1], den: [1, 1] }\n\
                wires:\n  - r -> ctrl\n  - ctrl -> sub\n  - sub -> plant\n";
    let bad = good.replace("transfer_function", "transfer_fuction");
    std::fs::write(&graph, &bad).unwrap();
    let doc = uri(&graph);

    let mut c = Client::start();
    let init = c.request("initialize", json!({ "processId": null, "rootUri": null, "capabilities": {} }));
    assert_eq!(init["capabilities"]["hoverProvider"], json!(true));
    c.notify("initialized", json!({}));

    // A misspelt type: the diagnostic at line 7, column 18 (0-based 6, 17), as `ctlgraph check` places it.
    c.notify(
        "textDocument/didOpen",
        json!({ "textDocument": { "uri": doc, "languageId": "yaml", "version": 1, "text": bad } }),
    );
    let d = c.diagnostics(&doc);
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(d[0]["range"]["start"], json!({ "line": 6, "character": 17 }), "{d:?}");
    let message = d[0]["message"].as_str().unwrap();
    assert!(
        message.contains("unknown block type `transfer_fuction`")
            && message.contains("did you mean `transfer_function`?"),
        "{message}"
    );

    // Fixed: no diagnostics.
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 2 }, "contentChanges": [{ "text": good }] }),
    );
    assert_eq!(c.diagnostics(&doc), Vec::<Value>::new());

    // Hover on `pid` (line 5, `  ctrl: { type: pid, kp: kp }`): the PID's documentation.
    let h = c.request("textDocument/hover", at(&doc, 4, 18));
    let text = h["contents"]["value"].as_str().unwrap();
    assert!(text.contains("**pid**") && text.contains("PID controller") && text.contains("anti_windup"), "{text}");
    // On the parameter `kp` of the graph: its value.
    let h = c.request("textDocument/hover", at(&doc, 1, 3));
    assert_eq!(h["contents"]["value"], json!("parameter `kp` = 2"));

    // Completion after `type: `: every registered type.
    let edit = good.replace("  r: { type: step }", "  r: { type: }");
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 3 }, "contentChanges": [{ "text": edit }] }),
    );
    let items = c.request("textDocument/completion", at(&doc, 3, 13));
    let labels: Vec<&str> = items.as_array().unwrap().iter().map(|i| i["label"].as_str().unwrap()).collect();
    assert_eq!(labels.len(), ctlgraph::registry().names().count());
    assert!(labels.contains(&"transfer_function") && labels.contains(&"pid"));

    // `ctrl.` in a wire: the PID's output; `sub.` after `->`: the subsystem's inport.
    let edit = good.replace("  - r -> ctrl\n", "  - r -> ctrl\n  - ctrl.\n");
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 4 }, "contentChanges": [{ "text": edit }] }),
    );
    let items = c.request("textDocument/completion", at(&doc, 9, 9));
    assert_eq!(items.as_array().unwrap().iter().map(|i| i["label"].clone()).collect::<Vec<_>>(), vec![json!("u")]);
    let edit = good.replace("  - r -> ctrl\n", "  - r -> ctrl\n  - r -> sub.\n");
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 5 }, "contentChanges": [{ "text": edit }] }),
    );
    let items = c.request("textDocument/completion", at(&doc, 9, 13));
    assert_eq!(items.as_array().unwrap().iter().map(|i| i["label"].clone()).collect::<Vec<_>>(), vec![json!("u")]);

    // A parameter key inside `{ type: pid, … }`: the PID's parameters not yet written.
    let edit = good.replace("{ type: pid, kp: kp }", "{ type: pid, kp: kp, an }");
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 6 }, "contentChanges": [{ "text": edit }] }),
    );
    let items = c.request("textDocument/completion", at(&doc, 4, 31));
    let labels: Vec<&str> = items.as_array().unwrap().iter().map(|i| i["label"].as_str().unwrap()).collect();
    assert!(labels.contains(&"anti_windup") && labels.contains(&"ki") && !labels.contains(&"kp"), "{labels:?}");

    // A value: the graph's parameters; a check: the metrics and loop figures.
    let edit = good.replace("{ type: pid, kp: kp }", "{ type: pid, kp: kp, ki: k }");
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 7 }, "contentChanges": [{ "text": edit }] }),
    );
    let items = c.request("textDocument/completion", at(&doc, 4, 34));
    assert_eq!(items.as_array().unwrap().iter().map(|i| i["label"].clone()).collect::<Vec<_>>(), vec![json!("kp")]);
    let edit = format!("{good}checks:\n  - \"s\n");
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 8 }, "contentChanges": [{ "text": edit }] }),
    );
    let items = c.request("textDocument/completion", at(&doc, 12, 6));
    let labels: Vec<&str> = items.as_array().unwrap().iter().map(|i| i["label"].as_str().unwrap()).collect();
    assert!(labels.contains(&"settling_time") && labels.contains(&"phase_margin"), "{labels:?}");

    // Definition: the subsystem's `file:` opens that file; a block in a wire goes to its line.
    c.notify(
        "textDocument/didChange",
        json!({ "textDocument": { "uri": doc, "version": 7 }, "contentChanges": [{ "text": good }] }),
    );
    let d = c.request("textDocument/definition", at(&doc, 5, 38));
    assert_eq!(d["uri"], json!(uri(&lib.canonicalize().unwrap())));
    let d = c.request("textDocument/definition", at(&doc, 8, 10));
    assert_eq!(d["range"]["start"], json!({ "line": 4, "character": 2 }));

    // Symbols: the parameter and the blocks.
    let s = c.request("textDocument/documentSymbol", json!({ "textDocument": { "uri": doc } }));
    let names: Vec<&str> = s.as_array().unwrap().iter().map(|i| i["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["kp", "r", "ctrl", "sub", "plant"]);

    assert_eq!(c.request("shutdown", Value::Null), Value::Null);
    c.notify("exit", Value::Null);
    let status = c.child.wait().unwrap();
    assert!(status.success(), "{status}");
}

/// A real editor as the client: Debian's Neovim (`nvim --headless`, its
/// built-in LSP client, 0.7's API) opens a graph with a misspelt block
/// type, attaches `ctlgraph lsp`, and writes the diagnostics it received
/// and the hover text on `pid`. Skipped without `nvim`, unless
/// `CTLGRAPH_REQUIRE_NVIM` is set (`.ci/run` installs it and sets it).
#[test]
fn neovim_shows_the_diagnostic_and_the_hover() {
    let found = Command::new("nvim").arg("--version").output().is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var_os("CTLGRAPH_REQUIRE_NVIM").is_none(),
            "CTLGRAPH_REQUIRE_NVIM is set but nvim is missing"
        );
        eprintln!("skipped: nvim not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let graph = dir.path().join("loop.yaml");
    std::fs::write(&graph, "blocks:\n  r: { type: step }\n  ctrl: { type: pid }\n  plant: { type: transfer_fuction, num: [1], den: [1, 1] }\nwires:\n  - r -> ctrl\n  - ctrl -> plant\n").unwrap();
    let init = dir.path().join("init.lua");
    std::fs::write(
        &init,
        r#"
vim.api.nvim_create_autocmd("VimEnter", { callback = function()
  local id = vim.lsp.start_client({ name = "ctlgraph", cmd = { vim.env.CTLGRAPH_BIN, "lsp" }, root_dir = vim.fn.getcwd() })
  vim.lsp.buf_attach_client(0, id)
  vim.wait(20000, function() return #vim.diagnostic.get(0) > 0 end, 50)
  local lines = {}
  for _, d in ipairs(vim.diagnostic.get(0)) do
    table.insert(lines, string.format("diagnostic %d:%d %s", d.lnum + 1, d.col + 1, (d.message:gsub("\n", " | "))))
  end
  vim.api.nvim_win_set_cursor(0, { 3, 16 })
  local replies = vim.lsp.buf_request_sync(0, "textDocument/hover", vim.lsp.util.make_position_params(), 10000) or {}
  for _, r in pairs(replies) do
    if r.result then table.insert(lines, "hover " .. (r.result.contents.value:gsub("\n", " | "))) end
  end
  vim.fn.writefile(lines, vim.env.CTLGRAPH_NVIM_OUT)
  vim.cmd("qa!")
end })
"#,
    )
    .unwrap();
    let out = dir.path().join("seen.txt");
    let status = Command::new("timeout")
        .args(["60", "nvim", "--headless", "-n", "-i", "NONE", "-u"])
        .arg(&init)
        .arg(&graph)
        .current_dir(dir.path())
        .env("CTLGRAPH_BIN", env!("CARGO_BIN_EXE_ctlgraph"))
        .env("CTLGRAPH_NVIM_OUT", &out)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "nvim: {status}");
    let seen = std::fs::read_to_string(&out).unwrap();
    assert!(
        seen.contains("diagnostic 4:18 block `plant`: unknown block type `transfer_fuction` | hint: did you mean `transfer_function`?"),
        "{seen}"
    );
    assert!(seen.contains("hover **pid** (control)"), "{seen}");
}
