//! The README's commands, run: every `$ ctlgraph …` block and the
//! tutorial's inline quotes must match what today's binary prints, so the
//! documentation cannot drift from the program.

mod common;
use common::{ctlgraph, text};

const README: &str = include_str!("../README.md");

/// Wall-clock figures vary between machines: `(0.61 s)` at the end of a
/// line and `in 1.19 ms wall (2516.0x real time)` become placeholders.
fn normalise(line: &str) -> String {
    let mut l = line.trim_end().to_string();
    if let Some(open) = l.rfind(" (").filter(|_| l.ends_with(" s)")) {
        let inner = &l[open + 2..l.len() - 3];
        if inner.parse::<f64>().is_ok() {
            l.truncate(open);
            l.push_str(" (… s)");
        }
    }
    if let (Some(a), Some(b)) = (l.find(" simulated in "), l.find("x real time)")) {
        l.replace_range(a + " simulated in ".len()..b + "x real time)".len(), "…");
    }
    // An FMU's size and whether its binary was built depend on the build and the cache.
    if let Some(a) = l.find(" co-simulation FMU, ").and_then(|_| l.rfind(" (")).filter(|_| l.ends_with(')')) {
        l.replace_range(a + 2..l.len() - 1, "…");
    }
    // Whether an accelerated step was built or loaded depends on the cache.
    if let Some(a) = l.find(", accelerated (step ").filter(|_| l.ends_with(')')) {
        l.replace_range(a + ", accelerated (".len()..l.len() - 1, "…");
    }
    l
}

/// Matches `expected` (with `...` lines standing for any number of lines)
/// against `actual`, in order.
fn matches(expected: &[String], actual: &[String]) -> Result<(), String> {
    let mut at = 0;
    let mut gap = false;
    for e in expected {
        if e.trim() == "..." {
            gap = true;
            continue;
        }
        let found = if gap {
            actual[at..].iter().position(|a| a == e).map(|p| at + p)
        } else {
            (actual.get(at) == Some(e)).then_some(at)
        };
        match found {
            Some(i) => at = i + 1,
            None => return Err(format!("expected line not found: `{e}`\nactual output:\n{}", actual.join("\n"))),
        }
        gap = false;
    }
    Ok(())
}

#[test]
fn every_quoted_command_prints_what_the_readme_shows() {
    let lines: Vec<&str> = README.lines().collect();
    let mut ran = 0;
    let mut i = 0;
    while i < lines.len() {
        let Some(command) = lines[i].strip_prefix("    $ ctlgraph ") else {
            i += 1;
            continue;
        };
        let mut expected = Vec::new();
        i += 1;
        while i < lines.len() && lines[i].starts_with("    ") {
            expected.push(normalise(&lines[i][4..]));
            i += 1;
        }
        let args: Vec<&str> = command.split_whitespace().collect();
        let out = ctlgraph(&args);
        let actual: Vec<String> = text(&out.stdout).lines().map(normalise).collect();
        if let Err(e) = matches(&expected, &actual) {
            panic!("README: `ctlgraph {command}`: {e}");
        }
        ran += 1;
    }
    assert!(ran >= 3, "found only {ran} quoted commands");
}

/// Step 3's softer gain fails two of the graph's checks, as the README
/// says it does, with the quoted line and exit code.
#[test]
fn the_softer_gain_of_step_3_fails_the_checks_the_readme_says() {
    let command = README.lines().find(|l| l.contains("--set kp=0.5")).expect("step 3's command");
    let command = command.split('#').next().unwrap().trim();
    let args: Vec<&str> = command.split_whitespace().skip(1).collect();
    let out = ctlgraph(&args);
    assert!(
        README.contains("exits 1: see below") && README.contains("the run\nexits 1 and says `2 of 4 checks failed`")
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("2 of 4 checks failed"), "{}", text(&out.stderr));
    let words = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let quoted = words(README.split("fail (`").nth(1).unwrap().split(", …)`").next().unwrap());
    let printed = text(&out.stdout);
    assert!(printed.lines().any(|l| words(l).starts_with(&quoted)), "no `{quoted}` in {printed}");
}

#[test]
fn the_first_tutorial_step_prints_what_it_says() {
    // The YAML after "Save as `lag.yaml`:", run as the tutorial says.
    let start = README.find("Save as `lag.yaml`:").expect("tutorial step 1");
    let body = &README[start..];
    let yaml = &body[body.find("```yaml\n").unwrap() + 8..];
    let yaml = &yaml[..yaml.find("```").unwrap()];
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lag.yaml"), yaml).unwrap();
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_ctlgraph"))
            .args(args)
            .current_dir(dir.path())
            .env("CI", "1")
            .output()
            .unwrap()
    };
    let out = run(&["run", "lag.yaml", "--out", "lag.csv", "--plot", "lag.svg"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let summary = normalise(text(&out.stdout).lines().next().unwrap());
    let quoted =
        README.split("prints one summary line (`").nth(1).unwrap().split('`').next().unwrap().replace('\n', " ");
    assert_eq!(summary, normalise(&quoted));
    let csv = std::fs::read_to_string(dir.path().join("lag.csv")).unwrap();
    assert!(csv.starts_with("t,u,y\n"));
    let row = README.split("the row at t = 0.5 reads `").nth(1).unwrap().split('`').next().unwrap();
    assert!(csv.lines().any(|l| l == row), "row `{row}` not in the CSV");
    // Step 8: the misspelt type, as quoted.
    std::fs::write(dir.path().join("lag.yaml"), yaml.replace("transfer_function", "transfer_fuction")).unwrap();
    let out = run(&["check", "lag.yaml"]);
    assert_eq!(out.status.code(), Some(2));
    let quoted = README.split("**8. Mistakes are reported, not crashed on.**").nth(1).unwrap();
    for line in quoted.lines().skip(1).take_while(|l| l.starts_with("    ")) {
        assert!(text(&out.stderr).contains(line.trim()), "stderr lacks `{}`:\n{}", line.trim(), text(&out.stderr));
    }
}

#[test]
fn the_block_reference_page_is_the_library_as_it_is() {
    let page = std::fs::read_to_string("docs/blocks.md").unwrap();
    let out = ctlgraph(&["blocks", "--markdown"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(
        page == text(&out.stdout),
        "docs/blocks.md is stale: regenerate it with `ctlgraph blocks --markdown > docs/blocks.md`"
    );
    // What a new user looks for is there.
    for entry in
        ["### `gain`", "| `k` |", "### `gaussian_noise`", "| `variance` |", "### `state_space`", "| `A` |", "| `D` |"]
    {
        assert!(page.contains(entry), "docs/blocks.md lacks {entry}");
    }
}

/// Every ctlgraph name in the README's "Coming from Simulink" table is a
/// registered block type (the table's section names aside).
#[test]
fn the_simulink_table_names_registered_types() {
    let start = README.find("| Simulink | ctlgraph |").expect("the table");
    let registry = ctlgraph::registry();
    let sections = ["scopes:", "record:", "--plot", "--out", "constant:", "enable:", "trigger:"];
    let mut named = 0;
    for row in README[start..].lines().skip(2).take_while(|l| l.starts_with('|')) {
        let ours = row.split('|').nth(2).unwrap();
        for name in ours.split('`').skip(1).step_by(2) {
            if !sections.contains(&name) {
                assert!(registry.get(name).is_some(), "`{name}` in the Simulink table is not a block type");
                named += 1;
            }
        }
    }
    assert!(named > 50, "{named} names");
}
