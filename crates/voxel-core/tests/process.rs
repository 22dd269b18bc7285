//! The command line's process set-up, in a process of its own: after `cli::prepare_process`, memory that was freed is
//! handed out again without a page fault; within `cli::with_workers_awake`, the pool's other workers spin, and they
//! stop when it returns.
#![cfg(all(feature = "cli", target_os = "linux", target_env = "gnu"))]

/// This process's minor page faults so far (`minflt`, the 10th field of `/proc/self/stat`).
fn minor_faults() -> u64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    // The fields after the command name (which is in parentheses and may hold spaces): the state is field 3.
    let fields: Vec<&str> = stat.rsplit_once(')').expect("a command name").1.split_whitespace().collect();
    fields[7].parse().expect("minflt")
}

/// Allocates `bytes`, writes every page and frees them; returns the page faults that took.
fn touch(bytes: usize) -> u64 {
    let before = minor_faults();
    let mut block = vec![0u8; bytes];
    for page in block.chunks_mut(4096) {
        page[0] = 1;
    }
    std::hint::black_box(&block);
    drop(block);
    minor_faults() - before
}

#[test]
fn a_block_freed_before_is_reused_without_page_faults() {
    voxel_core::cli::prepare_process();
    let bytes = 8 << 20;
    let pages = (bytes / 4096) as u64;
    // The first touch faults on (nearly) every page; glibc's default would map the second block afresh and fault
    // on every page again (its threshold rises to 8 MiB, where a block of 8 MiB is still mapped).
    let first = touch(bytes);
    let second = touch(bytes);
    assert!(first > pages / 2, "the first touch of {pages} pages took {first} faults");
    assert!(second < pages / 16, "the second touch of {pages} pages took {second} faults (the first {first})");
}

/// The user and system CPU time of thread `tid` of this process so far, in clock ticks (`utime` + `stime`, the
/// 14th and 15th fields of its `stat`).
fn cpu_ticks(tid: &str) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/self/task/{tid}/stat")).expect("a thread's stat");
    let fields: Vec<&str> = stat.rsplit_once(')').expect("a command name").1.split_whitespace().collect();
    fields[11].parse::<u64>().expect("utime") + fields[12].parse::<u64>().expect("stime")
}

#[test]
fn the_other_workers_spin_while_the_work_runs_and_stop_when_it_returns() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("a pool");
    // Each worker's thread id: the first field of its own stat.
    let tids: Vec<String> = pool.broadcast(|_| {
        let stat = std::fs::read_to_string("/proc/thread-self/stat").expect("/proc/thread-self/stat");
        stat.split_whitespace().next().expect("a thread id").to_string()
    });
    let cpu = || tids.iter().map(|tid| cpu_ticks(tid)).sum::<u64>();
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
    // 300 ms is 30 ticks at the usual 100 a second: the awake worker takes most of them, then none.
    assert!(during >= 10, "{during} ticks of CPU while the work ran");
    assert!(after <= 3, "{after} ticks of CPU after it returned");
}
