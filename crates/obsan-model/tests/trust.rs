//! The readers never panic on user text, every
//! rejection has a place, and benign file variations (byte-order mark, CRLF
//! or CR line ends, non-ASCII comments) read as the plain file does.

use obsan_model::{decode_text, EffectLibrary, ModelError, System};

const BASE: &str = "system s
description demo
state x, y
param a
const k = 2
input u
x' = a*y + u
y' = -k*x
output h = x
restrict r: u = 3*v
";

fn parse(src: &str) -> Result<System, ModelError> {
    System::parse(src, "t.sys")
}

/// The normal forms of a system, as text, without and with each restriction.
fn forms(s: &System) -> Vec<String> {
    let mut names = vec![None];
    names.extend(s.restrictions.iter().map(|r| Some(r.name.as_str())));
    names
        .into_iter()
        .map(|r| {
            let mut nf = s.normal_form(r, &[]).unwrap();
            let mut out = format!("{:?} {:?} {:?}", nf.state, nf.inputs, r);
            let ids: Vec<_> = nf
                .f0
                .iter()
                .chain(nf.fields.iter().flatten())
                .copied()
                .collect();
            for id in ids {
                out.push(' ');
                out.push_str(&nf.ctx.to_text(id));
            }
            let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
            for id in outs {
                out.push(' ');
                out.push_str(&nf.ctx.to_text(id));
            }
            out
        })
        .collect()
}

/// The character column of `^` in the caret line equals that of the
/// reported column in the shown source line (the caret sits under it).
fn caret_under(e: &ModelError, want: char) {
    let shown = e.to_string();
    let lines: Vec<&str> = shown.lines().collect();
    let src_line = lines
        .iter()
        .find(|l| l.contains(" | ") && !l.trim_start().starts_with('|'));
    let caret_line = lines.last().unwrap();
    let src_line = src_line.unwrap_or_else(|| panic!("no source line in {shown}"));
    let src_col = src_line.chars().position(|c| c == want).unwrap();
    let caret_col = caret_line.chars().position(|c| c == '^').unwrap();
    assert_eq!(src_col, caret_col, "caret not under '{want}':\n{shown}");
    // And the column number counts characters.
    let (_, text) = src_line.split_once(" | ").unwrap();
    assert_eq!(
        text.chars().position(|c| c == want).map(|p| p + 1),
        e.col,
        "{shown}"
    );
}

#[test]
fn a_byte_order_mark_reads_as_nothing() {
    let plain = parse(BASE).unwrap();
    let bom = parse(&format!("\u{feff}{BASE}")).unwrap();
    assert_eq!(forms(&plain), forms(&bom));
    // Errors keep their columns: the mark is not a character of line 1.
    let e = parse("\u{feff}system 2s\nstate x\n").unwrap_err();
    assert_eq!((e.line, e.col), (Some(1), Some(1)), "{e}");
    assert_eq!(
        decode_text(b"\xEF\xBB\xBFsystem s\n", "t.sys").unwrap(),
        "system s\n"
    );
}

#[test]
fn crlf_and_cr_line_ends_read_as_lines() {
    let plain = forms(&parse(BASE).unwrap());
    for nl in ["\r\n", "\r"] {
        let s = parse(&BASE.replace('\n', nl)).unwrap();
        assert_eq!(forms(&s), plain, "line end {nl:?}");
        assert_eq!(s.description, "demo");
        // An error on line 7 is reported on line 7, not on line 1.
        let bad = BASE
            .replace("x' = a*y + u", "x' = a*y + $")
            .replace('\n', nl);
        let e = parse(&bad).unwrap_err();
        assert_eq!((e.line, e.col), (Some(7), Some(12)), "{nl:?}: {e}");
        assert!(!e.to_string().contains('\r'), "{e:?}");
    }
    let lib = "model s\r\neffect e\r\nparam b\routput h = h + b\r";
    let lib = EffectLibrary::parse(lib, "t.eff").unwrap();
    assert_eq!(lib.effects[0].outputs, vec![("h".into(), "h + b".into())]);
    assert_eq!(decode_text(b"a\r\nb\rc", "f").unwrap(), "a\nb\nc");
}

