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
