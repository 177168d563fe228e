//! Any bytes as an expression over two named parameters: parse, fold and
//! evaluate without panicking or overflowing the stack.
#![no_main]

use ctlgraph::core::expr::{Constants, Expr};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let params = [("a".to_string(), 1.5), ("b".to_string(), -2.0)];
    if let Ok(e) = Expr::parse(text, &Constants(&params)) {
        let _ = e.eval(&[]);
    }
});
