//! How the app uses the machine's cores. Two choices, both measured with `cargo bench --bench frame` on a
//! 2-core machine (README, "Threads"):
//! - the compute task pool gets every core. Bevy's default gives it only what the IO and async-compute pools
//!   leave — one thread on 2 cores — and with one compute thread every `par_iter` runs sequentially;
//! - on machines with at most [`SINGLE_THREADED_UP_TO`] cores the main world's schedules run on the
//!   single-threaded executor: the multi-threaded one wakes a worker thread for every system, which cost more
//!   (about 2 ms a frame) than running the app's light systems in parallel gained. Per-voxel systems still
//!   spread their work over every core;
//! - jobs (voxelizations, the transition's layouts) run in pools of their own whose threads run at a low
//!   priority (`job_queue`): a big
//!   model's seconds of voxelizing take only the time the frame leaves, and a second job runs beside it in a
//!   second pool. A job is handed to those pools, not run from an async-compute thread ([`spawn_job`]): the
//!   async-compute pool has one thread on 2 cores, and Bevy's own tasks there (compiling pipelines) are waited
//!   for by frames.

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

/// Jobs (voxelizations, the transition's layouts) that run at once, each in a rayon pool of its own
/// (`job_queue`): a second job (another dropped file, a new setting) starts beside a long one, and a batch (every
/// model after a setting change, the one on screen first) runs this many at a time in the order it was queued.
pub const JOB_LANES: usize = 2;

/// A queued job.
type Job = Box<dyn FnOnce() + Send>;

/// The queue of jobs, served by [`JOB_LANES`] lanes: a lane is a thread that takes the next job and
/// runs it in the lane's rayon pool, a thread per core, each at a low priority ([`JOB_NICENESS`]), so the frame's
/// threads (the main world, rendering, rayon's global pool that frame systems use) always run first and a job takes
/// only the time they leave. One pool for all jobs would not do: its threads take a newly queued job only when no
/// job they have started has work left to split, so a second job would wait for the parallel passes of the first.
fn job_queue() -> &'static async_channel::Sender<Job> {
    static QUEUE: std::sync::OnceLock<async_channel::Sender<Job>> = std::sync::OnceLock::new();
    QUEUE.get_or_init(|| {
        let (sender, receiver) = async_channel::unbounded::<Job>();
        let threads = bevy::tasks::available_parallelism().max(2);
        for lane in 0..JOB_LANES {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .thread_name(move |i| format!("voxelize-{lane}-{i}"))
                .start_handler(|_| lower_priority())
                .build()
                .expect("the operating system starts the voxelization threads");
            let receiver = receiver.clone();
            std::thread::Builder::new()
                .name(format!("voxelize-{lane}"))
                .spawn(move || {
                    while let Ok(job) = receiver.recv_blocking() {
                        pool.install(job);
                    }
                })
                .expect("the operating system starts the voxelization threads");
        }
        sender
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

/// Queues `work` for the next free lane of `job_queue`; the returned task (on the async-compute pool) waits for
/// its result without holding a thread, and yields `None` if the work panicked.
pub fn spawn_job<T: Send + 'static>(work: impl FnOnce() -> T + Send + 'static) -> Task<Option<T>> {
    let (sender, receiver) = async_channel::bounded(1);
    // The queue is never closed (its lanes hold its receiver for good).
    let _ = job_queue().send_blocking(Box::new(move || {
        // The receiver is gone when the job's task was dropped (a stale job): nothing waits for the result.
        let _ = sender.send_blocking(catch_unwind(AssertUnwindSafe(work)));
    }));
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

    /// The lanes are shared by every test of the process: the checks that fill them run one after another here.
    #[test]
    fn jobs_run_in_lanes_at_a_low_priority_a_second_beside_a_busy_first() {
        AsyncComputeTaskPool::get_or_init(TaskPool::default);
        #[cfg(target_os = "linux")]
        a_job_runs_at_a_low_priority_and_a_second_beside_a_waiting_first();
        a_second_job_starts_while_the_first_keeps_its_threads_busy();
        a_batch_of_jobs_runs_a_lane_at_a_time_each();
    }

    #[cfg(target_os = "linux")]
    fn a_job_runs_at_a_low_priority_and_a_second_beside_a_waiting_first() {
        let niceness = || rustix::process::getpriority_process(Some(rustix::thread::gettid())).ok();
        assert_eq!(block_on(spawn_job(niceness)), Some(Some(JOB_NICENESS)));
        // The first job waits for the second: it finishes only if the second starts while it runs.
        let (sender, receiver) = std::sync::mpsc::channel();
        let first = spawn_job(move || receiver.recv_timeout(std::time::Duration::from_secs(20)).is_ok());
        let second = spawn_job(move || sender.send(()).is_ok());
        assert_eq!(block_on(second), Some(true));
        assert_eq!(block_on(first), Some(true), "the second job waited for the first");
    }

    fn a_second_job_starts_while_the_first_keeps_its_threads_busy() {
        use rayon::prelude::*;
        use std::sync::Arc;
        use std::sync::atomic::{AtomicBool, Ordering};
        use std::time::{Duration, Instant};
        let started = Arc::new(AtomicBool::new(false));
        let seen = Arc::clone(&started);
        // Parallel work that always has items left to split until the second job has run (or 10 s have passed):
        // the threads running it never run out of it, as a big model's passes keep them busy.
        let first = spawn_job(move || {
            let deadline = Instant::now() + Duration::from_secs(10);
            let stopped = (0..u64::MAX).into_par_iter().try_for_each(|_| {
                if seen.load(Ordering::Relaxed) {
                    return Err(true);
                }
                if Instant::now() > deadline {
                    return Err(false);
                }
                std::hint::spin_loop();
                Ok(())
            });
            stopped.err()
        });
        // Let the first job take its pool's threads before the second is queued.
        std::thread::sleep(Duration::from_millis(100));
        let second = spawn_job(move || started.store(true, Ordering::Relaxed));
        assert_eq!(block_on(second), Some(()));
        assert_eq!(block_on(first), Some(Some(true)), "the second job ran only once the first had given up");
    }

    fn a_batch_of_jobs_runs_a_lane_at_a_time_each() {
        use std::sync::Arc;
        use std::sync::atomic::{AtomicUsize, Ordering};
        let (running, most) = (Arc::new(AtomicUsize::new(0)), Arc::new(AtomicUsize::new(0)));
        let jobs: Vec<_> = (0..JOB_LANES + 2)
            .map(|_| {
                let (running, most) = (Arc::clone(&running), Arc::clone(&most));
                spawn_job(move || {
                    let now = running.fetch_add(1, Ordering::SeqCst) + 1;
                    most.fetch_max(now, Ordering::SeqCst);
                    std::thread::sleep(std::time::Duration::from_millis(150));
                    running.fetch_sub(1, Ordering::SeqCst);
                })
            })
            .collect();
        for job in jobs {
            assert_eq!(block_on(job), Some(()));
        }
        assert_eq!(most.load(Ordering::SeqCst), JOB_LANES, "jobs beyond the lanes wait for a free one");
    }
}
