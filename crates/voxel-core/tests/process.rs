//! The command line's process set-up (`cli::prepare_process`), in a process of its own: after it, memory that was
//! freed is handed out again without a page fault.
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