#[test]
fn non_ascii_comments_and_descriptions_are_read() {
    let src = BASE
        .replace("description demo", "description für α-Messung")
        .replace("param a", "param a # größe α");
    let s = parse(&format!("# für\n{src}")).unwrap();
    assert_eq!(s.description, "für α-Messung");
    assert_eq!(forms(&s), forms(&parse(BASE).unwrap()));
    let printed = s.to_sys_text();
    assert_eq!(forms(&parse(&printed).unwrap()), forms(&s));
}

#[test]
fn non_ascii_names_are_refused_at_their_place() {
    // The expression language's names are ASCII (docs/sys-format.md).
    let e = parse(&BASE.replace("state x, y", "state x, yα")).unwrap_err();
    assert_eq!((e.line, e.col), (Some(3), Some(10)), "{e}");
    assert!(e.message.contains("ASCII"), "{e}");
    let e = parse(&BASE.replace("state x, y", "state α, y")).unwrap_err();
    assert_eq!((e.line, e.col), (Some(3), Some(7)), "{e}");
    caret_under(&e, 'α');
    let e = parse(&BASE.replace("y' = -k*x", "y' = -k*x + 2*é")).unwrap_err();
    assert_eq!((e.line, e.col), (Some(8), Some(15)), "{e}");
    caret_under(&e, 'é');
    assert!(e.message.contains("ASCII"), "{e}");
    let e = parse(&BASE.replace("y' = -k*x", "ÿ' = -k*x")).unwrap_err();
    assert_eq!((e.line, e.col), (Some(8), Some(1)), "{e}");
    assert!(e.message.contains("ASCII"), "{e}");
    let e = parse(&BASE.replace("restrict r: u = 3*v", "restrict r: u = 3*ν")).unwrap_err();
    assert_eq!((e.line, e.col), (Some(10), Some(19)), "{e}");
}

#[test]
fn columns_count_characters_and_the_caret_aligns() {
    // ModelError::at takes byte offsets; the column is in characters.
    let src = "ab üü cd\n";
    let at = src.find('c').unwrap();
    let e = ModelError::at("f", src, at, at + 2, "here");
    assert_eq!((e.line, e.col), (Some(1), Some(7)));
    caret_under(&e, 'c');
    assert!(e.to_string().ends_with("      ^^"), "{e}");
    // An end inside a character underlines the whole character.
    let e = ModelError::at("f", "a üb", 2, 3, "here");
    assert!(e.to_string().ends_with("|   ^"), "{e}");
    let e = ModelError::at("f", "a üb", 0, 3, "here");
    assert!(e.to_string().ends_with("| ^^^"), "{e}");
    // A tab before the place is kept in the caret line.
    let src = "\tx = ü";
    let e = ModelError::at("f", src, src.find('ü').unwrap(), src.len(), "here");
    assert_eq!(e.col, Some(6));
    assert!(e.to_string().ends_with("| \t    ^"), "{e:?}");
}

#[test]
fn error_offsets_outside_the_text_never_panic() {
    let src = "aé\nb";
    for (a, b) in [
        (0, 0),
        (2, 1),
        (2, 3),
        (3, 99),
        (99, 3),
        (99, 199),
        (usize::MAX, 0),
    ] {
        let e = ModelError::at("f", src, a, b, "m");
        let shown = e.to_string();
        assert!(shown.starts_with("f:"), "{shown}");
        assert!(e.line.unwrap() <= 2 && e.col.unwrap() >= 1, "{shown}");
    }
    // Inside 'é' (byte 2 of 3): the place is the character itself.
    let e = ModelError::at("f", src, 2, 3, "m");
    assert_eq!((e.line, e.col), (Some(1), Some(2)));
}

