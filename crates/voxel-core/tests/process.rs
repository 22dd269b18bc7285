//! The command line's process set-up, in a process of its own: after `cli::prepare_process`, memory that was freed is
//! handed out again without a page fault; within `cli::with_workers_awake`, the pool's other workers spin, off the
//! caller's core, which the caller keeps to, and they stop when it returns, all free to run anywhere again.
#![cfg(all(feature = "cli", target_os = "linux", target_env = "gnu"))]

#[path = "support/cpu.rs"]
mod cpu;

#[test]
fn a_block_freed_before_is_reused_without_page_faults() {
    voxel_core::cli::prepare_process();
    let bytes = 8 << 20;
    let pages = (bytes / 4096) as u64;
    // The first touch faults on (nearly) every page; glibc's default would map the second block afresh and fault
    // on every page again (its threshold rises to 8 MiB, where a block of 8 MiB is still mapped).
    let first = cpu::touch(bytes, cpu::minor_faults);
    let second = cpu::touch(bytes, cpu::minor_faults);
    assert!(first > pages / 2, "the first touch of {pages} pages took {first} faults");
    assert!(second < pages / 16, "the second touch of {pages} pages took {second} faults (the first {first})");
}

/// A pool of two workers, and their thread ids.
fn pool_of_two() -> (rayon::ThreadPool, Vec<String>) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("a pool");
    let tids = pool.broadcast(|_| cpu::thread_id().expect("a thread id"));
    (pool, tids)
}

#[test]
fn the_other_workers_spin_while_the_work_runs_and_stop_when_it_returns() {
    let (pool, tids) = pool_of_two();
    let cpu = || tids.iter().map(|tid| cpu::task_cpu_ns(tid).expect("a thread's CPU time")).sum::<u64>() / 1_000_000;
    let pause = std::time::Duration::from_millis(300);
    let (during, after) = pool.install(|| {
        let start = cpu();
        // The caller (a worker) sleeps: only the other worker, kept awake, uses CPU meanwhile.
        let value = voxel_core::cli::with_workers_awake(|| {
            std::thread::sleep(pause);
            7
        });
        assert_eq!(value, 7);
        let returned = cpu();
        std::thread::sleep(pause);
        (returned - start, cpu() - returned)
    });
    // Of 300 ms, the awake worker runs most while the work runs, then next to none.
    assert!(during >= 100, "{during} ms of CPU while the work ran");
    assert!(after <= 30, "{after} ms of CPU after it returned");
}

#[test]
fn the_caller_keeps_to_its_core_and_the_other_workers_keep_off_it_while_the_work_runs() {
    let (pool, tids) = pool_of_two();
    let (caller, during, before, after) = pool.install(|| {
        let caller = cpu::thread_id().expect("a thread id");
        let other = tids.iter().find(|&tid| *tid != caller).expect("another worker").clone();
        let threads = [caller.clone(), other];
        let allowed = || threads.each_ref().map(|tid| cpu::allowed_cores(tid).expect("a thread's cores"));
        let before = allowed();
        let during = voxel_core::cli::with_workers_awake(|| {
            // The other worker moves when it takes up its spin.
            std::thread::sleep(std::time::Duration::from_millis(200));
            allowed()
        });
        std::thread::sleep(std::time::Duration::from_millis(50));
        (caller, during, before, allowed())
    });
    assert_eq!(after, before, "the caller's and the other worker's cores once the work returned");
    let [caller_during, other_during] = &during;
    let all = &before[1];
    if all.len() < 2 {
        assert_eq!(other_during, all, "one core: nowhere to move");
        return;
    }
    // The caller on one core (the one it ran on when the work started), the other worker on every other.
    assert_eq!(caller_during.len(), 1, "the caller {caller} on {caller_during:?} of {all:?}");
    let mut together = [caller_during.clone(), other_during.clone()].concat();
    together.sort_unstable();
    assert_eq!(&together, all, "caller {caller_during:?}, other {other_during:?}");
}
