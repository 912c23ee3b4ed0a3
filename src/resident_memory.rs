//! Peak resident memory of this process, as the kernel counts it (`VmHWM` in
//! `/proc/self/status`), for the memory figures reported after a render. Owns that reading only;
//! on systems without `/proc` it reports nothing rather than guessing.

/// Highest resident set size so far, in bytes; `None` where the kernel does not say.
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line
        .trim_start_matches("VmHWM:")
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_high_water_mark_in_bytes() {
        let status = "Name:\tdpm\nVmPeak:\t  999 kB\nVmHWM:\t    2048 kB\nVmRSS:\t 1 kB\n";
        assert_eq!(parse_vm_hwm(status), Some(2048 * 1024));
        assert_eq!(parse_vm_hwm("Name:\tdpm\n"), None);
        // This process has touched at least its own stack and binary.
        assert!(peak_resident_bytes().is_none_or(|b| b > 1 << 20));
    }

    #[test]
    fn covers_memory_that_was_touched() {
        let block = vec![1u8; 64 << 20];
        assert!(block.iter().step_by(4096).all(|&b| b == 1));
        if let Some(peak) = peak_resident_bytes() {
            assert!(peak >= 64 << 20, "{peak}");
        }
    }
}
