//! CPU time and page faults of this process, for benchmarks on a shared machine and tests of the command line's
//! process set-up (included with `#[path]`).
#![allow(dead_code)] // each including target uses its own subset

/// Nanoseconds this process's threads have run on a CPU (Linux, from /proc/self/task/*/schedstat), `None`
/// elsewhere. A machine shared with other builds inflates it far less than wall time.
pub fn cpu_ns() -> Option<u64> {
    let tasks = std::fs::read_dir("/proc/self/task").ok()?;
    Some(tasks.flatten().filter_map(|task| task_cpu_ns(&task.file_name().to_string_lossy())).sum())
}

/// Nanoseconds thread `tid` of this process has run on a CPU (Linux: the first field of its schedstat).
pub fn task_cpu_ns(tid: &str) -> Option<u64> {
    std::fs::read_to_string(format!("/proc/self/task/{tid}/schedstat")).ok()?.split_whitespace().next()?.parse().ok()
}

/// The calling thread's id in this process (Linux: the first field of /proc/thread-self/stat).
pub fn thread_id() -> Option<String> {
    Some(std::fs::read_to_string("/proc/thread-self/stat").ok()?.split_whitespace().next()?.to_string())
}

/// Minor page faults of this process so far (Linux: field 10 of /proc/self/stat; 0 elsewhere).
pub fn minor_faults() -> u64 {
    faults_in("/proc/self/stat")
}

/// Minor page faults of the calling thread so far (Linux: field 10 of /proc/thread-self/stat; 0 elsewhere).
pub fn thread_minor_faults() -> u64 {
    faults_in("/proc/thread-self/stat")
}

/// Allocates `bytes` on the calling thread, writes every page and frees them; returns how much `faults` (a count of
/// page faults: [`minor_faults`], [`thread_minor_faults`]) rose meanwhile.
pub fn touch(bytes: usize, faults: fn() -> u64) -> u64 {
    let before = faults();
    let mut block = vec![0u8; bytes];
    for page in block.chunks_mut(4096) {
        page[0] = 1;
    }
    std::hint::black_box(&block);
    drop(block);
    faults() - before
}

/// The minor page faults a `stat` file of /proc lists (0 where it cannot be read).
fn faults_in(path: &str) -> u64 {
    let stat = std::fs::read_to_string(path).unwrap_or_default();
    // The fields after the command name, which is in parentheses and may hold spaces: minflt is the eighth.
    let fields = stat.rfind(')').map_or("", |end| &stat[end + 1..]);
    fields.split_whitespace().nth(7).and_then(|f| f.parse().ok()).unwrap_or(0)
}

/// The cores thread `tid` of this process may run on (Linux: `Cpus_allowed_list` of its status, expanded).
pub fn allowed_cores(tid: &str) -> Option<Vec<usize>> {
    let status = std::fs::read_to_string(format!("/proc/self/task/{tid}/status")).ok()?;
    let list = status.lines().find_map(|line| line.strip_prefix("Cpus_allowed_list:"))?.trim();
    let mut cores = Vec::new();
    for range in list.split(',') {
        let (first, last) = range.split_once('-').unwrap_or((range, range));
        cores.extend(first.parse::<usize>().ok()?..=last.parse().ok()?);
    }
    Some(cores)
}
