//! What an editor waits for: `ctlgraph lsp`'s diagnostics of a document
//! (load, expand, compile, as `ctlgraph check`) after each change, on the
//! largest bundled graphs.
//!
//!     cargo bench --bench editor

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::str::FromStr;

fn diagnostics(c: &mut Criterion) {
    let mut group = c.benchmark_group("lsp_diagnostics");
    for graph in ["graphs/fladrc/compare.yaml", "graphs/contact-force/compare.yaml", "graphs/milling/lobes.yaml"] {
        let path = std::fs::canonicalize(graph).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let uri = lsp_types::Uri::from_str(&format!("file://{}", path.display())).unwrap();
        assert!(ctlgraph::lsp::diagnostics(&uri, &text).is_empty(), "{graph} has diagnostics");
        group.bench_function(graph, |b| b.iter(|| black_box(ctlgraph::lsp::diagnostics(&uri, black_box(&text)))));
    }
    group.finish();
}

criterion_group!(benches, diagnostics);
criterion_main!(benches);
