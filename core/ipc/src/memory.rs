//! Giving memory back to the system when the daemon goes idle.
//!
//! A daemon left running for a working day serves bursts of large requests from many threads.
//! glibc's allocator keeps what those threads freed in per-thread arenas, so the resident set
//! after a burst stays near its peak although nothing is in use. When the last running request
//! ends, [`release_free_memory`] asks the allocator to return its free pages (`malloc_trim`),
//! so that an idle daemon's resident set comes back to what it holds (scripts/soak.sh checks
//! it: within 10 % of the idle resident set after the warm-up).

/// Returns the allocator's free pages to the system (glibc's `malloc_trim(0)`: the top of every
/// arena and the whole free pages inside them); a no-op elsewhere. Takes a few milliseconds
/// on a heap of a few hundred megabytes, so it runs only when the daemon has nothing to do.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks and trims the allocator's own free lists.
    unsafe {
        libc::malloc_trim(0);
    }
}