#[test]
fn a_file_ending_in_an_operator_is_an_error_at_its_end() {
    let head = "system s\nstate x\noutput y = x\n";
    for (tail, col) in [
        ("x' = x*", 8),
        ("x' = (x", 6),
        ("x' = x +", 9),
        ("x' = x^", 8),
    ] {
        for nl in ["", "\n", "\r\n"] {
            let e = parse(&format!("{head}{tail}{nl}")).unwrap_err();
            assert_eq!((e.line, e.col), (Some(4), Some(col)), "{tail:?}{nl:?}: {e}");
            assert!(e.to_string().contains('^'), "{e}");
        }
    }
    // An empty value after '=' in a declaration is an error at the name.
    let e = parse("system s\nstate x\nparam a =\nx' = a\noutput y = x\n").unwrap_err();
    assert_eq!((e.line, e.col), (Some(3), Some(7)), "{e}");
    let e = parse("system s\nstate x\ninput u = \nx' = u\noutput y = x").unwrap_err();
    assert_eq!((e.line, e.col), (Some(3), Some(7)), "{e}");
}

#[test]
fn invalid_utf8_is_located() {
    // Third line, after two characters of which one is two bytes.
    let e = decode_text(b"system s\nstate x\n\xC3\xA9x\xFFx' = x\n", "t.sys").unwrap_err();
    assert_eq!((e.line, e.col), (Some(3), Some(3)), "{e}");
    assert!(
        e.to_string()
            .starts_with("t.sys:3:3: invalid UTF-8 (byte 0xFF)"),
        "{e}"
    );
    // CR-only line ends count as lines; a truncated sequence at the end too.
    let e = decode_text(b"a\rb\r\ncd\xE2\x82", "t.sys").unwrap_err();
    assert_eq!((e.line, e.col), (Some(3), Some(3)), "{e}");
    // A BOM is not a character of line 1.
    let e = decode_text(b"\xEF\xBB\xBFab\x80", "t.sys").unwrap_err();
    assert_eq!((e.line, e.col), (Some(1), Some(3)), "{e}");
}

#[test]
fn effect_errors_are_located_in_characters() {
    let src = "model s\n# größe\neffect e\n\u{3000}param 2b\n";
    let e = EffectLibrary::parse(src, "t.eff").unwrap_err();
    assert_eq!((e.line, e.col), (Some(4), Some(2)), "{e}");
    assert!(e.to_string().starts_with("t.eff:4:2: "), "{e}");
    // Non-ASCII text survives substitution (a description, a comment-free line).
    let m = vec![("u".to_string(), "v".to_string())];
    assert_eq!(obsan_model::substitute_names("ü*u + é", &m), "ü*(v) + é");
}

mod props {
    //! Random files from valid pieces, then mutated: never a panic, every
    //! rejection located inside the file and naming it.
    use super::*;
    use proptest::prelude::*;
    use proptest::test_runner::{Config, FileFailurePersistence};

    const SYS_PIECES: &[&str] = &[
        "system s",
        "system t # für",
        "description Messung α, (open",
        "state x, y",
        "state α",
        "states z = u0",
        "param a, b = 0.5",
        "param",
        "const k = 2, g",
        "input u, w",
        "input du = rate(u)",
        "input u0",
        "x' = a*y + u",
        "y' = -k*x + b*w*",
        "  sin(x - a)",
        "z' = (x +",
        "  y)",
        "x' = x^2 + é",
        "output h = x",
        "output m = atan2(y, x) - b",
        "restrict r: u = v, w = 2*v",
        "restrict q: w = k*u",
        "delay a",
        "# ein Kommentar ü",
        "",
        "\t",
    ];

    const EFF_PIECES: &[&str] = &[
        "model calib",
        "effect e1",
        "effect e2 # größe",
        "description für α",
        "param kb",
        "param T = 0.2, s",
        "state va = v",
        "va' = (wR - va)/T",
        "const later",
        "input dwR = rate(wR)",
        "subst wR = wR - kb*dwR, wL = wL",
        "output beta = (1 + kb)*beta",
        "compare wR = wL",
        "delay kb",
        "mu' = -mu",
        "",
    ];

