//! `cargo xtask kernel-campaign`: the long campaign of the AVR kernels against their twins
//! (`integration_tests::kernels`, classes of `integration_tests::kernel_edges`): per kernel,
//! a share of `--evaluations` values of its classes (every value of a class that fits, the
//! values nearest the edges first), seeded by `--seed`. Each kernel's run appends one JSON line
//! to the ledger (`--ledger`, default `target/kernel-campaign/ledger.jsonl`); the last lines
//! printed are the ledger's totals per kernel as Markdown (a table, and the evaluations by
//! class), also written into `BENCHMARKS.md` between its `kernel-campaign` markers.
//!
//! Usage: `kernel-campaign [--kernel NAME]... [--evaluations N] [--poses N] [--seed S]
//! [--ledger PATH] [--totals]` (`--totals`: run nothing, only print and write the totals) (kernels: the firmware's six by default: atan2_fixed, sin_cos_fixed, add,
//! sub, mul, sqrt; with `--poses` and no `--kernel`, none). `--poses N` also runs `N` random
//! body poses and foot targets through the firmware's IK end to end
//! (`integration_tests::end_to_end`), its figures as a ledger line of kernel `end-to-end`.
//! Exit status 1 when a kernel differs from its twin (the findings printed in hex) or the
//! end-to-end run has a verdict difference or an outlier.

use integration_tests::end_to_end;
use integration_tests::kernel_edges::{classes, plan};
use integration_tests::kernels::{run_plan, Harness, Kernel};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// The firmware's kernels, run by default.
const FIRMWARE_KERNELS: [Kernel; 6] = [
    Kernel::Atan2Fixed,
    Kernel::SinCosFixed,
    Kernel::Add,
    Kernel::Sub,
    Kernel::Mul,
    Kernel::Sqrt,
];

/// One ledger line.
#[derive(serde::Serialize, serde::Deserialize)]
struct Entry {
    kernel: String,
    seed: u64,
    evaluations: u64,
    mismatches: u64,
    seconds: f64,
    evaluations_per_s: f64,
    classes: Vec<(String, u64, u64)>,
}

fn usage(e: &str) -> ExitCode {
    eprintln!("kernel-campaign: {e}\nusage: kernel-campaign [--kernel NAME]... [--evaluations N] [--poses N] [--seed S] [--ledger PATH] [--totals]");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let mut kernels = Vec::new();
    let mut evaluations: u64 = 100_000_000;
    let mut seed: u64 = 1;
    let mut poses: u64 = 0;
    let mut totals_only = false;
    let mut ledger = PathBuf::from("target/kernel-campaign/ledger.jsonl");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or_else(|| format!("{name} needs a value"));
        let parsed = match a.as_str() {
            "--kernel" => value("--kernel").and_then(|v| {
                Kernel::named(&v)
                    .map(|k| kernels.push(k))
                    .ok_or_else(|| format!("--kernel {v}: no such kernel"))
            }),
            "--evaluations" => value("--evaluations").and_then(|v| {
                v.replace('_', "")
                    .parse()
                    .map(|n| evaluations = n)
                    .map_err(|e| format!("--evaluations {v}: {e}"))
            }),
            "--poses" => value("--poses").and_then(|v| {
                v.replace('_', "")
                    .parse()
                    .map(|n| poses = n)
                    .map_err(|e| format!("--poses {v}: {e}"))
            }),
            "--seed" => value("--seed").and_then(|v| {
                v.parse()
                    .map(|n| seed = n)
                    .map_err(|e| format!("--seed {v}: {e}"))
            }),
            "--ledger" => value("--ledger").map(|v| ledger = v.into()),
            "--totals" => {
                totals_only = true;
                Ok(())
            }
            other => Err(format!("unknown argument {other}")),
        };
        if let Err(e) = parsed {
            return usage(&e);
        }
    }
    if totals_only {
        print_totals(&ledger);
        return ExitCode::SUCCESS;
    }
    if kernels.is_empty() && poses == 0 {
        kernels = FIRMWARE_KERNELS.to_vec();
    }
    if let Some(dir) = ledger.parent() {
        std::fs::create_dir_all(dir).expect("the ledger's directory");
    }
    let mut failed = false;
    for kernel in kernels {
        let classes = classes(kernel);
        let share = plan(&classes, evaluations, seed ^ (kernel as u64) << 56);
        let mut harness = Harness::boot();
        let started = Instant::now();
        let mut next_report = 0.0;
        let report = run_plan(&mut harness, kernel, &classes, &share, |r| {
            let t = started.elapsed().as_secs_f64();
            if t >= next_report {
                eprintln!(
                    "{}: {} of {evaluations} evaluations ({:.1} %), {} mismatches, {:.0}/s, {:.0} s",
                    r.kernel,
                    r.evaluations,
                    100.0 * r.evaluations as f64 / evaluations as f64,
                    r.mismatches,
                    r.evaluations_per_s,
                    t
                );
                next_report = t + 30.0;
            }
        });
        let entry = Entry {
            kernel: report.kernel.clone(),
            seed,
            evaluations: report.evaluations,
            mismatches: report.mismatches,
            seconds: started.elapsed().as_secs_f64(),
            evaluations_per_s: report.evaluations_per_s,
            classes: report.classes.clone(),
        };
        append(&ledger, &entry);
        for f in &report.first_findings {
            eprintln!("FINDING {f}");
        }
        failed |= report.mismatches > 0;
    }
    if poses > 0 {
        let mut harness = Harness::boot();
        let started = Instant::now();
        let mut next_report = 0.0;
        let fig = end_to_end::run(&mut harness, poses, seed, |f| {
            let t = started.elapsed().as_secs_f64();
            if t >= next_report {
                eprintln!(
                    "end-to-end: {} of {poses} cases, {} outliers, {} verdict differences, {:.0} s",
                    f.cases, f.outliers, f.verdict_differences, t
                );
                next_report = t + 30.0;
            }
        });
        println!("{}", serde_json::to_string_pretty(&fig).expect("JSON"));
        let entry = Entry {
            kernel: "end-to-end".to_string(),
            seed,
            evaluations: fig.cases,
            mismatches: fig.outliers + fig.verdict_differences,
            seconds: started.elapsed().as_secs_f64(),
            evaluations_per_s: fig.cases as f64 / started.elapsed().as_secs_f64().max(1e-9),
            classes: vec![
                ("solved".to_string(), fig.solved, 0),
                (
                    "bit-identical to the host".to_string(),
                    fig.bit_identical,
                    0,
                ),
                (
                    "referenced against f64".to_string(),
                    fig.referenced,
                    fig.outliers,
                ),
                (
                    format!("max error vs f64 {:.3e} rad", fig.max_error_rad),
                    fig.referenced,
                    fig.outliers,
                ),
            ],
        };
        append(&ledger, &entry);
        failed |= fig.outliers + fig.verdict_differences > 0;
    }
    print_totals(&ledger);
    if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    }
}

