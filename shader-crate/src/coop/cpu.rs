//! CPU emulation of a workgroup for [`Coop`] kernels (tests, benchmarks and CPU baselines).
//!
//! Every invocation of a workgroup is an OS thread running the kernel closure. Collective
//! operations synchronise in lock-step: a subgroup shuffle is "write my value to my lane slot —
//! subgroup barrier — read the source slot", a ballot likewise with one bit per lane, and
//! `workgroup_barrier` is a barrier over all invocations. Consecutive subgroup operations use
//! alternate banks of slots, so one barrier per operation suffices: operation `i + 2` writes the
//! bank of operation `i` only after the barrier of operation `i + 1`, which every lane reaches
//! after its read of operation `i`. Workgroup memory is a shared
//! array of relaxed atomics; the barriers (mutex + condvar) order the accesses, exactly as the
//! GPU's acquire/release barrier does, so a missing barrier shows up as a data race the tests can
//! observe. Invocation `l` belongs to subgroup `l / width`, lane `l % width` — one of the mappings
//! a GPU may use; kernels read the built-ins and never rely on it.
//!
//! Robustness: if an invocation panics, or if the invocations of a subgroup/workgroup do not all
//! reach the same collective operation (non-uniform control flow) within [`DEADLOCK_TIMEOUT`],
//! every waiting invocation panics with a message naming the barrier, so a broken kernel fails
//! its test instead of hanging it.
use super::{Coop, SharedU32};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// How long a barrier waits before declaring that an invocation never arrives.
pub const DEADLOCK_TIMEOUT: Duration = Duration::from_secs(60);

/// Largest emulated subgroup: ballots carry 128 bits.
pub const MAX_WIDTH: u32 = 128;

struct BarrierState {
    arrived: u32,
    generation: u64,
    poisoned: bool,
}

/// A reusable barrier that can be poisoned (a panicking invocation releases everyone).
struct PoisonBarrier {
    n: u32,
    what: &'static str,
    state: Mutex<BarrierState>,
    cv: Condvar,
}

impl PoisonBarrier {
    fn new(n: u32, what: &'static str) -> Self {
        Self {
            n,
            what,
            state: Mutex::new(BarrierState { arrived: 0, generation: 0, poisoned: false }),
            cv: Condvar::new(),
        }
    }

    fn wait(&self) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        if s.poisoned {
            panic!("{} barrier: another invocation panicked", self.what);
        }
        let gen = s.generation;
        s.arrived += 1;
        if s.arrived == self.n {
            s.arrived = 0;
            s.generation += 1;
            self.cv.notify_all();
            return;
        }
        while s.generation == gen && !s.poisoned {
            let (next, timeout) = self
                .cv
                .wait_timeout(s, DEADLOCK_TIMEOUT)
                .unwrap_or_else(|e| e.into_inner());
            s = next;
            if timeout.timed_out() && s.generation == gen {
                s.poisoned = true;
                self.cv.notify_all();
                panic!(
                    "{} barrier: only {} of {} invocations arrived (non-uniform control flow?)",
                    self.what, s.arrived, self.n
                );
            }
        }
        if s.poisoned && s.generation == gen {
            panic!("{} barrier: another invocation panicked", self.what);
        }
    }

    fn poison(&self) {
        let mut s = self.state.lock().unwrap_or_else(|e| e.into_inner());
        s.poisoned = true;
        self.cv.notify_all();
    }
}

struct SubgroupState {
    barrier: PoisonBarrier,
    /// Two banks of `width` slots / votes (alternate subgroup operations).
    slots: Vec<AtomicU32>,
    votes: Vec<AtomicBool>,
}

/// One emulated invocation's view of its workgroup.
pub struct CpuCoop<'a> {
    width: u32,
    lane: u32,
    subgroup_id: u32,
    num_subgroups: u32,
    local_index: u32,
    subgroup: &'a SubgroupState,
    workgroup: &'a PoisonBarrier,
    /// Subgroup operations so far (their parity picks the bank).
    ops: std::cell::Cell<u32>,
}

impl CpuCoop<'_> {
    /// First slot of the bank of the next subgroup operation.
    fn bank(&self) -> usize {
        let n = self.ops.get();
        self.ops.set(n.wrapping_add(1));
        (n & 1) as usize * self.width as usize
    }
}

