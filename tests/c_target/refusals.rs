//! What C generation refuses, with the message, the block and its place.

use crate::common::{ctlgraph, text};
use ctlgraph::target_c::from_model;
use ctlgraph_core::codegen::c::Real;

/// The diagnostic for `yaml`'s whole graph, as `file:line:col: message`.
fn refusal(yaml: &str) -> String {
    let model = ctlgraph::compile_str(yaml, "test.yaml", &[]).unwrap_or_else(|d| panic!("{d}"));
    match from_model(model, None, "ctl", Real::Double, "test.yaml") {
        Ok(_) => panic!("generated C for\n{yaml}"),
        Err(d) => d.to_string(),
    }
}

#[test]
fn a_continuous_block_in_the_controller_is_refused_at_its_line() {
    let e = refusal(
        "blocks:\n  u: { type: inport }\n  k: { type: gain, k: 2, sample_time: 0.01 }\n  p: { type: transfer_function, num: [1], den: [1, 1] }\n  y: { type: outport }\n\
         wires:\n  - u -> k\n  - k -> p\n  - p -> y\n",
    );
    assert!(e.starts_with("test.yaml:4:"), "{e}");
    assert!(e.contains("block `p` (transfer_function) is continuous"), "{e}");
    assert!(e.contains("sample_time"), "{e}");
}

#[test]
fn a_rate_that_is_not_a_whole_multiple_of_the_base_is_refused() {
    let e = refusal(
        "blocks:\n  u: { type: inport }\n  a: { type: gain, k: 2, sample_time: 0.01 }\n  b: { type: gain, k: 3, sample_time: 0.015 }\n  y: { type: outport }\n\
         wires:\n  - u -> a\n  - a -> b\n  - b -> y\n",
    );
    assert!(e.starts_with("test.yaml:4:"), "{e}");
    assert!(e.contains("sample time 0.015 s is not a whole multiple of the base rate 0.01 s"), "{e}");
}

#[test]
fn a_sample_time_offset_is_refused() {
    let e = refusal(
        "blocks:\n  u: { type: inport }\n  a: { type: gain, k: 2, sample_time: [0.01, 0.005] }\n  y: { type: outport }\n\
         wires:\n  - u -> a\n  - a -> y\n",
    );
    assert!(e.starts_with("test.yaml:3:"), "{e}");
    assert!(e.contains("offset"), "{e}");
}

#[test]
fn a_block_without_a_c_form_is_refused_with_the_types_that_have_one() {
    let e = refusal(
        "blocks:\n  u: { type: inport }\n  n: { type: band_limited_white_noise, power: 1, sample_time: 0.01 }\n  s: { type: sum, signs: '++' }\n  y: { type: outport }\n\
         wires:\n  - u -> s.u1\n  - n -> s.u2\n  - s -> y\n",
    );
    assert!(e.starts_with("test.yaml:3:"), "{e}");
    assert!(e.contains("type `band_limited_white_noise` has no C form"), "{e}");
    assert!(e.contains("types with a C form: ") && e.contains("tracking_differentiator"), "{e}");
}

#[test]
fn a_controller_needs_an_outport_and_a_sample_time() {
    let e =
        refusal("blocks:\n  u: { type: inport }\n  k: { type: gain, k: 2, sample_time: 0.01 }\nwires:\n  - u -> k\n");
    assert!(e.contains("the controller has no outport"), "{e}");
    let e = refusal(
        "blocks:\n  u: { type: inport }\n  k: { type: gain, k: 2 }\n  y: { type: outport }\nwires:\n  - u -> k\n  - k -> y\n",
    );
    assert!(e.contains("no block of the controller has a sample time"), "{e}");
}

#[test]
fn the_command_line_names_what_is_missing() {
    let out =
        ctlgraph(&["codegen", "--target", "c", "graphs/fladrc/ladrc.yaml", "--subsystem", "ctl", "--out", "unused"]);
    assert_eq!(out.status.code(), Some(2));
    let e = text(&out.stderr);
    assert!(e.contains("has no subsystem `ctl`") && e.contains("did you mean `ctrl`?"), "{e}");
    let out =
        ctlgraph(&["codegen", "--target", "c", "graphs/fladrc/ladrc.yaml", "--subsystem", "plant", "--out", "unused"]);
    assert!(text(&out.stderr).contains("its subsystems: ctrl"), "{}", text(&out.stderr));
    let out = ctlgraph(&["codegen", "--target", "c", "graphs/fladrc/ladrc.yaml", "--subsystem", "ctrl"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("--out DIR"), "{}", text(&out.stderr));
    assert!(!std::path::Path::new("unused").exists());
    let out = ctlgraph(&["codegen", "graphs/fladrc/ladrc.yaml", "--subsystem", "ctrl"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("belong to --target c"), "{}", text(&out.stderr));
}
