//! An allocation-counting global allocator: the memory bound of the harness. Every parser
//! must size its allocations by its input; one that asks for more than [`SINGLE_CAP`] in one
//! request, or holds more than [`LIVE_CAP`] at once, fails the run. The allocator cannot
//! unwind (that is undefined behaviour), so past a cap it writes the input being run to
//! standard error and refuses the allocation, which aborts the process: a failed run whose
//! output names the input.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicPtr, AtomicUsize, Ordering};

/// Largest single allocation any parser may make on these small inputs.
pub const SINGLE_CAP: usize = 256 << 20;
/// Largest total live heap of the harness process.
pub const LIVE_CAP: usize = 1 << 30;

pub struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static LARGEST: AtomicUsize = AtomicUsize::new(0);
/// The input being run (pointer and length), shown if a cap is hit.
static INPUT: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
static INPUT_LEN: AtomicUsize = AtomicUsize::new(0);

std::thread_local! {
    /// The largest request made by this thread since [`reset_thread_largest`].
    static THREAD_LARGEST: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Starts measuring this thread's largest request afresh (other tests run beside it).
pub fn reset_thread_largest() {
    THREAD_LARGEST.with(|c| c.set(0));
}

/// This thread's largest request since [`reset_thread_largest`].
pub fn thread_largest() -> usize {
    THREAD_LARGEST.with(|c| c.get())
}

/// Registers the input about to run, for the message a breached cap writes.
pub fn set_input(bytes: &[u8]) {
    INPUT_LEN.store(bytes.len(), Ordering::SeqCst);
    INPUT.store(bytes.as_ptr() as *mut u8, Ordering::SeqCst);
}

/// Peak live bytes and the largest single request so far.
pub fn stats() -> (usize, usize) {
    (
        PEAK.load(Ordering::Relaxed),
        LARGEST.load(Ordering::Relaxed),
    )
}

fn write_stderr(bytes: &[u8]) {
    // SAFETY: writing a valid buffer to file descriptor 2; no allocation.
    unsafe {
        libc::write(2, bytes.as_ptr().cast(), bytes.len());
    }
}

fn breach(size: usize) {
    write_stderr(b"\nfuzz: memory cap exceeded (request of ");
    let mut digits = [0u8; 20];
    let mut n = size;
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    write_stderr(&digits[i..]);
    write_stderr(b" bytes); the input, up to 4096 bytes:\n");
    let (ptr, len) = (
        INPUT.load(Ordering::SeqCst),
        INPUT_LEN.load(Ordering::SeqCst),
    );
    if !ptr.is_null() {
        // SAFETY: the harness keeps the registered input alive while it runs.
        let input = unsafe { std::slice::from_raw_parts(ptr, len.min(4096)) };
        write_stderr(input);
    }
    write_stderr(b"\n");
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let size = layout.size();
        LARGEST.fetch_max(size, Ordering::Relaxed);
        // A const-initialised Cell has no destructor: safe to touch from the allocator, and
        // try_with leaves a thread being torn down alone.
        let _ = THREAD_LARGEST.try_with(|c| c.set(c.get().max(size)));
        let live = LIVE.fetch_add(size, Ordering::Relaxed) + size;
        if size > SINGLE_CAP || live > LIVE_CAP {
            LIVE.fetch_sub(size, Ordering::Relaxed);
            breach(size);
            return std::ptr::null_mut();
        }
        PEAK.fetch_max(live, Ordering::Relaxed);
        // SAFETY: forwarded with the caller's layout.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
        // SAFETY: `ptr` came from `alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
}
