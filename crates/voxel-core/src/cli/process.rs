//! How a command-line process is set up before it reads its first file: its thread pool and its allocator.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::progress::Settle;

/// Readies the calling process, from its main thread, to voxelize files: the allocator keeps the memory a read frees
/// ([`keep_freed_memory`]) and the calling thread joins the thread pool ([`join_pool`]). For a program's main
/// thread, which outlives every job, before its first file.
pub fn prepare_process() {
    keep_freed_memory();
    join_pool();
}

/// Makes the calling thread a worker of rayon's global thread pool, whose other workers start now (they come up
/// while the first file is read). A pass's parallel work then starts on this thread while the others wake, where a
/// thread outside the pool hands the work to a worker that may be asleep and waits for it (at each parallel step: a
/// fresh run of a small model at R=128 took up to 45 % longer). Does nothing when the pool is already built.
fn join_pool() {
    let _ = rayon::ThreadPoolBuilder::new().use_current_thread().build_global();
}

/// The size from which glibc's allocator maps a block of its own (and unmaps it when freed): its largest
/// setting, 32 MiB on 64-bit systems.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MAPPED_FROM: libc::c_int = 32 << 20;

/// The free memory at the top of glibc's heap from which the allocator returns it to the system.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const RETURNED_FROM: libc::c_int = 256 << 20;

/// Keeps the memory a read frees in the process, for the voxelization after it (glibc: elsewhere nothing to do).
///
/// By default glibc maps each block from 128 KiB up on its own and unmaps it when it is freed, and gives the heap's
/// free top back to the system from 128 KiB: a read's buffers and decoded textures go back to the system, and the
/// voxelization's lists (the shell's runs and their sort, a few hundred KB to a few MB for a model at R=128) land
/// on fresh pages, each touched first at the cost of a page fault (≈ 1.5–2.5 µs on a 2-core VM; CesiumMan's first
/// voxelization at R=128 took 330). With blocks up to [`MAPPED_FROM`] in the heap and up to [`RETURNED_FROM`] of
/// free heap kept, the voxelization reuses the pages the read touched (17–110 faults).
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: `mallopt` sets a parameter of glibc's allocator, which takes effect for later allocations (it locks the
    // allocator's arenas, MT-safe); it reads and writes no memory of ours. A value it does not accept leaves the
    // parameter as it was (it returns 0), which costs only the gain.
    #[allow(unsafe_code)]
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MAPPED_FROM);
        libc::mallopt(libc::M_TRIM_THRESHOLD, RETURNED_FROM);
    }
}

/// Runs `work` with the current thread pool's other workers kept awake until it returns: each spins (on a core other
/// than the caller's, when the caller is a worker too, as a command line's main thread is), running any job it finds
/// and otherwise yielding its core (to any thread that shares it). An idle rayon worker goes to sleep after a few
/// dozen rounds, and waking it again costs each parallel step that follows a serial one 30–45 µs on a 2-core VM,
/// during which the caller works alone: a small model's voxelization takes a dozen such steps in 2–5 ms. A worker
/// woken on the caller's core, or on a core the hypervisor has parked, may not run at all for milliseconds
/// ([`off_core`]). Meanwhile the caller keeps to its core ([`on_core`]), which the scheduler would otherwise move next to
/// a spinning worker now and then. Before it spins, each other worker readies its heap ([`warm_heap`]). For a command
/// line's main thread, whose pool has nothing else to do meanwhile (OpenMP runtimes spin the same way by default, and
/// bind threads to cores on request).
pub fn with_workers_awake<T>(work: impl FnOnce() -> T) -> T {
    let done = Arc::new(AtomicBool::new(false));
    let caller = rayon::current_thread_index();
    // A caller outside the pool waits for the pool's work: only a worker's core is kept for it.
    let core = caller.and(current_core());
    let flag = done.clone();
    rayon::spawn_broadcast(move |context| {
        if Some(context.index()) == caller {
            return;
        }
        let _moved = core.and_then(off_core);
        warm_heap(&flag);
        while !flag.load(Ordering::Relaxed) {
            if rayon::yield_now() != Some(rayon::Yield::Executed) {
                std::thread::yield_now();
            }
        }
    });
    let _settle = Settle(&done);
    let _kept = core.and_then(on_core);
    work()
}

/// The memory each other worker of [`with_workers_awake`] writes and frees before it spins ([`warm_heap`]).
const WARMED: usize = 4 << 20;

/// The memory [`warm_heap`] writes at a time before it looks for a job.
const WARM_STEP: usize = 64 << 10;

