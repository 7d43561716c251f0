//! Peak memory of this process from `/proc/self/status`.

/// A field of `/proc/self/status` in KiB (`VmRSS`, `VmHWM`, ...); 0 when unavailable.
pub fn status_kib(key: &str) -> u64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/status") else {
        return 0;
    };
    s.lines()
        .find_map(|l| {
            let rest = l.strip_prefix(key)?.strip_prefix(':')?;
            rest.split_whitespace().next()?.parse().ok()
        })
        .unwrap_or(0)
}

/// Returns freed heap to the OS and resets the peak resident set (`VmHWM`) to the current
/// one, so that a later `VmHWM` is the peak of what ran in between. `false` when the kernel
/// refused the reset (then `VmHWM` still includes earlier peaks).
pub fn reset_peak() -> bool {
    // SAFETY: malloc_trim only releases free memory of glibc's heap (which only Linux has).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::malloc_trim(0);
    }
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}
