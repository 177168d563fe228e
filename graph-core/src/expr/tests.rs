use super::*;

fn val(src: &str) -> f64 {
    let scope: Vec<(String, f64)> = vec![("h".into(), 1e-4), ("w0".into(), 1000.0)];
    Expr::parse(src, &Constants(&scope)).unwrap().constant().unwrap()
}

#[test]
fn precedence_and_associativity() {
    assert_eq!(val("1 + 2 * 3"), 7.0);
    assert_eq!(val("(1 + 2) * 3"), 9.0);
    assert_eq!(val("2^3^2"), 512.0);
    assert_eq!(val("-2^2"), -4.0);
    assert_eq!(val("2^-1"), 0.5);
    assert_eq!(val("8 / 4 / 2"), 1.0);
    assert_eq!(val("10 - 4 - 3"), 3.0);
}

#[test]
fn names_functions_and_constants() {
    assert_eq!(val("5*h"), 5e-4);
    assert_eq!(val("3*w0"), 3000.0);
    assert_eq!(val("w0^2"), 1e6);
    assert_eq!(val("sqrt(16) + abs(-2) + max(1, 7, 3) + min(4, 2)"), 4.0 + 2.0 + 7.0 + 2.0);
    assert!((val("atan2(1, 1)") - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    assert!((val("sin(pi/2) + cos(0) + tan(0) + exp(0) + ln(1)") - 3.0).abs() < 1e-15);
    assert_eq!(val("1.5e3 + .5 + 2E-1"), 1500.7);
    assert_eq!(val("sign(-3) + sign(0)"), -1.0);
}

#[test]
fn variables_are_slots() {
    struct Vars;
    impl Scope for Vars {
        fn lookup(&self, name: &str) -> Option<Binding> {
            match name {
                "u1" => Some(Binding::Slot(0)),
                "t" => Some(Binding::Slot(1)),
                "k" => Some(Binding::Value(2.0)),
                _ => None,
            }
        }
        fn names(&self) -> Vec<String> {
            vec!["u1".into(), "t".into(), "k".into()]
        }
    }
    let e = Expr::parse("k * u1 + sin(t) * (1 + 1)", &Vars).unwrap();
    assert_eq!(e.constant(), None);
    assert_eq!(e.eval(&[3.0, 0.0]), 6.0);
    let err = Expr::parse("k * u + 1", &Vars).unwrap_err();
    assert_eq!((err.offset, err.message.as_str()), (4, "unknown name `u`"));
    assert_eq!(err.hint.as_deref(), Some("did you mean `u1`?"));
}

#[test]
fn errors_point_at_the_offending_character() {
    let scope: Vec<(String, f64)> = vec![];
    let cases = [
        ("1 +", 3, "expression ends too early"),
        ("(1 + 2", 6, "expected `)`, found the end"),
        ("2 $ 3", 2, "unexpected character `$`"),
        ("1 2", 2, "unexpected number 2 after the end of the expression"),
        ("sqr(2)", 0, "unknown function `sqr`"),
        ("atan2(1)", 0, "`atan2` takes two arguments, got 1"),
    ];
    for (src, offset, message) in cases {
        let e = Expr::parse(src, &Constants(&scope)).unwrap_err();
        assert_eq!((e.offset, e.message.as_str()), (offset, message), "{src}");
    }
}
