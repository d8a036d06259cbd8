//! The memory a run really used, as the operating system counts it.

/// Peak resident memory of this process so far, in bytes: the kernel's
/// high-water mark of the resident set (`VmHWM` in `/proc/self/status`,
/// the figure `/usr/bin/time` and `getrusage` report as the maximum
/// resident set size). `None` where the system does not provide it (not
/// Linux). It counts the whole process: in Python, the interpreter too.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status_peak(&status)
}

/// `VmHWM` of a `/proc/<pid>/status` text, in bytes.
fn status_peak(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut it = line["VmHWM:".len()..].split_whitespace();
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
        assert_eq!(status_peak(s), Some(2048 * 1024));
        assert_eq!(status_peak("VmRSS:\t1 kB\n"), None);
        if cfg!(target_os = "linux") {
            // this process holds at least its own code and this buffer
            let big = vec![1u8; 32 << 20];
            let peak = peak_resident_bytes().expect("Linux has VmHWM");
            assert!(peak >= big.len() as u64, "{peak}");
            assert_eq!(big.iter().map(|&b| b as usize).sum::<usize>(), 32 << 20);
        }
    }
}
