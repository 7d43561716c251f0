//! How a process that holds large meshes asks glibc for their buffers.
//!
//! glibc maps an allocation of at least its *mmap threshold* on its own and unmaps it when it
//! is freed; smaller ones come from its heap, which keeps freed memory for reuse. The threshold
//! starts at 128 KiB but rises to the size of any mapped block that is freed (up to 32 MiB):
//! after the first mesh-sized buffer goes, the next ones come from the heap, interleaved with
//! small allocations, and a long-running daemon's resident memory grows with the heap's holes
//! from one job to the next (measured: the grid simplification of a 1 M-triangle torus at
//! 50 % took 1.29× its input in extra peak memory on a first call, 2.00× over three calls).
//! Fixing the threshold turns that rise off: every buffer of 4 MiB or more is its own mapping,
//! returned to the system the moment it is freed, and a call's peak is what it holds (1.31×
//! over three calls). 4 MiB rather than less: each mapping is faulted in afresh, and at 1 MiB
//! the adaptive simplifications ran 5–10 % slower; smaller buffers stay on the heap.

/// Buffers at least this large get their own mapping (see the module doc).
pub const LARGE_BUFFER: usize = 4 << 20;

/// Fixes glibc's mmap threshold at [`LARGE_BUFFER`] for this process (the daemon and the
/// benchmarks call it first thing). A no-op on other C libraries.
pub fn return_large_buffers_to_system() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes the allocator's tuning; it is called before any thread
    // is started and the value is within glibc's accepted range.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, LARGE_BUFFER as libc::c_int);
    }
}

/// Returns the allocator's free pages to the system (glibc's `malloc_trim(0)`: the top of every
/// arena and the whole free pages inside them); a no-op elsewhere.
///
/// The daemon calls it when its last running request ends: a daemon left running for a working
/// day serves bursts of large requests from many threads, and glibc keeps what those threads
/// freed in per-thread arenas, so
/// the resident set after a burst would stay near its peak although nothing is in use
/// (`scripts/soak.sh` checks it comes back). The benchmarks call it between timed calls for the
/// same reason, so that their peaks are the daemon's. Takes a few milliseconds on a heap of a
/// few hundred megabytes, so it runs only between jobs.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks and trims the allocator's own free lists.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// The global allocator of the daemon and the benchmarks: the system's, with every buffer of
/// [`LARGE_BUFFER`] or more backed by transparent huge pages where the kernel grants them on
/// request (`/sys/kernel/mm/transparent_hugepage/enabled` = `madvise`, the common default).
///
/// Why: each call's mesh-sized buffers are fresh mappings (see the module doc), and every 4 KiB
/// page of them is faulted in on first touch (issue 33, point 6: page faults were 16 % of the
/// samples). On a 2 M-triangle grid simplification, 7 calls in one process (the benchmark's
/// child), this advice took 113 000 faults down to 64 000 and the call's median from 103 to
/// 95 ms. The advice is a hint: where the kernel refuses it, or on other systems, this is
/// exactly [`std::alloc::System`].
///
/// Keeping freed heap between calls (`M_TRIM_THRESHOLD` at 64 MiB) saved another 13 % of the
/// time but raised the extra peak of a grid call at 50 % from 1.9× to 2.6× the input, past
/// issue 33's limit of 2×: not done.
pub struct LargePages;

// SAFETY: every method forwards to `System` with the same arguments and returns its result
// unchanged; the only addition is an `madvise` on memory `System` just handed out, which
// changes how the kernel backs the pages, never their contents or the allocation's bounds.
unsafe impl std::alloc::GlobalAlloc for LargePages {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: forwarded as is (the caller upholds `alloc`'s contract).
        let p = unsafe { std::alloc::System.alloc(layout) };
        advise_huge_pages(p, layout.size());
        p
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        advise_huge_pages(p, layout.size());
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: forwarded as is.
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        // SAFETY: forwarded as is.
        let p = unsafe { std::alloc::System.realloc(ptr, layout, new_size) };
        advise_huge_pages(p, new_size);
        p
    }
}

