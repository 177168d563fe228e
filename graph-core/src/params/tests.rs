//! The parameter table as the parser reads it: a parameter left out takes
//! the table's default, of the kind the block asks for.

use super::{ParamDefault::*, ParamDoc, ParamKind, Params};
use crate::block::SampleTime;

const TABLE: &[ParamDoc] = &[
    ParamDoc::new("gain", Number(2.5), "a gain"),
    ParamDoc::new("tau", Required, "a time constant").unit("s").kind(ParamKind::Number),
    ParamDoc::new("initial", Numbers(&[1.0, -1.0]), "x(0)"),
    ParamDoc::new("mode", Word("fast"), "fast | slow").options(&["slow", "fast"]),
    ParamDoc::new("weights", Number(0.5), "one weight, or one per element").kind(ParamKind::Numbers),
    ParamDoc::new("hold", Flag(true), "hold the input"),
    ParamDoc::new("h0", Described("2·sample_time"), "a filter factor").kind(ParamKind::Number),
    ParamDoc::new("sample_time", Number(0.0), "0 continuous, T > 0 discrete").kind(ParamKind::SampleTime),
];

/// Runs `f` on the parameters of a block `b` of a type with `TABLE`,
/// written `{ type: t, <written> }`.
fn with<R>(written: &str, table: &'static [ParamDoc], f: impl FnOnce(&mut Params) -> R) -> R {
    let text = format!("blocks:\n  b: {{ type: t, {written} }}\n");
    let flat = crate::load_str(&text, "t.yaml".into(), &[]).unwrap_or_else(|d| panic!("{d}"));
    let b = &flat.blocks[0];
    let mut p = Params::new("b", "t", &b.spec.pos, &b.spec.params, &b.scope, &b.dir, table);
    f(&mut p)
}

#[test]
fn a_parameter_left_out_takes_the_tables_default_of_the_kind_asked() {
    with("tau: 0.1", TABLE, |p| {
        assert_eq!(p.number("gain").unwrap(), 2.5);
        assert_eq!(p.vector("initial").unwrap(), vec![1.0, -1.0]);
        assert_eq!(p.choice("mode", &["slow", "fast"]).unwrap(), "fast");
        assert!(p.flag("hold").unwrap());
        assert_eq!(p.sample_time().unwrap(), SampleTime::Continuous);
        // A number default of a list is a list of one.
        assert_eq!(p.vector("weights").unwrap(), vec![0.5]);
        assert_eq!(p.number("tau").unwrap(), 0.1);
    });
}

#[test]
fn a_parameter_written_overrides_the_default() {
    with("tau: 1, gain: -3, initial: [4, 5], mode: slow, hold: false, sample_time: 0.01", TABLE, |p| {
        assert_eq!(p.number("gain").unwrap(), -3.0);
        assert_eq!(p.vector("initial").unwrap(), vec![4.0, 5.0]);
        assert_eq!(p.choice("mode", &["slow", "fast"]).unwrap(), "slow");
        assert!(!p.flag("hold").unwrap());
        assert_eq!(p.sample_time().unwrap(), SampleTime::Discrete { period: 0.01, offset: 0.0 });
    });
}

#[test]
fn a_required_parameter_left_out_is_an_error_naming_it() {
    with("gain: 1", TABLE, |p| {
        let e = p.number("tau").unwrap_err();
        assert!(e.message.contains("missing parameter `tau`"), "{}", e.message);
        assert_eq!(e.hint.as_deref(), Some("see `ctlgraph blocks t`"));
        assert_eq!(p.opt_number("tau").unwrap(), None);
    });
}

#[test]
fn a_described_default_is_left_to_the_block() {
    with("", TABLE, |p| {
        assert_eq!(p.opt_number("h0").unwrap(), None);
        assert_eq!(p.number_or("h0", 0.02).unwrap(), 0.02);
        // A derived default does not hide the table's value where there is one.
        assert_eq!(p.number_or("gain", 7.0).unwrap(), 2.5);
    });
}

/// Tables whose defaults are not of the kind they declare.
const MISMATCHED: &[ParamDoc] = &[
    ParamDoc::new("mode", Word("fast"), "").kind(ParamKind::Number),
    ParamDoc::new("gain", Number(1.0), "").kind(ParamKind::Flag),
    ParamDoc::new("name", Number(1.0), "").kind(ParamKind::Text),
];

#[test]
fn a_default_of_another_kind_than_the_block_asks_for_is_an_internal_error() {
    with("", MISMATCHED, |p| {
        let e = p.number("mode").unwrap_err();
        assert!(e.message.contains("internal error") && e.message.contains("`fast`"), "{}", e.message);
        assert!(p.flag("gain").unwrap_err().message.contains("as a flag"));
        assert!(p.opt_string("name").unwrap_err().message.contains("as a string"));
    });
}

#[test]
#[cfg(debug_assertions)]
#[should_panic(expected = "reads parameter `mode` as [Number], but its table declares it Word")]
fn a_block_reading_a_parameter_as_another_kind_than_its_table_declares_stops_a_debug_build() {
    with("", TABLE, |p| {
        let _ = p.number("mode");
    })
}

#[test]
fn a_block_without_a_table_gives_its_own_defaults() {
    with("", &[], |p| {
        assert_eq!(p.number_or("k", 4.0).unwrap(), 4.0);
        assert!(p.number("k").is_err());
        assert_eq!(p.choice("mode", &["a", "b"]).unwrap(), "a");
        assert_eq!(p.sample_time().unwrap(), SampleTime::Inherited);
    });
}

#[test]
#[cfg(debug_assertions)]
#[should_panic(expected = "reads parameter `gian`, which its parameter table does not list")]
fn a_block_reading_a_key_its_table_does_not_list_stops_a_debug_build() {
    with("", TABLE, |p| {
        let _ = p.opt_number("gian");
    })
}

#[test]
fn the_documentation_prints_each_default_as_a_graph_writes_it() {
    let shown: Vec<String> = TABLE.iter().map(|d| d.default.to_string()).collect();
    assert_eq!(shown, ["2.5", "required", "[1, -1]", "fast", "0.5", "true", "2·sample_time", "0"]);
    assert_eq!(TABLE[1].unit, "s");
    let kinds: Vec<&str> = TABLE.iter().map(|d| d.kind.name()).collect();
    assert_eq!(kinds, ["number", "number", "numbers", "word", "numbers", "flag", "number", "sample time"]);
}