/// Appends `entry` to the ledger as one JSON line.
fn append(ledger: &PathBuf, entry: &Entry) {
    let mut file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(ledger)
        .expect("the ledger opens");
    writeln!(file, "{}", serde_json::to_string(entry).expect("JSON")).expect("ledger write");
}

/// One kernel's totals over the ledger's runs.
struct Total {
    kernel: String,
    runs: u64,
    evaluations: u64,
    mismatches: u64,
    seconds: f64,
    rates: Vec<u64>,
    /// `(class, evaluations, mismatches)`, summed over the runs.
    classes: Vec<(String, u64, u64)>,
}

/// The ledger's totals per kernel as Markdown (a table, then each kernel's evaluations by
/// class), printed, and written into `BENCHMARKS.md` between its campaign markers when the
/// page has them.
fn print_totals(ledger: &PathBuf) {
    let text = std::fs::read_to_string(ledger).unwrap_or_default();
    let mut totals: Vec<Total> = Vec::new();
    for line in text.lines() {
        let Ok(e) = serde_json::from_str::<Entry>(line) else {
            continue;
        };
        let i = match totals.iter().position(|t| t.kernel == e.kernel) {
            Some(i) => i,
            None => {
                totals.push(Total {
                    kernel: e.kernel.clone(),
                    runs: 0,
                    evaluations: 0,
                    mismatches: 0,
                    seconds: 0.0,
                    rates: Vec::new(),
                    classes: Vec::new(),
                });
                totals.len() - 1
            }
        };
        let t = &mut totals[i];
        t.runs += 1;
        t.evaluations += e.evaluations;
        t.mismatches += e.mismatches;
        t.seconds += e.seconds;
        t.rates.push(e.evaluations_per_s as u64);
        for (class, n, bad) in e.classes {
            match t.classes.iter_mut().find(|c| c.0 == class) {
                Some(c) => {
                    c.1 += n;
                    c.2 += bad;
                }
                None => t.classes.push((class, n, bad)),
            }
        }
    }
    let mut md = String::from(
        "| kernel | runs | evaluations | mismatches | hours | evaluations/s (median run) |\n|---|---|---|---|---|---|\n",
    );
    for t in &mut totals {
        t.rates.sort_unstable();
        md += &format!(
            "| {} | {} | {} | {} | {:.2} | {} |\n",
            t.kernel,
            t.runs,
            t.evaluations,
            t.mismatches,
            t.seconds / 3600.0,
            t.rates[t.rates.len() / 2]
        );
    }
    for t in &totals {
        md += &format!(
            "\n<details><summary>{}: evaluations by class</summary>\n\n| class | evaluations | mismatches |\n|---|---|---|\n",
            t.kernel
        );
        for (class, n, bad) in &t.classes {
            md += &format!("| {class} | {n} | {bad} |\n");
        }
        md += "\n</details>\n";
    }
    print!("{md}");
    write_benchmarks(&md);
}

/// The markers of the campaign's section in `BENCHMARKS.md`.
const BEGIN: &str = "<!-- kernel-campaign:begin -->";
const END: &str = "<!-- kernel-campaign:end -->";

/// Replaces the text between the campaign markers of `BENCHMARKS.md` (in the current
/// directory) by `md`; nothing when the page or its markers are missing.
fn write_benchmarks(md: &str) {
    let path = std::path::Path::new("BENCHMARKS.md");
    let Ok(page) = std::fs::read_to_string(path) else {
        return;
    };
    let (Some(b), Some(e)) = (page.find(BEGIN), page.find(END)) else {
        return;
    };
    if e < b {
        return;
    }
    let new = format!("{}{BEGIN}\n{md}{}", &page[..b], &page[e..]);
    match std::fs::write(path, new) {
        Ok(()) => eprintln!(
            "kernel-campaign: the totals written into {}",
            path.display()
        ),
        Err(err) => eprintln!("kernel-campaign: cannot write {}: {err}", path.display()),
    }
}