impl Coop for CpuCoop<'_> {
    fn subgroup_size(&self) -> u32 {
        self.width
    }
    fn lane(&self) -> u32 {
        self.lane
    }
    fn subgroup_id(&self) -> u32 {
        self.subgroup_id
    }
    fn num_subgroups(&self) -> u32 {
        self.num_subgroups
    }
    fn local_index(&self) -> u32 {
        self.local_index
    }
    fn shuffle(&self, v: u32, src: u32) -> u32 {
        assert!(src < self.width, "shuffle source lane {src} >= subgroup width {}", self.width);
        let bank = self.bank();
        self.subgroup.slots[bank + self.lane as usize].store(v, Ordering::Relaxed);
        self.subgroup.barrier.wait();
        self.subgroup.slots[bank + src as usize].load(Ordering::Relaxed)
    }
    fn shuffle_xor(&self, v: u32, mask: u32) -> u32 {
        self.shuffle(v, (self.lane ^ mask) % self.width)
    }
    fn ballot(&self, pred: bool) -> [u32; 4] {
        let bank = self.bank();
        self.subgroup.votes[bank + self.lane as usize].store(pred, Ordering::Relaxed);
        self.subgroup.barrier.wait();
        let mut m = [0u32; 4];
        for (l, vote) in self.subgroup.votes[bank..bank + self.width as usize].iter().enumerate() {
            if vote.load(Ordering::Relaxed) {
                m[l / 32] |= 1 << (l % 32);
            }
        }
        m
    }
    fn workgroup_barrier(&self) {
        self.workgroup.wait();
    }
}

/// One emulated invocation's handle on workgroup memory.
pub struct CpuShared<'a> {
    words: &'a [AtomicU32],
}

impl SharedU32 for CpuShared<'_> {
    fn load(&self, i: u32) -> u32 {
        self.words[i as usize].load(Ordering::Relaxed)
    }
    fn store(&mut self, i: u32, v: u32) {
        self.words[i as usize].store(v, Ordering::Relaxed);
    }
}

/// Shape of an emulated dispatch.
#[derive(Clone, Copy, Debug)]
pub struct Emulation {
    /// Subgroup width (power of two, 1..=128).
    pub width: u32,
    /// Invocations per workgroup (a multiple of `width`).
    pub workgroup_size: u32,
    /// Words of workgroup memory.
    pub shared_words: usize,
}

/// Runs `groups` workgroups one after the other; returns each invocation's result in global
/// invocation order (`group * workgroup_size + local_index`).
pub fn run_workgroups<R, F>(emu: Emulation, groups: u32, kernel: F) -> Vec<R>
where
    R: Send,
    F: Fn(u32, &CpuCoop<'_>, &mut CpuShared<'_>) -> R + Sync,
{
    let Emulation { width, workgroup_size, shared_words } = emu;
    assert!(
        width.is_power_of_two() && width <= MAX_WIDTH,
        "subgroup width {width} must be a power of two <= {MAX_WIDTH}"
    );
    assert!(
        workgroup_size >= width && workgroup_size % width == 0,
        "workgroup size {workgroup_size} must be a multiple of the subgroup width {width}"
    );
    let num_subgroups = workgroup_size / width;
    let mut out = Vec::with_capacity((groups * workgroup_size) as usize);
    for group in 0..groups {
        let shared: Vec<AtomicU32> = (0..shared_words).map(|_| AtomicU32::new(0)).collect();
        let subgroups: Vec<SubgroupState> = (0..num_subgroups)
            .map(|_| SubgroupState {
                barrier: PoisonBarrier::new(width, "subgroup"),
                slots: (0..2 * width).map(|_| AtomicU32::new(0)).collect(),
                votes: (0..2 * width).map(|_| AtomicBool::new(false)).collect(),
            })
            .collect();
        let wg_barrier = PoisonBarrier::new(workgroup_size, "workgroup");
        let results: Vec<R> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..workgroup_size)
                .map(|local_index| {
                    let sg = &subgroups[(local_index / width) as usize];
                    let (kernel, shared, wg_barrier) = (&kernel, &shared, &wg_barrier);
                    std::thread::Builder::new()
                        .stack_size(256 * 1024)
                        .spawn_scoped(s, move || {
                            let ctx = CpuCoop {
                                width,
                                lane: local_index % width,
                                subgroup_id: local_index / width,
                                num_subgroups,
                                local_index,
                                subgroup: sg,
                                workgroup: wg_barrier,
                                ops: std::cell::Cell::new(0),
                            };
                            let mut mem = CpuShared { words: shared };
                            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                                kernel(group, &ctx, &mut mem)
                            }));
                            if r.is_err() {
                                sg.barrier.poison();
                                wg_barrier.poison();
                            }
                            r
                        })
                        .expect("spawning an emulated invocation")
                })
                .collect();
            let joined: Vec<_> = handles.into_iter().map(|h| h.join()).collect();
            let mut results = Vec::with_capacity(joined.len());
            let mut first_panic = None;
            for j in joined {
                match j {
                    Ok(Ok(r)) => results.push(r),
                    Ok(Err(p)) | Err(p) => {
                        first_panic.get_or_insert(p);
                    }
                }
            }
            if let Some(p) = first_panic {
                std::panic::resume_unwind(p);
            }
            results
        });
        out.extend(results);
    }
    out
}