/// Asks the kernel to back the buffer `[p, p + len)` with huge pages when it is large; a
/// refusal is harmless and ignored. The advice covers the whole pages the buffer touches: a
/// buffer this large is a mapping of its own (see the module doc), which Linux ≥ 6.7 places on a
/// 2 MiB boundary, so the advice reaches from the mapping's start (glibc's chunk header sits
/// there, 16 bytes before `p`) and the first huge page is not lost to rounding `p` up.
#[cfg(target_os = "linux")]
fn advise_huge_pages(p: *mut u8, len: usize) {
    const PAGE: usize = 4096;
    if p.is_null() || len < LARGE_BUFFER {
        return;
    }
    let start = p as usize & !(PAGE - 1);
    let end = (p as usize + len).next_multiple_of(PAGE);
    // SAFETY: `[start, end)` is the span of whole pages holding an allocation just returned by
    // the system allocator, all mapped; MADV_HUGEPAGE only sets a flag on that mapping.
    unsafe {
        libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
    }
}

#[cfg(not(target_os = "linux"))]
fn advise_huge_pages(_: *mut u8, _: usize) {}

#[cfg(test)]
mod tests {
    use super::*;
    use std::alloc::{GlobalAlloc, Layout};

    /// Large and small blocks, fresh, zeroed and grown, keep their contents through the
    /// allocator (the advice must never change what a buffer holds).
    #[test]
    fn large_pages_keep_contents() {
        for &n in &[
            64usize,
            LARGE_BUFFER - 8,
            LARGE_BUFFER,
            3 * LARGE_BUFFER + 5,
        ] {
            let layout = Layout::from_size_align(n, 8).unwrap();
            // SAFETY: layouts of non-zero size; every block is freed with its own layout.
            unsafe {
                let z = LargePages.alloc_zeroed(layout);
                assert!(!z.is_null());
                assert!(std::slice::from_raw_parts(z, n).iter().all(|&b| b == 0));
                LargePages.dealloc(z, layout);
                let p = LargePages.alloc(layout);
                for i in 0..n {
                    *p.add(i) = (i % 251) as u8;
                }
                let q = LargePages.realloc(p, layout, 2 * n);
                assert!((0..n).all(|i| *q.add(i) == (i % 251) as u8), "size {n}");
                LargePages.dealloc(q, Layout::from_size_align(2 * n, 8).unwrap());
            }
        }
    }

    /// Where the kernel grants huge pages on request, a large buffer from the allocator gets
    /// them once touched (read back from `/proc/self/smaps`, the kernel's own account).
    #[cfg(target_os = "linux")]
    #[test]
    fn large_buffers_get_huge_pages() {
        let mode = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
            .unwrap_or_default();
        let n = 16 << 20;
        let layout = Layout::from_size_align(n, 8).unwrap();
        // SAFETY: a 16 MiB block, written within its bounds and freed with its layout.
        let huge_kib = unsafe {
            let p = LargePages.alloc(layout);
            std::ptr::write_bytes(p, 1, n);
            let kib = anon_huge_kib_at(p as usize);
            LargePages.dealloc(p, layout);
            kib
        };
        if mode.contains("[madvise]") || mode.contains("[always]") {
            assert!(
                huge_kib > 0,
                "no huge page backs a touched 16 MiB buffer (THP: {mode})"
            );
        } else {
            assert_eq!(
                huge_kib, 0,
                "THP is off ({mode}), yet huge pages were counted"
            );
        }
    }

    /// `AnonHugePages` of the mapping holding `addr`, in KiB.
    #[cfg(target_os = "linux")]
    fn anon_huge_kib_at(addr: usize) -> u64 {
        let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap();
        let mut inside = false;
        for line in smaps.lines() {
            let first = line.split_whitespace().next().unwrap_or("");
            if let Some((lo, hi)) = first.split_once('-')
                && let (Ok(lo), Ok(hi)) =
                    (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
            {
                inside = (lo..hi).contains(&addr);
            } else if inside && let Some(v) = line.strip_prefix("AnonHugePages:") {
                return v.trim().trim_end_matches("kB").trim().parse().unwrap();
            }
        }
        panic!("no mapping holds {addr:#x}")
    }
}
