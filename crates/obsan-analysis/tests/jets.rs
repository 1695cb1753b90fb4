//! The rank test by jets against the older symbolic route (an independent
//! computation: Lie derivatives built on the graph and differentiated), and
//! the paper's published ranks.

use obsan_analysis::{rank, rank_symbolic, RankOptions, RankReport};
use obsan_model::System;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn load(path: &str) -> System {
    let src = std::fs::read_to_string(format!("{ROOT}/{path}")).unwrap();
    System::parse(&src, path).unwrap()
}

fn both(sys: &System, input: Option<&str>, seed: u64) -> (RankReport, RankReport) {
    let mut nf = sys.normal_form(input, &[]).unwrap();
    let a = rank(
        &mut nf,
        RankOptions {
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    let mut nf = sys.normal_form(input, &[]).unwrap();
    let b = rank_symbolic(
        &mut nf,
        RankOptions {
            seed,
            ..Default::default()
        },
    )
    .unwrap();
    (a, b)
}

fn assert_same(what: &str, a: &RankReport, b: &RankReport) {
    assert_eq!(a.rank, b.rank, "{what}: rank");
    assert_eq!(a.basis, b.basis, "{what}: basis words");
    assert_eq!(a.observable, b.observable, "{what}: verdicts");
    assert_eq!(a.pivots, b.pivots, "{what}: pivots");
    assert_eq!(a.max_order, b.max_order, "{what}: order");
    assert!(a.degree_bound >= 1 && a.error_bound < 1e-6, "{what}: bound {}", a.degree_bound);
}

#[test]
fn jets_agree_with_the_symbolic_route_on_every_shipped_system() {
    let mut files: Vec<String> = Vec::new();
    for dir in ["systems", "systems/classic"] {
        for e in std::fs::read_dir(format!("{ROOT}/{dir}")).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "sys") {
                files.push(format!("{dir}/{}", p.file_name().unwrap().to_str().unwrap()));
            }
        }
    }
    files.sort();
    assert!(files.len() >= 15, "{files:?}");
    for f in &files {
        let sys = load(f);
        let mut restrictions: Vec<Option<String>> = vec![None];
        restrictions.extend(sys.restrictions.iter().map(|r| Some(r.name.clone())));
        for r in &restrictions {
            let (a, b) = both(&sys, r.as_deref(), 1);
            assert_same(&format!("{f} {r:?}"), &a, &b);
        }
    }
}
