//! The memory a run really used, as the operating system counts it.

/// Peak resident memory of this process so far, in bytes: the kernel's
/// high-water mark of the resident set (`VmHWM` in `/proc/self/status`,
/// the figure `/usr/bin/time` and `getrusage` report as the maximum
/// resident set size). `None` where the system does not provide it (not
/// Linux). It counts the whole process: in Python, the interpreter too.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status_field(&status, "VmHWM:")
}

/// Resident memory of this process now, in bytes (`VmRSS`); `None` where
/// the system does not provide it.
pub fn resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status_field(&status, "VmRSS:")
}

/// Keep large allocations in their own memory maps (glibc): blocks of
/// 128 KiB and more are mapped on allocation and unmapped when freed.
///
/// glibc raises this threshold each time such a block is freed, up to
/// 32 MiB, so that the arrays a neighbour rebuild frees and allocates again
/// (a few MiB each at 10⁵–10⁶ discs) end up in the heap, where the holes
/// they leave are kept: a 10⁶-disc run then peaked at 288 bytes per disc
/// instead of 228. Called once by `efgdem` and the Python module at start;
/// it changes nothing elsewhere (other C libraries, other systems).
pub fn keep_large_allocations_mapped() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets a parameter of the allocator; 128 KiB is
    // glibc's own starting value, fixed instead of adapted.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 128 * 1024);
    }
}

/// The field `key` (`VmHWM:`, `VmRSS:`) of a `/proc/<pid>/status` text,
/// in bytes.
fn status_field(status: &str, key: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with(key))?;
    let mut it = line[key.len()..].split_whitespace();
    let v: u64 = it.next()?.parse().ok()?;
    match it.next() {
        Some("kB") => Some(v * 1024),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_high_water_mark() {
        let s = "Name:\tefgdem\nVmPeak:\t  999 kB\nVmHWM:\t   2048 kB\nVmRSS:\t 1024 kB\n";
        assert_eq!(status_field(s, "VmHWM:"), Some(2048 * 1024));
        assert_eq!(status_field(s, "VmRSS:"), Some(1024 * 1024));
        assert_eq!(status_field("VmRSS:\t1 kB\n", "VmHWM:"), None);
        if cfg!(target_os = "linux") {
            // this process holds at least its own code and this buffer
            let big = vec![1u8; 32 << 20];
            let peak = peak_resident_bytes().expect("Linux has VmHWM");
            assert!(peak >= big.len() as u64, "{peak}");
            assert_eq!(big.iter().map(|&b| b as usize).sum::<usize>(), 32 << 20);
        }
    }
}
