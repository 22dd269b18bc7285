//! CPU time of this process, for benchmarks on a shared machine (included with `#[path]`).

/// Nanoseconds this process's threads have run on a CPU (Linux, from /proc/self/task/*/schedstat), `None`
/// elsewhere. A machine shared with other builds inflates it far less than wall time.
pub fn cpu_ns() -> Option<u64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    let on_cpu = |task: std::fs::DirEntry| -> Option<u64> {
        std::fs::read_to_string(task.path().join("schedstat")).ok()?.split_whitespace().next()?.parse().ok()
    };
    Some(tasks.flatten().filter_map(on_cpu).sum())
}
