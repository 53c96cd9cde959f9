//! glibc's allocator told to keep freed memory in the process.
//!
//! burn allocates every tensor afresh, so the cascade network allocates and frees the same
//! few hundred megabytes of tensors in every frame. glibc serves blocks above its mmap
//! threshold with fresh `mmap`s and gives freed memory back to the system, so every frame
//! page-faults its tensors in again and the kernel zeroes each page: a fifth of the cascade's
//! CPU time on 4 frames was system time (`crates/omnimvs-net/README.md`, "Inference on a
//! CPU"). With `mmap` off for the heap and trimming off, freed blocks are reused and the peak
//! memory is unchanged (the process keeps what it peaked at, which it needed anyway).
//!
//! The user's own settings win: nothing is changed when `GLIBC_TUNABLES` names a
//! `glibc.malloc` tunable.

/// Largest `M_TRIM_THRESHOLD` that `mallopt` takes (an `int`): never trim below it.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const NEVER_TRIM_BYTES: libc::c_int = libc::c_int::MAX;

/// Applies the settings; returns whether it did (not on other C libraries, nor when the user
/// set malloc tunables).
pub fn keep_freed_memory() -> bool {
    let user_set = std::env::var_os("GLIBC_TUNABLES")
        .is_some_and(|v| v.to_string_lossy().contains("glibc.malloc."));
    !user_set && apply()
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
fn apply() -> bool {
    // SAFETY: `mallopt` only sets parameters of glibc's allocator; it takes the allocator's
    // own lock, and this runs at the start of `main`, before any thread of ours exists.
    // Blocks already allocated stay valid whatever the settings.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0) == 1
            && libc::mallopt(libc::M_TRIM_THRESHOLD, NEVER_TRIM_BYTES) == 1
    }
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
fn apply() -> bool {
    false
}
