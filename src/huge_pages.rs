//! Big arrays on 2 MiB pages where the kernel allows it: Linux's
//! transparent huge pages, which Debian enables in `madvise` mode, for the
//! memory a process asks for only. Traversal reads nodes and triangles at
//! random over hundreds of MiB, and with 4 KiB pages nearly every such read
//! also misses the TLB and walks the page tables: the CPU back end
//! rendered bumpy-5m (5 M triangles) at 1.24-1.27x and bumpy-1.31m at
//! 1.26-1.46x the samples/s with huge pages, and built the 5 M-triangle
//! BVH with half the page-fault time (docs/performance.md, "Huge pages").
//! Asking changes no value; where the kernel says no, the pages stay
//! small.

/// A huge page.
const HUGE_PAGE: usize = 2 << 20;

/// Arrays smaller than this are left alone: they hold at most a huge page
/// or two, and a system call each would cost more than it saves.
const WORTH_ASKING: usize = 4 * HUGE_PAGE;

/// Asks for huge pages under `v`'s whole capacity, written or not. Pages
/// already touched stay small until the kernel merges them, so call it
/// before the array is filled.
pub fn advise<T>(v: &Vec<T>) {
    let bytes = v.capacity() * size_of::<T>();
    if bytes < WORTH_ASKING {
        return;
    }
    #[cfg(target_os = "linux")]
    {
        let start = v.as_ptr() as usize;
        let lo = start.next_multiple_of(HUGE_PAGE);
        let hi = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
        if hi > lo {
            // SAFETY: MADV_HUGEPAGE changes how the kernel backs these pages,
            // never what they hold, and the range lies inside `v`'s
            // allocation. A refusal (an old kernel, huge pages off) is
            // harmless, so its result is not checked.
            unsafe {
                libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
            }
        }
    }
}

/// `Vec::with_capacity(n)`, advised before anything is written.
pub fn with_capacity<T>(n: usize) -> Vec<T> {
    let v = Vec::with_capacity(n);
    advise(&v);
    v
}

/// `n` zeroed items, advised before anything is written (the zeroed pages
/// of a fresh mapping are not touched until written).
pub fn zeroed_vec<T: bytemuck::Zeroable + Clone>(n: usize) -> Vec<T> {
    let v = bytemuck::zeroed_vec(n);
    advise(&v);
    v
}
