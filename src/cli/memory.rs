//! The process's memory policy. The daemon plans frame after frame, each
//! needing the same few frame-sized buffers (the cloud, its coordinate
//! planes, masks and labels): handing them back to the kernel between
//! frames only makes the next frame fault in and zero the same pages again.
//! A one-shot command has no next frame, and there the policy only costs:
//! main applies it to the commands that plan frame after frame. And, for
//! `weldseam bench`, the count of the heap a plan uses ([`heap_peak_of`]).

/// Keeps freed memory in the process for reuse: no `mmap` of its own for
/// any buffer up to twice a 2.3 MP frame, and no trimming of the heap.
/// `weldseam bench --quick --stages-only --runs 6` (21 plans of 2.3 MP
/// frames) took 133,000 page faults before and 19,000 after. Only
/// glibc's allocator has these settings; elsewhere this does nothing.
///
/// Not for a process that plans once: the fixed mmap threshold puts every
/// frame-sized buffer in the heap, where a freed one need not fit the next
/// request, and a one-shot `weldseam plan` of the 2.2 M point unorganized
/// V-butt frame peaked about 7 MB higher with it (4.1 instead of 3.9 times
/// its 26.2 MB of raw points; the trim threshold alone changes nothing).
pub fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // glibc's largest accepted threshold on 64-bit systems.
        const MMAP_THRESHOLD_BYTES: libc::c_int = 32 << 20;
        // SAFETY: mallopt only changes allocator parameters; it is called
        // before any thread starts, as glibc recommends.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES);
            libc::mallopt(libc::M_TRIM_THRESHOLD, libc::c_int::MAX);
        }
    }
}

/// With the `heap-count` feature the process counts its heap: every
/// allocation and free moves a live-bytes counter and its peak (two atomic
/// operations each, which the daemon, the same program, does without).
#[cfg(feature = "heap-count")]
#[global_allocator]
static HEAP: &peakmem_alloc::PeakMemAlloc<std::alloc::System> = &peakmem_alloc::INSTRUMENTED_SYSTEM;

/// Runs `f` and returns its result and the peak of the heap bytes live
/// while it ran, above those live when it started (a block allocated
/// before and freed meanwhile lowers the count, as a cloud handed to the
/// planner and freed there should); `None` without the `heap-count`
/// feature. Every thread's allocations count, so the caller runs nothing
/// else meanwhile.
pub fn heap_peak_of<T>(f: impl FnOnce() -> T) -> (T, Option<u64>) {
    #[cfg(feature = "heap-count")]
    {
        use peakmem_alloc::PeakMemAllocTrait;
        HEAP.reset_peak_memory();
        let result = f();
        (result, Some(HEAP.get_peak_memory() as u64))
    }
    #[cfg(not(feature = "heap-count"))]
    {
        (f(), None)
    }
}
