//! Every parser a user's file reaches, run on its checked-in corpus (fuzz/corpus, the
//! regression inputs) and on 400 fresh mutations per target with a fixed seed: none may
//! panic. Longer runs: `cargo run --release --example fuzz_parsers -- --seconds 600`
//! (docs/reliability.md).

mod common;
mod fuzz;

#[test]
fn no_parser_panics_on_mutated_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let targets = fuzz::targets(tmp.path());
    assert_eq!(targets.len(), 14);
    let mut failures = Vec::new();
    for t in &targets {
        let rep = fuzz::fuzz(t, &fuzz::corpus(t.name), 0x5eed, 400, None, tmp.path());
        assert!(rep.runs >= 400);
        // Valid seeds parse (else the mutations would explore little but the error paths).
        assert_eq!(
            rep.rejected_seeds, 0,
            "{}: a seed or corpus file is rejected",
            t.name
        );
        for (input, msg) in rep.panics.iter().take(3) {
            let p = tmp
                .path()
                .join(format!("{}-panic-{}.bin", t.name, failures.len()));
            std::fs::write(&p, input).unwrap();
            failures.push(format!(
                "{}: {msg} (input of {} bytes)",
                t.name,
                input.len()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "parsers panicked:\n{}",
        failures.join("\n")
    );
}

#[test]
fn the_mutator_is_deterministic_and_changes_inputs() {
    let seed = b"{\"a\": [1, 2, 3.5], \"b\": \"x\"}".to_vec();
    let run = |s: u64| {
        let mut r = fuzz::Rng(s);
        (0..50)
            .map(|_| fuzz::mutate(&mut r, &seed, &seed))
            .collect::<Vec<_>>()
    };
    assert_eq!(run(7), run(7));
    assert!(run(7).iter().filter(|m| **m != seed).count() > 40);
}

#[test]
fn a_panicking_parser_is_caught_and_reported() {
    // The harness itself: a target that panics on some inputs must be reported.
    let tmp = tempfile::tempdir().unwrap();
    let t = fuzz::Target {
        name: "self_test",
        seeds: vec![b"{\"a\": 1}".to_vec()],
        run: |b, _| {
            if b.contains(&b'a') && b.len() != 8 {
                panic!("planted");
            }
            true
        },
    };
    let rep = fuzz::fuzz(&t, &[], 3, 200, None, tmp.path());
    assert!(!rep.panics.is_empty());
    assert!(rep.panics.iter().all(|(_, m)| m == "planted"));
}
