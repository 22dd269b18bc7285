//! The command line's pool, in a process of its own (every thread's heap fresh): within `cli::with_workers_awake` the
//! other worker readies its heap before it spins, so that the memory it allocates for its share of a voxelization is
//! handed out without page faults.
#![cfg(all(feature = "cli", target_os = "linux", target_env = "gnu"))]

#[path = "support/cpu.rs"]
mod cpu;

#[test]
fn the_other_worker_allocates_on_pages_it_touched_while_it_waited() {
    voxel_core::cli::prepare_process();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("a pool");
    let bytes = 2 << 20;
    let pages = (bytes / 4096) as u64;
    let (caller, others) = pool.install(|| {
        let caller = cpu::touch(bytes, cpu::thread_minor_faults);
        let index = rayon::current_thread_index();
        let others = voxel_core::cli::with_workers_awake(|| {
            // The other worker readies its heap meanwhile (a few milliseconds).
            std::thread::sleep(std::time::Duration::from_millis(200));
            rayon::broadcast(|context| {
                (Some(context.index()) != index).then(|| cpu::touch(bytes, cpu::thread_minor_faults))
            })
        });
        (caller, others.into_iter().flatten().collect::<Vec<_>>())
    });
    // The caller's heap, fresh, faults on (nearly) every page; the other worker's, readied, on next to none.
    assert!(caller > pages / 2, "the caller's first touch of {pages} pages took {caller} faults");
    assert_eq!(others.len(), 1, "one other worker");
    assert!(others[0] < pages / 16, "the other worker's touch of {pages} pages took {} faults", others[0]);
}