    /// A valid system: BASE's statements in any order (declarations may come
    /// in any order), with comments and blank lines between them.
    fn valid_sys() -> impl Strategy<Value = String> {
        let lines: Vec<&'static str> = BASE.lines().collect();
        (
            Just(lines).prop_shuffle(),
            prop::collection::vec(
                prop::sample::select(&["", "# für α", "\t# tab", "  "][..]),
                0..4,
            ),
            prop::sample::select(&["\n", "\r\n", "\r"][..]),
            any::<bool>(),
        )
            .prop_map(|(mut lines, extra, nl, bom)| {
                for (i, c) in extra.into_iter().enumerate() {
                    lines.insert((i * 3) % (lines.len() + 1), c);
                }
                let bom = if bom { "\u{feff}" } else { "" };
                format!("{bom}{}{nl}", lines.join(nl))
            })
    }

    /// Same names, restrictions and normal forms, compared exactly: each
    /// entry of `a`'s forms printed, re-read in `b`'s context, and subtracted.
    fn equivalent(a: &System, b: &System) -> Result<(), TestCaseError> {
        let kinds = |s: &System| -> Vec<(String, obsan_model::Kind)> {
            s.decls.iter().map(|d| (d.name.clone(), d.kind)).collect()
        };
        prop_assert_eq!(kinds(a), kinds(b));
        prop_assert_eq!(a.output_names(), b.output_names());
        prop_assert_eq!(a.restrictions.len(), b.restrictions.len());
        let mut names = vec![None];
        names.extend(a.restrictions.iter().map(|r| Some(r.name.as_str())));
        for r in names {
            let (Ok(mut x), Ok(mut y)) = (a.normal_form(r, &[]), b.normal_form(r, &[])) else {
                prop_assert_eq!(a.normal_form(r, &[]).is_ok(), b.normal_form(r, &[]).is_ok());
                continue;
            };
            prop_assert_eq!(&x.state, &y.state);
            prop_assert_eq!(&x.inputs, &y.inputs);
            let xs: Vec<_> =
                x.f0.iter()
                    .chain(x.fields.iter().flatten())
                    .chain(x.outputs.iter().map(|o| &o.1))
                    .copied()
                    .collect();
            let ys: Vec<_> =
                y.f0.iter()
                    .chain(y.fields.iter().flatten())
                    .chain(y.outputs.iter().map(|o| &o.1))
                    .copied()
                    .collect();
            prop_assert_eq!(xs.len(), ys.len());
            for (i, j) in xs.into_iter().zip(ys) {
                let text = x.ctx.to_text(i);
                let back = y.parse_expr(&text, true);
                prop_assert!(back.is_ok(), "'{}' does not re-parse", text);
                let d = y.ctx.sub(back.unwrap(), j);
                prop_assert!(y.ctx.is_identically_zero(d), "'{}' changed", text);
            }
        }
        Ok(())
    }

