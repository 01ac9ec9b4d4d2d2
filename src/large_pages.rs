//! The command's allocator: the system's, with large blocks advised onto transparent huge
//! pages (Linux's `MADV_HUGEPAGE`).
//!
//! A scan's arrays are hundreds of megabytes (a 10 M-splat scene's splats alone are 480 MB),
//! and the mirror's rays, disk tests and coverage probes read them at random: with 4 KiB
//! pages most of those reads also miss the TLB, and every first touch of a fresh buffer is a
//! page fault. Where the system leaves huge pages to the program's choice (`madvise`, the
//! usual default), advising each large block onto them made the mirror's render of a 10 M
//! glossy terrain about 8 % faster, its photons 10–20 % (docs/measurements.md, "Dense scans on
//! the mirror: huge pages, and where the 10 M EM goes"). Blocks below `LARGE` are left as they
//! are: a few pages' misses are not worth a system call.

use std::alloc::{GlobalAlloc, Layout, System};

/// The system allocator, with blocks of `LARGE` bytes or more advised onto huge pages.
pub struct LargePages;

/// Blocks this large or larger are advised.
pub const LARGE: usize = 8 << 20;

/// The huge page's size on x86-64 and most AArch64 kernels; advising a range rounded to it
/// is harmless where the system's differs.
const HUGE_PAGE: usize = 2 << 20;

// SAFETY: every call is forwarded to `System` unchanged; `advise` only gives the kernel a
// hint about memory the block already owns, and changes neither its contents nor its layout.
unsafe impl GlobalAlloc for LargePages {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // A large zeroed block comes fresh from the kernel, untouched: advised before its
        // first touch, it is faulted in a huge page at a time.
        let p = unsafe { System.alloc_zeroed(layout) };
        advise(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, p: *mut u8, layout: Layout) {
        unsafe { System.dealloc(p, layout) }
    }

    unsafe fn realloc(&self, p: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, layout, new_size) };
        advise(q, new_size);
        q
    }
}

/// Advises the whole huge pages within `size` bytes at `p` onto huge pages, if the block is
/// large; a refusal (a kernel without them) changes nothing.
fn advise(p: *mut u8, size: usize) {
    #[cfg(target_os = "linux")]
    if !p.is_null() && size >= LARGE {
        let start = (p as usize).next_multiple_of(HUGE_PAGE);
        let end = (p as usize + size) / HUGE_PAGE * HUGE_PAGE;
        if end > start {
            // SAFETY: [start, end) lies within the block just allocated, which this process
            // owns; MADV_HUGEPAGE is a hint and cannot change the memory's contents.
            unsafe {
                libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (p, size);
}
