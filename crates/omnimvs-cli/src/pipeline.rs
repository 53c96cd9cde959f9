//! Frames through a method with their files read one frame ahead and written one frame
//! behind, on threads of their own.
//!
//! Decoding a frame's images and ground truth and encoding its outputs (TIFF, PNG, the
//! visualisation) run on one core each; done in turn with the method's parallel work they
//! leave a core idle. Here they overlap it. The outputs and the lines printed are the same as
//! frame by frame, in order; the first error stops the run.

use std::sync::mpsc;

use anyhow::Result;

/// Runs `frames` in order through `read` (on a reader thread, one frame ahead), `compute` (on
/// the calling thread) and `write` (on a writer thread, one frame behind).
///
/// # Errors
/// The first error of `read`, `compute` or `write`; a panic of the writer thread as an error.
pub fn run_frames<R: Send, E: Send>(
    frames: &[u32],
    read: impl Fn(u32) -> Result<R> + Send,
    mut compute: impl FnMut(u32, R) -> Result<E>,
    mut write: impl FnMut(u32, E) -> Result<()> + Send,
) -> Result<()> {
    std::thread::scope(|scope| {
        let (read_tx, read_rx) = mpsc::sync_channel::<(u32, Result<R>)>(1);
        let (done_tx, done_rx) = mpsc::sync_channel::<(u32, E)>(1);
        scope.spawn(move || {
            for &f in frames {
                let read = read(f);
                let failed = read.is_err();
                // A closed channel: the run stopped at an error.
                if read_tx.send((f, read)).is_err() || failed {
                    break;
                }
            }
        });
        let writer = scope.spawn(move || -> Result<()> {
            for (f, done) in done_rx {
                write(f, done)?;
            }
            Ok(())
        });
        let computed = (|| -> Result<()> {
            for (f, read) in read_rx {
                let done = compute(f, read?)?;
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
        computed?;
        written
    })
}
