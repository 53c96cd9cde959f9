//! Standard output and error reports with the manners of the tools people know.
//!
//! `println!` panics when stdout is a pipe that the reader has closed
//! (`omnimvs info DATASET | head -5`); [`line()`] and [`text()`] (behind the `outln!` and
//! `out!` macros) end the program instead with the status of a process stopped by
//! `SIGPIPE`, and print nothing. [`error_chain`] says each cause of an error once.

use std::fmt;
use std::io::{self, Write};

/// Exit status of a process stopped by a broken pipe, as a shell reports it (128 + SIGPIPE).
pub const BROKEN_PIPE_STATUS: i32 = 141;

/// Writes `args` and a newline to stdout.
pub fn line(args: fmt::Arguments<'_>) {
    write_stdout(|w| writeln!(w, "{args}"));
}

/// Writes `args` to stdout.
pub fn text(args: fmt::Arguments<'_>) {
    write_stdout(|w| w.write_fmt(args));
}

fn write_stdout(write: impl FnOnce(&mut io::StdoutLock<'static>) -> io::Result<()>) {
    let mut stdout = io::stdout().lock();
    if let Err(e) = write(&mut stdout).and_then(|()| stdout.flush()) {
        if e.kind() == io::ErrorKind::BrokenPipe {
            // The reader has all it wanted: stop as `SIGPIPE` would, quietly.
            std::process::exit(BROKEN_PIPE_STATUS);
        }
        eprintln!("error: writing to standard output: {e}");
        std::process::exit(1);
    }
}

/// The error and its causes joined by `: `, leaving out a cause whose text the
/// message already holds (library errors often show their source in their own
/// text, so `{e:#}` would say "No such file or directory" twice).
pub fn error_chain(error: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if message.contains(&text) {
            continue;
        }
        if !message.is_empty() {
            message.push_str(": ");
        }
        message.push_str(&text);
    }
    message
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug)]
    struct WithSource {
        path: &'static str,
        source: io::Error,
    }

    impl fmt::Display for WithSource {
        fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "{}: {}", self.path, self.source)
        }
    }

    impl std::error::Error for WithSource {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.source)
        }
    }

    #[test]
    fn a_cause_already_in_the_message_is_said_once() {
        let e = anyhow::Error::new(WithSource {
            path: "/no/such/ds",
            source: io::Error::from(io::ErrorKind::NotFound),
        });
        let cause = io::Error::from(io::ErrorKind::NotFound).to_string();
        assert_eq!(error_chain(&e), format!("/no/such/ds: {cause}"));
    }

    #[test]
    fn context_and_new_causes_are_all_said() {
        let e = anyhow::Error::new(io::Error::other("disk full")).context("writing out.png");
        assert_eq!(error_chain(&e), "writing out.png: disk full");
    }
}
