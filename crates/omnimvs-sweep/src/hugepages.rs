//! Asks the kernel to back a large new buffer with huge pages where it can.
//!
//! A full-size lookup table is about 300 MB; filled through 4 KiB pages it takes some
//! 77 000 page faults, a sixth of the build's time. With transparent huge pages in
//! `madvise` mode (the default of most Linux distributions) the same buffer faults in
//! 2 MiB at a time. Elsewhere, or when the kernel refuses, this does nothing: the
//! contents are the same either way.

/// Advises huge pages for the whole 2 MiB-aligned part of `buf`, before it is written.
#[cfg(target_os = "linux")]
pub(crate) fn advise_huge_pages(buf: &mut [f32]) {
    const HUGE: usize = 2 << 20;
    let start = buf.as_mut_ptr() as usize;
    let end = start + std::mem::size_of_val(buf);
    let aligned_start = start.next_multiple_of(HUGE);
    let aligned_end = end - end % HUGE;
    if aligned_end <= aligned_start {
        return;
    }
    // SAFETY: the range lies inside `buf`, which this function borrows mutably; madvise
    // with MADV_HUGEPAGE changes how the pages are backed, never their contents, and its
    // failure (an old kernel, THP disabled) is harmless and ignored.
    #[allow(unsafe_code)]
    unsafe {
        libc::madvise(
            aligned_start as *mut libc::c_void,
            aligned_end - aligned_start,
            libc::MADV_HUGEPAGE,
        );
    }
}

/// Elsewhere: nothing to do.
#[cfg(not(target_os = "linux"))]
pub(crate) fn advise_huge_pages(_buf: &mut [f32]) {}
