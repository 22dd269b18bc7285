//! How the app uses the machine's cores. Two choices, both measured with `cargo bench --bench frame` on a
//! 2-core machine (README, "Threads"):
//! - the compute task pool gets every core. Bevy's default gives it only what the IO and async-compute pools
//!   leave — one thread on 2 cores — and with one compute thread every `par_iter` runs sequentially;
//! - on machines with at most [`SINGLE_THREADED_UP_TO`] cores the main world's schedules run on the
//!   single-threaded executor: the multi-threaded one wakes a worker thread for every system, which cost more
//!   (about 2 ms a frame) than running the app's light systems in parallel gained. Per-voxel systems still
//!   spread their work over every core;
//! - voxelization jobs run in a pool of their own whose threads run at a low priority ([`job_pool`]): a big
//!   model's seconds of voxelizing take only the time the frame leaves, and a second job runs beside it. A job
//!   is handed to that pool, not run from an async-compute thread ([`spawn_job`]): the async-compute pool has
//!   one thread on 2 cores, and Bevy's own tasks there (compiling pipelines) are waited for by frames.

use std::panic::{AssertUnwindSafe, catch_unwind};

use bevy::app::{TaskPoolOptions, TaskPoolPlugin};
use bevy::ecs::schedule::{Schedules, SingleThreadedExecutor};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task};

/// Machines with this many cores or fewer run the main schedules single-threaded.
pub const SINGLE_THREADED_UP_TO: usize = 2;

/// The task pools: the compute pool gets every core (the IO and async-compute pools keep Bevy's defaults).
pub fn task_pools() -> TaskPoolPlugin {
    let mut options = TaskPoolOptions::default();
    options.compute.min_threads = bevy::tasks::available_parallelism();
    TaskPoolPlugin { task_pool_options: options }
}

/// The rayon pool voxelization jobs run in: a thread per core, each at a low priority ([`JOB_NICENESS`]), so the
/// frame's threads (the main world, rendering, rayon's global pool that frame systems use) always run first and a
/// job takes only the time they leave. With more than one thread, a second job (another dropped file, a new
/// setting) starts while a long one runs instead of queuing behind it.
pub fn job_pool() -> &'static rayon::ThreadPool {
    static POOL: std::sync::OnceLock<rayon::ThreadPool> = std::sync::OnceLock::new();
    POOL.get_or_init(|| {
        let threads = bevy::tasks::available_parallelism().max(2);
        let builder = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("voxelize-{i}"))
            .start_handler(|_| lower_priority());
        builder.build().expect("the operating system starts the voxelization threads")
    })
}

/// The niceness of the voxelization threads (Linux: 0 is normal, 19 the lowest priority). At 10 a busy frame
/// thread gets about nine tenths of a core the two share.
pub const JOB_NICENESS: i32 = 10;

/// Lowers the calling thread's priority to [`JOB_NICENESS`] (Linux, where a thread has its own niceness; elsewhere
/// the threads keep the normal priority). A failure leaves the thread at the normal priority.
fn lower_priority() {
    #[cfg(target_os = "linux")]
    let _ = rustix::process::setpriority_process(Some(rustix::thread::gettid()), JOB_NICENESS);
}

/// Runs `work` in [`job_pool`]; the returned task (on the async-compute pool) waits for its result without
/// holding a thread, and yields `None` if the work panicked.
pub fn spawn_job<T: Send + 'static>(work: impl FnOnce() -> T + Send + 'static) -> Task<Option<T>> {
    let (sender, receiver) = async_channel::bounded(1);
    job_pool().spawn(move || {
        // The receiver is gone when the job's task was dropped (a stale job): nothing waits for the result.
        let _ = sender.send_blocking(catch_unwind(AssertUnwindSafe(work)));
    });
    AsyncComputeTaskPool::get().spawn(async move { receiver.recv().await.ok()?.ok() })
}

/// Whether a machine with `cores` cores runs the main schedules single-threaded.
pub fn single_threaded(cores: usize) -> bool {
    cores <= SINGLE_THREADED_UP_TO
}

/// Puts every schedule of the main world on the single-threaded executor when the machine is small (call
/// once all plugins have added their schedules). Returns how many schedules were switched.
pub fn choose_executor(app: &mut App) -> usize {
    if !single_threaded(bevy::tasks::available_parallelism()) {
        return 0;
    }
    let Some(mut schedules) = app.world_mut().get_resource_mut::<Schedules>() else { return 0 };
    let mut switched = 0;
    for (_, schedule) in schedules.iter_mut() {
        schedule.set_executor(SingleThreadedExecutor::new());
        switched += 1;
    }
    switched
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::tasks::{TaskPool, block_on};

    #[test]
    fn a_job_hands_back_its_result_and_a_panic_as_none() {
        AsyncComputeTaskPool::get_or_init(TaskPool::default);
        let thread = block_on(spawn_job(|| std::thread::current().name().map(str::to_owned)));
        let thread = thread.flatten().unwrap_or_default();
        assert!(thread.starts_with("voxelize-"), "the work runs in the job pool, not on {thread:?}");
        let panicked: Option<u32> = block_on(spawn_job(|| panic!("a malformed file the reader missed")));
        assert_eq!(panicked, None, "a panic comes back as None, not into the caller");
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn jobs_run_at_a_low_priority_and_a_second_runs_beside_the_first() {
        AsyncComputeTaskPool::get_or_init(TaskPool::default);
        let niceness = || rustix::process::getpriority_process(Some(rustix::thread::gettid())).ok();
        assert_eq!(block_on(spawn_job(niceness)), Some(Some(JOB_NICENESS)));
        // The first job waits for the second: it finishes only if the second starts while it runs.
        let (sender, receiver) = std::sync::mpsc::channel();
        let first = spawn_job(move || receiver.recv_timeout(std::time::Duration::from_secs(20)).is_ok());
        let second = spawn_job(move || sender.send(()).is_ok());
        assert_eq!(block_on(second), Some(true));
        assert_eq!(block_on(first), Some(true), "the second job waited for the first");
    }
}