    fn file(pieces: &'static [&'static str]) -> impl Strategy<Value = String> {
        (
            prop::collection::vec(prop::sample::select(pieces), 0..14),
            prop::sample::select(&["\n", "\r\n", "\r"][..]),
            any::<bool>(),
            any::<bool>(),
        )
            .prop_map(|(lines, nl, bom, final_nl)| {
                let mut s = if bom {
                    "\u{feff}".to_string()
                } else {
                    String::new()
                };
                s.push_str(&lines.join(nl));
                if final_nl {
                    s.push_str(nl);
                }
                s
            })
    }

    #[derive(Clone, Debug)]
    enum Edit {
        Delete(usize),
        Insert(usize, u8),
        Swap(usize, usize),
        Truncate(usize),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        let byte = prop::sample::select(
            &b"()+-*/^=,:'#\n\r \t0123456789xyzuab_\xC3\xA9\xCE\xB1\xFF\xEF\xBB\xBF"[..],
        );
        prop_oneof![
            any::<usize>().prop_map(Edit::Delete),
            (any::<usize>(), byte).prop_map(|(i, b)| Edit::Insert(i, b)),
            (any::<usize>(), any::<usize>()).prop_map(|(i, j)| Edit::Swap(i, j)),
            any::<usize>().prop_map(Edit::Truncate),
        ]
    }

    fn mutate(src: &str, edits: &[Edit]) -> Vec<u8> {
        let mut b = src.as_bytes().to_vec();
        for e in edits {
            let n = b.len().max(1);
            match *e {
                Edit::Delete(i) if !b.is_empty() => {
                    b.remove(i % n);
                }
                Edit::Insert(i, c) => b.insert(i % (b.len() + 1), c),
                Edit::Swap(i, j) if !b.is_empty() => b.swap(i % n, j % n),
                Edit::Truncate(i) => b.truncate(i % (b.len() + 1)),
                _ => {}
            }
        }
        b
    }

    /// A rejection names the file and, if it has a place, it is in the text.
    fn located(e: &ModelError, origin: &str, text: &str) -> Result<(), TestCaseError> {
        let shown = e.to_string();
        prop_assert!(shown.starts_with(origin), "origin not named: {}", shown);
        if let (Some(l), Some(c)) = (e.line, e.col) {
            let lines: Vec<&str> = text.split('\n').collect();
            prop_assert!(l >= 1 && l <= lines.len(), "line {} outside: {}", l, shown);
            let len = lines[l - 1].chars().count();
            prop_assert!(c >= 1 && c <= len + 1, "column {} outside: {}", c, shown);
        } else {
            // Only whole-file problems have no place.
            prop_assert!(
                e.message.starts_with("no ")
                    || e.message.starts_with("the system has no")
                    || e.message.contains("effect '"),
                "an error without a place: {}",
                shown
            );
        }
        Ok(())
    }

    fn config() -> Config {
        Config {
            cases: 400,
            failure_persistence: Some(Box::new(FileFailurePersistence::SourceParallel(
                "proptest-regressions",
            ))),
            ..Config::default()
        }
    }

    proptest! {
        #![proptest_config(config())]

        #[test]
        fn sys_reader_never_panics_and_locates(src in prop_oneof![file(SYS_PIECES), valid_sys()], edits in prop::collection::vec(edit(), 0..4)) {
            let bytes = mutate(&src, &edits);
            let text = match decode_text(&bytes, "p.sys") {
                Ok(t) => t,
                Err(e) => {
                    let lossy = String::from_utf8_lossy(&bytes);
                    return located(&e, "p.sys", &obsan_model::normalize_text(&lossy));
                }
            };
            // The reader normalizes by itself too: raw text reads the same.
            let raw = String::from_utf8_lossy(&bytes).into_owned();
            let (a, b) = (System::parse(&text, "p.sys"), System::parse(&raw, "p.sys"));
            prop_assert_eq!(a.as_ref().err(), b.as_ref().err());
            match a {
                Err(e) => located(&e, "p.sys", &text)?,
                Ok(s) => {
                    let back = System::parse(&s.to_sys_text(), "printed.sys");
                    prop_assert!(back.is_ok(), "printed text not re-read: {:?}", back.err());
                    equivalent(&s, &back.unwrap())?;
                }
            }
        }

        #[test]
        fn shuffled_valid_files_read_as_the_plain_one(src in valid_sys()) {
            let s = System::parse(&src, "p.sys");
            prop_assert!(s.is_ok(), "{:?}", s.err());
            equivalent(&s.unwrap(), &System::parse(BASE, "base.sys").unwrap())?;
        }

        #[test]
        fn eff_reader_never_panics_and_locates(src in file(EFF_PIECES), edits in prop::collection::vec(edit(), 0..6)) {
            let calib = System::parse(include_str!("../../../systems/calib.sys"), "calib.sys").unwrap();
            let bytes = mutate(&src, &edits);
            let text = match decode_text(&bytes, "p.eff") {
                Ok(t) => t,
                Err(e) => {
                    let lossy = String::from_utf8_lossy(&bytes);
                    return located(&e, "p.eff", &obsan_model::normalize_text(&lossy));
                }
            };
            match EffectLibrary::parse(&text, "p.eff") {
                Err(e) => located(&e, "p.eff", &text)?,
                Ok(lib) => {
                    let _ = lib.check(&calib);
                    for e in &lib.effects {
                        if let Err(err) = calib.extend(&[e], "p.eff") {
                            prop_assert!(err.to_string().starts_with("p.eff:"), "{}", err);
                        }
                    }
                }
            }
        }
    }
}
