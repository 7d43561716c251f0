//! Resident memory of this process, from `/proc/self/status` (Linux).

/// One `/proc/self/status` field in KiB (`VmRSS`, `VmHWM`, ...); 0 when it cannot be read.
pub fn status_kib(key: &str) -> u64 {
    let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
        return 0;
    };
    status
        .lines()
        .find_map(|line| {
            let value = line.strip_prefix(key)?.strip_prefix(':')?;
            value.split_whitespace().next()?.parse().ok()
        })
        .unwrap_or(0)
}

/// Hands freed heap back to the OS and resets the peak resident set (`VmHWM`) to the current
/// resident set, so that a later `VmHWM` is the peak of what ran in between. Returns `false`
/// when the kernel refused the reset (the peak then still covers everything before).
pub fn reset_peak() -> bool {
    // SAFETY: malloc_trim only returns free pages of glibc's heap to the OS (Linux only).
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::malloc_trim(0);
    }
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// A resident-memory checkpoint: the resident set when taken, to measure a peak over it.
pub struct Baseline {
    /// `VmRSS` in KiB when the checkpoint was taken.
    pub rss_kib: u64,
    /// Whether the peak was reset at the checkpoint (see [`reset_peak`]).
    pub reset_ok: bool,
}

impl Baseline {
    /// Trims the heap, resets the peak and records the resident set.
    pub fn take() -> Baseline {
        let reset_ok = reset_peak();
        Baseline {
            rss_kib: status_kib("VmRSS"),
            reset_ok,
        }
    }

    /// Peak resident set since the checkpoint, over the checkpoint's resident set, in KiB.
    pub fn peak_over_kib(&self) -> u64 {
        status_kib("VmHWM").saturating_sub(self.rss_kib)
    }

    /// Current resident set over the checkpoint's, in KiB.
    pub fn rss_over_kib(&self) -> u64 {
        status_kib("VmRSS").saturating_sub(self.rss_kib)
    }
}
