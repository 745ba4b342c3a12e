//! What crosses the bus between the CPU and the GPU, counted where it happens: every map of a buffer
//! for reading (`GpuContext::read_buffer`, `read_texture`) and every write from the CPU
//! (`GpuContext::write_buffer`, `storage_init`, `uniform`, `write_texture`) goes through `gpu/` and
//! adds its bytes here. GPU timestamp queries are counted apart (`timestamps`): a frame's timings are
//! read back by design, its images are not.
//!
//! The counters are process-wide (one viewer or renderer a process); `Traffic::now` takes a
//! snapshot and `Traffic::since` the bytes moved after it. The viewer's stats report them per window
//! frame (`bytes_read_back`, `bytes_uploaded`).

use std::sync::atomic::{AtomicU64, Ordering};

static READ_BACK: AtomicU64 = AtomicU64::new(0);
static UPLOADED: AtomicU64 = AtomicU64::new(0);
static TIMESTAMPS: AtomicU64 = AtomicU64::new(0);
static BUFFERS_MADE: AtomicU64 = AtomicU64::new(0);

/// `bytes` mapped for reading on the CPU.
pub fn read_back(bytes: u64) {
    READ_BACK.fetch_add(bytes, Ordering::Relaxed);
}

/// `bytes` written to the GPU from the CPU.
pub fn uploaded(bytes: u64) {
    UPLOADED.fetch_add(bytes, Ordering::Relaxed);
}

/// `bytes` of GPU timestamp queries read back.
pub fn timestamps(bytes: u64) {
    TIMESTAMPS.fetch_add(bytes, Ordering::Relaxed);
}

/// A buffer made by `GpuContext::storage`, `storage_init` or `uniform` (`FVPL_TRACE_BUFFERS` prints
/// its label: which pass allocates in a frame).
pub fn buffer_made(label: &str) {
    BUFFERS_MADE.fetch_add(1, Ordering::Relaxed);
    if std::env::var_os("FVPL_TRACE_BUFFERS").is_some() {
        eprintln!("buffer made: {label}");
    }
}

/// Buffers made so far (`buffer_made`): a frame at a steady size should make none.
pub fn buffers_made() -> u64 {
    BUFFERS_MADE.load(Ordering::Relaxed)
}

/// The bytes moved since the process started (`now`), or between two snapshots (`since`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Traffic {
    pub read_back: u64,
    pub uploaded: u64,
    pub timestamps: u64,
}

impl Traffic {
    pub fn now() -> Traffic {
        Traffic {
            read_back: READ_BACK.load(Ordering::Relaxed),
            uploaded: UPLOADED.load(Ordering::Relaxed),
            timestamps: TIMESTAMPS.load(Ordering::Relaxed),
        }
    }

    /// The bytes moved from `earlier` to `self`.
    pub fn since(self, earlier: Traffic) -> Traffic {
        Traffic {
            read_back: self.read_back.saturating_sub(earlier.read_back),
            uploaded: self.uploaded.saturating_sub(earlier.uploaded),
            timestamps: self.timestamps.saturating_sub(earlier.timestamps),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counts add up and `since` subtracts (other tests may count at the same time, so only
    /// lower bounds hold across threads).
    #[test]
    fn counts_add_and_subtract() {
        let a = Traffic::now();
        read_back(100);
        uploaded(7);
        timestamps(16);
        let d = Traffic::now().since(a);
        assert!(
            d.read_back >= 100 && d.uploaded >= 7 && d.timestamps >= 16,
            "{d:?}"
        );
        assert_eq!(a.since(Traffic::now()), Traffic::default());
    }
}
