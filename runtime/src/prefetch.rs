//! Cache hints for the data one thread hands another: a batch slot the other core read last
//! is fetched, for writing, before it is filled ([`for_write`]); a slot the other core wrote
//! is fetched, for reading, a tick before it is read ([`for_read`]). Without them the copy
//! that fills or reads a slot waits for each of its cache lines in turn to come from the
//! other core (measured where they are used: `log::thread`, `ahead`). Hints only: they change
//! no value the program sees, and are no-ops off x86-64.

/// Fetches the cache lines of the `bytes` from `start` into this core's cache, for writing.
#[inline]
pub(crate) fn for_write<T>(start: *const T, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_ET0};
        each_line(start, bytes, |p| {
            // SAFETY: a prefetch is a hint: it reads nothing the program can observe and
            // never faults, whatever the address (`each_line` keeps the pointer arithmetic
            // defined), and SSE is part of every x86-64 processor.
            unsafe { _mm_prefetch::<_MM_HINT_ET0>(p) }
        });
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, bytes);
}

/// Fetches the cache lines of the `bytes` from `start` into this core's cache, for reading.
#[inline]
pub(crate) fn for_read<T>(start: *const T, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        each_line(start, bytes, |p| {
            // SAFETY: as in `for_write`.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p) }
        });
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, bytes);
}

/// Calls `hint` with an address in each 64-byte line of the `bytes` from `start`.
#[cfg(target_arch = "x86_64")]
#[inline]
fn each_line<T>(start: *const T, bytes: usize, mut hint: impl FnMut(*const i8)) {
    // From the start of the first line.
    let misalign = start.addr() % 64;
    let (start, bytes) = (start.cast::<i8>().wrapping_sub(misalign), bytes + misalign);
    let mut offset = 0;
    while offset < bytes {
        hint(start.wrapping_add(offset));
        offset += 64;
    }
}
