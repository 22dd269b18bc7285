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

/// Runs `work` with the current thread pool's other workers kept awake until it returns: each spins, running any job
/// it finds and otherwise yielding its core (to any thread that shares it). An idle rayon worker goes to sleep after a
/// few dozen rounds, and waking it again costs each parallel step that follows a serial one 30–45 µs on a 2-core VM
/// (more where the hypervisor has parked the idle core), during which the caller works alone: a small model's
/// voxelization takes a dozen such steps in 2–5 ms. For a command line's main thread, whose pool has nothing else
/// to do meanwhile (OpenMP runtimes spin the same way by default).
pub fn with_workers_awake<T>(work: impl FnOnce() -> T) -> T {
    let done = Arc::new(AtomicBool::new(false));
    let caller = rayon::current_thread_index();
    let flag = done.clone();
    rayon::spawn_broadcast(move |context| {
        if Some(context.index()) == caller {
            return;
        }
        while !flag.load(Ordering::Relaxed) {
            if rayon::yield_now() != Some(rayon::Yield::Executed) {
                std::thread::yield_now();
            }
        }
    });
    let _settle = Settle(&done);
    work()
}