/// Writes a block of up to [`WARMED`] bytes on the calling thread's heap, [`WARM_STEP`] at a time, and frees it; stops
/// at the first job it finds between steps (a voxelization has started: the job runs) or once `done` is set. glibc gives
/// each thread a heap of its own, fresh in a new thread, and keeps freed memory ([`keep_freed_memory`]): the worker's
/// share of the first voxelization's lists then lands on pages already touched, where each first touch cost a page
/// fault while the main thread waited (CesiumMan at R=128: 74–81 faults, 6–9 after; the first voxelization's time over
/// the process's next ones, median of 21 processes, 0.345 → 0.236 ms). A worker spins through the read anyway: the
/// writes take its idle core while the main thread reads.
fn warm_heap(done: &AtomicBool) {
    let mut block: Vec<u8> = Vec::with_capacity(WARMED);
    while block.len() < WARMED && !done.load(Ordering::Relaxed) {
        block.resize(block.len() + WARM_STEP, 1);
        if rayon::yield_now() == Some(rayon::Yield::Executed) {
            break;
        }
    }
    std::hint::black_box(&block);
}

/// The core the calling thread runs on (where the system says: Linux with glibc).
fn current_core() -> Option<usize> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: `sched_getcpu` reads the calling thread's current CPU; it takes no arguments and touches no memory.
        #[allow(unsafe_code)]
        let core = unsafe { libc::sched_getcpu() };
        usize::try_from(core).ok()
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    None
}

/// Moves the calling thread off `core` until the returned guard drops, when it may run anywhere it could before
/// (`None` where it cannot move: no other core allowed, or the system refuses). A worker woken by a thread that runs
/// on one core of a 2-core VM was mostly placed on that same core, beside the caller, which it shares until the
/// scheduler moves one of them (often not within a small model's voxelization: half of the fresh runs of the Fox at
/// R=128 as slow as one thread), where a worker kept on the other core spins there from the start.
fn off_core(core: usize) -> Option<Allowed> {
    restrict(core, Cores::AllBut)
}

/// Keeps the calling thread on `core` until the returned guard drops, when it may run anywhere it could before
/// (`None` where `core` is not allowed or the system refuses). Left free, a command line's main thread was now and then
/// moved onto the core where the other worker spins, which it then shared while its own stood idle (fresh runs of
/// CesiumMan at R=128 as slow as one thread or slower, 6–8 ms, in 3–5 of 41).
fn on_core(core: usize) -> Option<Allowed> {
    restrict(core, Cores::Only)
}

/// Which cores [`restrict`] leaves a thread, of those it may run on.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Cores {
    /// The one core.
    Only,
    /// All but the one core.
    AllBut,
}

/// Restricts the calling thread, until the returned guard drops, to `cores` of those it may run on, by `core` (Linux
/// with glibc; `None` where that leaves no core, `core` is not allowed, or the system refuses).
fn restrict(core: usize, cores: Cores) -> Option<Allowed> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let size = std::mem::size_of::<libc::cpu_set_t>();
        // SAFETY: a zeroed `cpu_set_t` is an empty set; `sched_getaffinity` writes at most `size` bytes into it, and
        // `CPU_ISSET`, `CPU_SET` and `CPU_CLR` read or write within it (they ignore a core past its end).
        #[allow(unsafe_code)]
        let (before, allowed) = unsafe {
            let mut before: libc::cpu_set_t = std::mem::zeroed();
            if libc::sched_getaffinity(0, size, &mut before) != 0 || !libc::CPU_ISSET(core, &before) {
                return None;
            }
            let mut allowed = before;
            if cores == Cores::Only {
                allowed = std::mem::zeroed();
                libc::CPU_SET(core, &mut allowed);
            } else {
                libc::CPU_CLR(core, &mut allowed);
            }
            (before, allowed)
        };
        // SAFETY: `CPU_COUNT` reads the set; `sched_setaffinity` reads `size` bytes of it, which it holds.
        #[allow(unsafe_code)]
        let moved = unsafe { libc::CPU_COUNT(&allowed) > 0 && libc::sched_setaffinity(0, size, &allowed) == 0 };
        moved.then_some(Allowed(before))
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        let _ = (core, cores);
        None
    }
}

/// The cores a thread was allowed before [`restrict`]: allowed again when this drops.
struct Allowed(#[cfg(all(target_os = "linux", target_env = "gnu"))] libc::cpu_set_t);

impl Drop for Allowed {
    fn drop(&mut self) {
        #[cfg(all(target_os = "linux", target_env = "gnu"))]
        // SAFETY: as in `restrict`: the set holds `size_of::<cpu_set_t>()` bytes, which `sched_setaffinity` reads.
        #[allow(unsafe_code)]
        unsafe {
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &self.0);
        }
    }
}
