//! Any bytes as the data file of a `from_csv` block: the loader refuses
//! malformed data with the file and row, never panics; a table that loads
//! is run.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("ctlgraph-fuzz-csv-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let file = dir.join("data.csv");
    if std::fs::write(&file, data).is_err() {
        return;
    }
    let graph = format!(
        "simulation: {{ stop: 1.0, solver: {{ method: rk4, step: 0.01 }} }}\nblocks:\n  s: {{ type: from_csv, file: \"{}\", column: y }}\n",
        file.display()
    );
    if let Ok(model) = ctlgraph::compile_str(&graph, "fuzz.yaml", &[]) {
        let _ = ctlgraph::simulate(model, None);
    }
});
