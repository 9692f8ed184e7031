//! [`keep_freed_memory`]: what a process running the model should do to glibc's allocator first;
//! and [`zeros`], how the runtime allocates a buffer whose size a file decides.

use crate::{Error, Result};

/// `len` zeros, or [`Error::OutOfMemory`] if the memory cannot be had: every buffer whose size a
/// file decides (a window, a camera's frame, the head's rows) is allocated so, so that a file can
/// never abort the process that loads it (a `vec!` that cannot be had aborts). The file's sizes
/// are bounded before (`pvt3_format::check_sizes`); this is what a machine smaller than the
/// bound gets.
pub(crate) fn zeros<T: Clone + Default>(len: usize, what: &'static str) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| Error::OutOfMemory { what, bytes: len.saturating_mul(std::mem::size_of::<T>()) })?;
    v.resize(len, T::default());
    Ok(v)
}

/// Keeps freed memory in the heap (glibc; nothing elsewhere). tract allocates every intermediate
/// tensor afresh on each run, and glibc hands large ones back to the kernel on free, so the next
/// run page-faults them in again: at batch 32 that halved the throughput, and a `[12000 × 40]`
/// product ran 6× slower (docs/deploy.md, docs/benchmarks.md step 18). glibc raises its threshold
/// by itself only after it has handed back a block of that size, so whether a process gets the
/// fast path otherwise depends on what it happened to allocate first.
///
/// # Safety
/// Call it at start-up, before the process starts other threads (glibc's `mallopt` is not
/// thread-safe).
pub unsafe fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: the caller guarantees no other thread exists yet (this function's contract).
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
    }
}
