//! Mutation fuzzing of every parser a user's file reaches (see tests/fuzz/mod.rs).
//!
//! Usage: cargo run --release --example fuzz_parsers -- [--seconds N] [--target NAME] [--seed S]
//!        [--write-corpus]
//! Runs each target for N seconds (default 60) and prints runs, panics, the slowest input and
//! the process's peak resident memory; panicking inputs are written to
//! fuzz/crashes/NAME-*.bin. `--write-corpus` writes the generated seeds to fuzz/corpus/NAME/.

#[path = "../tests/common/mod.rs"]
mod common; // its own `#![allow(dead_code)]` covers the helpers this example does not use
#[path = "../tests/fuzz/mod.rs"]
mod fuzz;

fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let val = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let seconds: f64 = val("--seconds")
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(60.0);
    let seed: u64 = val("--seed").map(|s| s.parse()).transpose()?.unwrap_or(1);
    let only = val("--target");
    let tmp = tempfile::tempdir()?;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz");
    // Panics are expected to be caught and reported, not printed one by one.
    std::panic::set_hook(Box::new(|_| {}));
    println!(
        "{:<16} {:>9} {:>9} {:>7} {:>11} {:>13}",
        "target", "runs", "accepted", "panics", "slowest ms", "peak RSS MiB"
    );
    for t in fuzz::targets(tmp.path()) {
        if only.as_deref().is_some_and(|o| o != t.name) {
            continue;
        }
        if args.iter().any(|a| a == "--write-corpus") {
            let d = root.join("corpus").join(t.name);
            std::fs::create_dir_all(&d)?;
            for (i, s) in t.seeds.iter().enumerate() {
                std::fs::write(d.join(format!("seed-{i}")), s)?;
            }
        }
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs_f64(seconds);
        let rep = fuzz::fuzz(
            &t,
            &fuzz::corpus(t.name),
            seed,
            u64::MAX,
            Some(deadline),
            tmp.path(),
        );
        for (i, (input, _)) in rep.panics.iter().take(20).enumerate() {
            std::fs::create_dir_all(root.join("crashes"))?;
            std::fs::write(
                root.join("crashes").join(format!("{}-{i}.bin", t.name)),
                input,
            )?;
        }
        let first = rep.panics.first().map(|p| p.1.clone()).unwrap_or_default();
        println!(
            "{:<16} {:>9} {:>9} {:>7} {:>11.1} {:>13.0}  {first}",
            t.name,
            rep.runs,
            rep.accepted,
            rep.panics.len(),
            rep.slowest_s * 1e3,
            peak_rss_mib()
        );
    }
    Ok(())
}
