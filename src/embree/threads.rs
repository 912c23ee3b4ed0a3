//! Threads that trace rays: rayon pools whose workers run with flush-to-zero and
//! denormals-are-zero set (as Embree asks of every thread that traces), with a bounded size.

/// Sets flush-to-zero and denormals-are-zero on the calling thread, as Embree asks of every
/// thread that traces rays.
pub fn enable_flush_to_zero() {
    #[cfg(target_arch = "x86_64")]
    {
        let mut csr: u32 = 0;
        // SAFETY: reads and writes this thread's MXCSR; FTZ (bit 15) and DAZ (bit 6) only change
        // how denormals are treated.
        unsafe {
            std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack));
            csr |= (1 << 15) | (1 << 6);
            std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack));
        }
    }
}

/// Whether flush-to-zero and denormals-are-zero are set on the calling thread.
pub fn flush_to_zero_enabled() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        let mut csr: u32 = 0;
        // SAFETY: reads this thread's MXCSR.
        unsafe { std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack)) };
        csr & ((1 << 15) | (1 << 6)) == (1 << 15) | (1 << 6)
    }
    #[cfg(not(target_arch = "x86_64"))]
    true
}

/// The most worker threads a pool may have. Far above any machine dpm runs on (tracing scales to
/// the cores, so more threads than cores only costs memory), and low enough that a mistyped
/// count (`--threads 100000`) is refused at once instead of spawning threads for minutes.
pub const MAX_THREADS: usize = 1024;

/// Why a rayon pool could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ThreadPoolError {
    #[error("{0} worker threads is more than the {MAX_THREADS} dpm allows (0: one per core)")]
    TooMany(usize),
    #[error("{0}")]
    Build(#[from] rayon::ThreadPoolBuildError),
}

/// A rayon pool whose workers all run with flush-to-zero set. `threads = 0` means all cores;
/// more than [`MAX_THREADS`] is refused.
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool, ThreadPoolError> {
    if threads > MAX_THREADS {
        return Err(ThreadPoolError::TooMany(threads));
    }
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| enable_flush_to_zero())
        .build()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_thread_counts_are_refused() {
        let err = thread_pool(100_000).unwrap_err();
        assert!(err.to_string().contains("1024"), "{err}");
        assert!(thread_pool(MAX_THREADS + 1).is_err());
        assert_eq!(thread_pool(3).unwrap().current_num_threads(), 3);
    }

    #[test]
    fn flush_to_zero_is_set_on_every_pool_worker() {
        let pool = thread_pool(2).unwrap();
        let all = pool.broadcast(|_| flush_to_zero_enabled());
        assert!(all.iter().all(|&b| b));
    }
}
