#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The command line behaves like the tools people know: a closed pipe ends it
//! quietly, `--help` gives one line per command, an error is said once.

use std::process::{Command, Output, Stdio};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::samples;

fn omnimvs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_omnimvs"))
}

fn output(args: &[&str]) -> Output {
    omnimvs().args(args).output().expect("run omnimvs")
}

/// `omnimvs info DATASET | head -5` where `head` has already gone: the reading
/// end of stdout is closed before the program writes its first line.
#[test]
fn a_closed_stdout_ends_info_quietly() {
    let dataset = samples().join("sunny_single");
    assert!(
        dataset.is_dir(),
        "the real samples are missing: {}",
        dataset.display()
    );
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = omnimvs()
        .arg("info")
        .arg(&dataset)
        .stdout(Stdio::from(writer))
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.is_empty(), "expected a quiet end, got: {stderr}");
    // 141 is what a shell reports for a writer stopped by SIGPIPE.
    assert_eq!(o.status.code(), Some(141), "{:?}", o.status);
}

#[test]
fn help_lists_one_line_per_command_and_the_detail_is_in_the_command_help() {
    let o = output(&["--help"]);
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    let commands: Vec<&str> = help
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .collect();
    assert!(commands.len() >= 11, "{help}");
    for line in &commands {
        assert!(line.len() <= 100, "summary too long: {line}");
    }
    let sgm = commands.iter().find(|l| l.trim_start().starts_with("sgm "));
    assert!(sgm.is_some_and(|l| l.contains("ZNCC")), "{help}");
    assert!(!help.contains("Writes per frame"), "{help}");

    let o = output(&["sgm", "--help"]);
    assert!(o.status.success());
    let detail = String::from_utf8_lossy(&o.stdout);
    assert!(detail.contains("Writes per frame"), "{detail}");
    assert!(detail.contains("semi-global"), "{detail}");
}

#[test]
fn a_missing_dataset_is_reported_once_with_its_path() {
    let o = output(&["info", "/nonexistent/dataset"]);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: /nonexistent/dataset"),
        "{stderr}"
    );
    assert_eq!(
        stderr.matches("No such file or directory").count(),
        1,
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
}
