//! Frames through a method with their files read one frame ahead and written one frame
//! behind, on threads of their own, timed by stage and stoppable by Ctrl-C.
//!
//! Decoding a frame's images and ground truth and encoding its outputs (TIFF, PNG, the
//! visualisation) run on one core each; done in turn with the method's parallel work they
//! leave a core idle. Here they overlap it. The outputs and the lines printed are the same as
//! frame by frame, in order; the first error stops the run. Ctrl-C (after
//! [`stop_on_ctrl_c`]) stops reading: the frames already read are estimated and written, so
//! every frame on disk is complete.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use anyhow::Result;

/// Set by Ctrl-C once [`stop_on_ctrl_c`] has been called: no frame is read after it.
static STOP: AtomicBool = AtomicBool::new(false);

/// Makes Ctrl-C stop a run after the frames in flight instead of ending the process (a second
/// Ctrl-C still ends it). Idempotent.
pub fn stop_on_ctrl_c() {
    static INSTALLED: AtomicBool = AtomicBool::new(false);
    if INSTALLED.swap(true, Ordering::SeqCst) {
        return;
    }
    let installed = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\nCtrl-C: stopping after the frames in flight (Ctrl-C again ends at once)");
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C will end the run at once: {e}");
    }
}

/// What a run did: how many frames it finished, whether Ctrl-C stopped it, and the time each
/// stage took.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunReport {
    /// Frames estimated and written.
    pub frames: usize,
    /// Whether Ctrl-C stopped the run before its last frame.
    pub stopped: bool,
    /// Wall time of the whole run.
    pub wall: Duration,
    /// Time spent reading, estimating and writing, summed over the frames.
    pub read: Duration,
    pub compute: Duration,
    pub write: Duration,
}

impl RunReport {
    /// The run's frames per second, wall clock.
    pub fn fps(&self) -> f64 {
        self.frames as f64 / self.wall.as_secs_f64().max(1e-9)
    }

    /// The line that sums the run up: frames per second, each stage's mean time, and the
    /// speed-up over one frame at a time (reading, estimating and writing in turn).
    pub fn summary(&self) -> String {
        if self.frames == 0 {
            return "no frame finished".into();
        }
        let per = |d: Duration| d.as_secs_f64() / self.frames as f64;
        let in_turn = per(self.read) + per(self.compute) + per(self.write);
        let wall = per(self.wall);
        format!(
            "{} frame(s) in {:.2} s: {:.2} frames/s; per frame read {:.3} s, estimate {:.3} s, \
             write {:.3} s, {:.3} s in turn: {:.2}x from overlapping them",
            self.frames,
            self.wall.as_secs_f64(),
            self.fps(),
            per(self.read),
            per(self.compute),
            per(self.write),
            in_turn,
            in_turn / wall.max(1e-9)
        )
    }
}

/// An error when Ctrl-C stopped the run (after its report and its `record` file were
/// written): the exit status says the run did not finish.
///
/// # Errors
/// The run was stopped.
pub fn check_not_stopped(report: &RunReport, asked: usize, record: &std::path::Path) -> Result<()> {
    if report.stopped {
        anyhow::bail!(
            "stopped by Ctrl-C: {} of {asked} frames written, each complete ({} lists them)",
            report.frames,
            record.display()
        );
    }
    Ok(())
}

/// Runs `frames` in order through `read` (on a reader thread, one frame ahead), `compute` (on
/// the calling thread) and `write` (on a writer thread, one frame behind), timing each stage.
///
/// # Errors
/// The first error of `read`, `compute` or `write`; a panic of the writer thread as an error.
pub fn run_frames<R: Send, E: Send>(
    frames: &[u32],
    read: impl Fn(u32) -> Result<R> + Send,
    mut compute: impl FnMut(u32, R) -> Result<E>,
    mut write: impl FnMut(u32, E) -> Result<()> + Send,
) -> Result<RunReport> {
    let started = Instant::now();
    std::thread::scope(|scope| {
        let (read_tx, read_rx) = mpsc::sync_channel::<(u32, Result<R>, Duration)>(1);
        let (done_tx, done_rx) = mpsc::sync_channel::<(u32, E)>(1);
        let reader = scope.spawn(move || -> bool {
            for &f in frames {
                if STOP.load(Ordering::SeqCst) {
                    return true;
                }
                let t = Instant::now();
                let read = read(f);
                let failed = read.is_err();
                // A closed channel: the run stopped at an error.
                if read_tx.send((f, read, t.elapsed())).is_err() || failed {
                    break;
                }
            }
            false
        });
        let writer = scope.spawn(move || -> Result<(usize, Duration)> {
            let (mut n, mut spent) = (0, Duration::ZERO);
            for (f, done) in done_rx {
                let t = Instant::now();
                write(f, done)?;
                spent += t.elapsed();
                n += 1;
            }
            Ok((n, spent))
        });
        let mut report = RunReport::default();
        let computed = (|| -> Result<()> {
            for (f, read, spent) in read_rx {
                report.read += spent;
                let t = Instant::now();
                let done = compute(f, read?)?;
                report.compute += t.elapsed();
                if done_tx.send((f, done)).is_err() {
                    break; // the writer stopped at an error, which it returns
                }
            }
            Ok(())
        })();
        drop(done_tx);
        let written = writer
            .join()
            .map_err(|_| anyhow::anyhow!("the thread writing the outputs panicked"))?;
        report.stopped = reader
            .join()
            .map_err(|_| anyhow::anyhow!("the thread reading the frames panicked"))?;
        computed?;
        (report.frames, report.write) = written?;
        report.wall = started.elapsed();
        Ok(report)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_go_through_in_order_and_are_counted() {
        let mut seen = Vec::new();
        let report = run_frames(
            &[3, 1, 2],
            |f| Ok(f * 10),
            |_, r| Ok(r + 1),
            |f, e| {
                seen.push((f, e));
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(seen, [(3, 31), (1, 11), (2, 21)]);
        assert_eq!(report.frames, 3);
        assert!(!report.stopped);
        assert!(report.summary().starts_with("3 frame(s) in"));
    }

    #[test]
    fn the_first_error_stops_the_run() {
        let err = run_frames(
            &[1, 2, 3],
            |f| {
                if f == 2 {
                    anyhow::bail!("frame {f} cannot be read")
                }
                Ok(f)
            },
            |_, r| Ok(r),
            |_, _| Ok(()),
        )
        .unwrap_err();
        assert!(err.to_string().contains("frame 2"), "{err}");
    }
}
