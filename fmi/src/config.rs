//! `resources/ctlgraph.json`: what the exporter tells the FMU's binary —
//! which file in `resources/` is the graph, the `--set` overrides it was
//! exported with, and the token the description carries.

use serde_json::{Value, json};
use std::path::Path;

/// The file's name in `resources/`.
pub const FILE: &str = "ctlgraph.json";

#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// The graph file, relative to `resources/` (`/`-separated).
    pub graph: String,
    /// `--set NAME=VALUE` pairs given at export.
    pub sets: Vec<(String, String)>,
    /// The description's `instantiationToken` (FMI 3) or `guid` (FMI 2).
    pub token: String,
}

impl Config {
    pub fn to_json(&self) -> String {
        let sets: Vec<Value> = self.sets.iter().map(|(n, v)| json!([n, v])).collect();
        let doc = json!({ "graph": self.graph, "sets": sets, "token": self.token });
        serde_json::to_string_pretty(&doc).unwrap_or_default()
    }

    /// Reads the configuration in the folder `resources`.
    pub fn read(resources: &Path) -> Result<Config, String> {
        let path = resources.join(FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let doc: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        let field = |name: &str| {
            doc.get(name).and_then(Value::as_str).map(str::to_string).ok_or_else(|| {
                format!("{}: no `{name}` (the FMU was not written by `ctlgraph fmu`, or was altered)", path.display())
            })
        };
        let pair = |v: &Value| match v.as_array().map(Vec::as_slice) {
            Some([Value::String(n), Value::String(v)]) => Some((n.clone(), v.clone())),
            _ => None,
        };
        let sets = match doc.get("sets").and_then(Value::as_array) {
            Some(list) => list.iter().map(pair).collect::<Option<Vec<_>>>(),
            None => Some(Vec::new()),
        }
        .ok_or_else(|| format!("{}: `sets` is not a list of [name, value] pairs", path.display()))?;
        Ok(Config { graph: field("graph")?, sets, token: field("token")? })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_and_read_back() {
        let dir = std::env::temp_dir().join(format!("ctlgraph-fmi-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let c = Config { graph: "model/a.yaml".into(), sets: vec![("k".into(), "2".into())], token: "{x}".into() };
        std::fs::write(dir.join(FILE), c.to_json()).unwrap();
        assert_eq!(Config::read(&dir).unwrap(), c);
        std::fs::write(dir.join(FILE), "{\"graph\": 1}").unwrap();
        assert!(Config::read(&dir).unwrap_err().contains("no `graph`"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
