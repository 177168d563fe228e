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

/// The postfix program gives the tree's value to the bit (or NaN where the
/// tree gives NaN) for random expressions over three variables — every
/// operator, function, atan2, min and max of one to four arguments — and
/// an expression deeper than the program's stack falls back to the tree.
#[test]
fn the_program_evaluates_as_the_tree() {
    // A small xorshift generator: the test needs no crate.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move |n: u64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state % n
    };
    fn random(depth: u32, next: &mut dyn FnMut(u64) -> u64) -> Node {
        if depth == 0 || next(4) == 0 {
            return if next(2) == 0 {
                Node::Var(next(3) as usize)
            } else {
                Node::Const(next(2001) as f64 / 100.0 - 10.0)
            };
        }
        let sub = |next: &mut dyn FnMut(u64) -> u64| Box::new(random(depth - 1, next));
        match next(6) {
            0 => Node::Neg(sub(next)),
            1 | 2 => {
                let op = [Op::Add, Op::Sub, Op::Mul, Op::Div, Op::Pow][next(5) as usize];
                Node::Bin(op, sub(next), sub(next))
            }
            3 => Node::Call(FUNC1[next(17) as usize].1, sub(next)),
            4 => Node::Atan2(sub(next), sub(next)),
            _ => {
                let n = 1 + next(4) as usize;
                Node::MinMax { max: next(2) == 0, args: (0..n).map(|_| random(depth - 1, next)).collect() }
            }
        }
    }
    let mut compared = 0;
    for _ in 0..3000 {
        let expr = Expr::new(random(6, &mut next));
        let Some(program) = &expr.program else { continue };
        for _ in 0..5 {
            let vars = [next(2001) as f64 / 100.0 - 10.0, next(2001) as f64 / 1000.0, next(7) as f64 - 3.0];
            let (by_program, by_tree) = (program::run(program, &vars), eval(&expr.root, &vars));
            assert!(
                by_program.to_bits() == by_tree.to_bits() || by_program.is_nan() && by_tree.is_nan(),
                "{:?} at {vars:?}: {by_program} vs {by_tree}",
                expr.root
            );
            compared += 1;
        }
    }
    assert!(compared > 14_000, "{compared}");
    // 2^2^…^2 nests to the right: 40 levels need a stack 40 deep.
    let tower = vec!["x"; 40].join("^");
    struct X;
    impl Scope for X {
        fn lookup(&self, name: &str) -> Option<Binding> {
            (name == "x").then_some(Binding::Slot(0))
        }
        fn names(&self) -> Vec<String> {
            vec!["x".into()]
        }
    }
    let expr = Expr::parse(&tower, &X).unwrap();
    assert!(expr.program.is_none());
    assert_eq!(expr.eval(&[1.0]), 1.0);
    assert!(Expr::parse("x^x^x", &X).unwrap().program.is_some());
    // A tower of k needs exactly k slots: STACK fit, one more does not.
    for (k, fits) in [(program::STACK, true), (program::STACK + 1, false)] {
        let expr = Expr::parse(&vec!["x"; k].join("^"), &X).unwrap();
        assert_eq!(expr.program.is_some(), fits, "tower of {k}");
        assert_eq!(expr.eval(&[1.0]), 1.0);
    }
}
