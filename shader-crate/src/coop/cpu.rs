//! CPU emulation of workgroups for [`Coop`] kernels (tests, benchmarks and CPU baselines).
//!
//! Every invocation is a stackful coroutine (`corosensei`) running the kernel closure; one OS
//! thread schedules all invocations of a workgroup in lock-step at every collective operation:
//!
//! 1. Each invocation of a subgroup runs until its next collective operation and *suspends* with
//!    a request: a shuffle (its value and source lane), a ballot (its vote), the subgroup barrier
//!    or the workgroup barrier — or it returns.
//! 2. When every lane of the subgroup waits on a subgroup operation, the scheduler checks that
//!    they all wait on the same kind, computes every lane's answer from the posted values (a
//!    shuffle reads the source lane's posted value, a ballot ORs the votes) and resumes each lane
//!    with it. Repeat until the whole subgroup waits on the barrier or has returned.
//! 3. When every subgroup waits on the barrier, all invocations are released (step 1 again).
//!
//! A switch costs tens of nanoseconds instead of the microseconds of the OS-thread emulation this
//! replaced, so a 2^20-key sort emulates in seconds. Workgroups are independent and spread over
//! the machine's cores; results come back in global invocation order.
//!
//! **Races.** Workgroup memory is plain cells owned by the workgroup's scheduler thread. Between
//! two barriers the invocations run one after another, each up to its next collective operation;
//! the order alternates between rounds (ascending lanes and subgroups, then descending), so a
//! kernel that reads another invocation's store without a barrier between them reads the old
//! value in one of the orders and fails its test.
//!
//! **Non-uniform control flow** (rule 1/2 of [`super`]) is detected, not hung on: lanes of a
//! subgroup waiting on different operations, or some of them returned while others wait, panic
//! with a message naming the subgroup and what each side waits on. A panicking invocation panics
//! the whole dispatch with its own message (the suspended invocations are unwound and dropped).
//!
//! Invocation `l` belongs to subgroup `l / width`, lane `l % width` — one of the mappings a GPU
//! may use; kernels read the built-ins and never rely on it.
use super::{Coop, SharedU32};
use corosensei::stack::DefaultStack;
use corosensei::{Coroutine, CoroutineResult, Yielder};
use std::cell::Cell;
use std::sync::Mutex;

/// Largest emulated subgroup: ballots carry 128 bits.
pub const MAX_WIDTH: u32 = 128;

/// Stack of one emulated invocation (debug builds of the kernels need more than release).
const STACK_BYTES: usize = 256 * 1024;

/// What a suspended invocation waits on.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Request {
    Shuffle { value: u32, src: u32 },
    Ballot(bool),
    SubgroupBarrier,
    Barrier,
}

impl Request {
    fn name(self) -> &'static str {
        match self {
            Request::Shuffle { .. } => "a shuffle",
            Request::Ballot(_) => "a ballot",
            Request::SubgroupBarrier => "the subgroup barrier",
            Request::Barrier => "the workgroup barrier",
        }
    }
}

/// The answer an invocation is resumed with (a shuffle's value in word 0, or a ballot's mask).
type Reply = [u32; 4];

/// One emulated invocation's view of its workgroup.
pub struct CpuCoop<'y> {
    width: u32,
    lane: u32,
    subgroup_id: u32,
    num_subgroups: u32,
    local_index: u32,
    yielder: &'y Yielder<Reply, Request>,
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
        self.yielder.suspend(Request::Shuffle { value: v, src })[0]
    }
    fn shuffle_xor(&self, v: u32, mask: u32) -> u32 {
        self.shuffle(v, (self.lane ^ mask) % self.width)
    }
    fn ballot(&self, pred: bool) -> [u32; 4] {
        self.yielder.suspend(Request::Ballot(pred))
    }
    fn workgroup_barrier(&self) {
        self.yielder.suspend(Request::Barrier);
    }
    fn subgroup_barrier(&self) {
        self.yielder.suspend(Request::SubgroupBarrier);
    }
    fn subgroup_storage_barrier(&self) {
        self.yielder.suspend(Request::SubgroupBarrier);
    }
}

/// One emulated invocation's handle on workgroup memory.
pub struct CpuShared<'a> {
    words: &'a [Cell<u32>],
}

impl SharedU32 for CpuShared<'_> {
    fn load(&self, i: u32) -> u32 {
        self.words[i as usize].get()
    }
    fn store(&mut self, i: u32, v: u32) {
        self.words[i as usize].set(v);
    }
    /// The invocations of a workgroup run one at a time: a plain read-modify-write is atomic.
    fn atomic_add(&mut self, i: u32, v: u32) -> u32 {
        let old = self.words[i as usize].get();
        self.words[i as usize].set(old.wrapping_add(v));
        old
    }
    fn atomic_or(&mut self, i: u32, v: u32) {
        self.words[i as usize].set(self.words[i as usize].get() | v);
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

/// Where one invocation stands between two scheduler steps.
enum State<R> {
    /// Runnable; resumed with this reply.
    Ready(Reply),
    Waiting(Request),
    Done(R),
}

/// Runs `groups` workgroups; returns each invocation's result in global invocation order
/// (`group * workgroup_size + local_index`). Workgroups run in parallel on the machine's cores.
pub fn run_workgroups<R, F>(emu: Emulation, groups: u32, kernel: F) -> Vec<R>
where
    R: Send,
    F: Fn(u32, &CpuCoop<'_>, &mut CpuShared<'_>) -> R + Sync,
{
    let Emulation { width, workgroup_size, .. } = emu;
    assert!(
        width.is_power_of_two() && width <= MAX_WIDTH,
        "subgroup width {width} must be a power of two <= {MAX_WIDTH}"
    );
    assert!(
        workgroup_size >= width && workgroup_size.is_multiple_of(width),
        "workgroup size {workgroup_size} must be a multiple of the subgroup width {width}"
    );
    // Enough groups per thread that the stacks' set-up is amortised.
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    let threads = threads.min(groups.div_ceil(4)).max(1);
    if threads == 1 {
        return Worker::new(emu).run(0..groups, &kernel);
    }
    let per = groups.div_ceil(threads);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let range = (t * per).min(groups)..((t + 1) * per).min(groups);
                let kernel = &kernel;
                s.spawn(move || Worker::new(emu).run(range, kernel))
            })
            .collect();
        let mut out = Vec::with_capacity((groups * workgroup_size) as usize);
        let mut first_panic = None;
        for h in handles {
            match h.join() {
                Ok(part) => out.extend(part),
                Err(p) => {
                    first_panic.get_or_insert(p);
                }
            }
        }
        // Re-raise the kernel's own panic (its message), not the scope's generic one.
        if let Some(p) = first_panic {
            std::panic::resume_unwind(p);
        }
        out
    })
}

/// Where workgroups that wait on each other (a chained scan) learn when the emulation starts and
/// ends each of them, so that they can tell a deadlock from a wait.
pub trait Residency: Sync {
    /// A thread starts workgroup `group`.
    fn launch(&self, group: u32);
    /// Workgroup `group` returned, or panicked.
    fn retire(&self, group: u32, panicked: bool);
}

/// Runs the workgroups `order[0], order[1], …` on `resident` threads: a thread launches the next
/// group of `order` when its previous one returned, as a GPU launches workgroups into free slots,
/// so at most `resident` groups run at once, and later groups of `order` start only when earlier
/// ones leave. Unlike [`run_workgroups`], workgroups may wait on each other (through `residency`,
/// which hears every launch and return). Results in group order (`order` is a permutation of
/// `0..order.len()`); a panic in any group fails the dispatch with its message.
pub fn run_workgroups_resident<R, F>(emu: Emulation, order: &[u32], resident: u32, residency: &dyn Residency, kernel: F) -> Vec<R>
where
    R: Send,
    F: Fn(u32, &CpuCoop<'_>, &mut CpuShared<'_>) -> R + Sync,
{
    use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
    use std::sync::atomic::{AtomicUsize, Ordering};
    let next = AtomicUsize::new(0);
    let results: Vec<Mutex<Option<Vec<R>>>> = order.iter().map(|_| Mutex::new(None)).collect();
    let first_panic = Mutex::new(None);
    std::thread::scope(|s| {
        for _ in 0..resident.max(1) {
            s.spawn(|| {
                let mut worker = Worker::new(emu);
                loop {
                    let at = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&group) = order.get(at) else { break };
                    residency.launch(group);
                    worker.shared.iter().for_each(|w| w.set(0));
                    let r = catch_unwind(AssertUnwindSafe(|| worker.group(group, &kernel)));
                    residency.retire(group, r.is_err());
                    match r {
                        Ok(out) => *results[group as usize].lock().unwrap_or_else(|e| e.into_inner()) = Some(out),
                        Err(p) => {
                            first_panic.lock().unwrap_or_else(|e| e.into_inner()).get_or_insert(p);
                            break;
                        }
                    }
                }
                worker.recycle();
            });
        }
    });
    if let Some(p) = first_panic.into_inner().unwrap_or_else(|e| e.into_inner()) {
        resume_unwind(p);
    }
    results.into_iter().flat_map(|r| r.into_inner().unwrap_or_else(|e| e.into_inner()).expect("every group ran")).collect()
}

/// One scheduler thread: the invocations' stacks and the workgroup memory, reused by every
/// workgroup it runs.
struct Worker {
    emu: Emulation,
    stacks: Vec<DefaultStack>,
    shared: Vec<Cell<u32>>,
}

/// Stacks of finished workers, reused by later dispatches: a fresh stack costs an `mmap`, a guard
/// page and a page fault per touched page, which dominated dispatches of small workgroups.
static STACK_POOL: Mutex<Vec<DefaultStack>> = Mutex::new(Vec::new());

/// Most stacks kept in [`STACK_POOL`] (128 MiB of address space, a few pages of each touched).
const POOL_CAPACITY: usize = 512;

impl Worker {
    fn new(emu: Emulation) -> Self {
        let n = emu.workgroup_size as usize;
        let mut stacks = {
            let mut pool = STACK_POOL.lock().unwrap_or_else(|e| e.into_inner());
            let keep = pool.len().saturating_sub(n);
            pool.split_off(keep)
        };
        while stacks.len() < n {
            stacks.push(DefaultStack::new(STACK_BYTES).expect("allocating an emulated invocation's stack"));
        }
        Self { emu, stacks, shared: (0..emu.shared_words).map(|_| Cell::new(0)).collect() }
    }

    fn run<R, F>(mut self, groups: std::ops::Range<u32>, kernel: &F) -> Vec<R>
    where
        F: Fn(u32, &CpuCoop<'_>, &mut CpuShared<'_>) -> R,
    {
        let mut out = Vec::with_capacity(groups.len() * self.emu.workgroup_size as usize);
        for group in groups {
            // Workgroup memory starts zeroed in every workgroup (a GPU leaves it undefined;
            // kernels here never read before writing).
            self.shared.iter().for_each(|w| w.set(0));
            out.extend(self.group(group, kernel));
        }
        self.recycle();
        out
    }

    /// Hands the stacks back to [`STACK_POOL`].
    fn recycle(mut self) {
        let mut pool = STACK_POOL.lock().unwrap_or_else(|e| e.into_inner());
        let room = POOL_CAPACITY.saturating_sub(pool.len());
        pool.extend(self.stacks.drain(..).take(room));
    }

    /// Runs one workgroup to completion (steps 1–3 of the module doc).
    fn group<R, F>(&mut self, group: u32, kernel: &F) -> Vec<R>
    where
        F: Fn(u32, &CpuCoop<'_>, &mut CpuShared<'_>) -> R,
    {
        let Emulation { width, workgroup_size, .. } = self.emu;
        let num_subgroups = workgroup_size / width;
        let shared = &self.shared[..];
        let mut coroutines: Vec<Coroutine<Reply, Request, R, &mut DefaultStack>> = self
            .stacks
            .iter_mut()
            .zip(0..)
            .map(|(stack, local_index)| {
                let body = move |yielder: &Yielder<Reply, Request>, _: Reply| {
                    let ctx = CpuCoop {
                        width,
                        lane: local_index % width,
                        subgroup_id: local_index / width,
                        num_subgroups,
                        local_index,
                        yielder,
                    };
                    kernel(group, &ctx, &mut CpuShared { words: shared })
                };
                // SAFETY: the body borrows `kernel`, `shared` and the stack, all of which outlive
                // `coroutines`: it is a local of this function, dropped (which unwinds any
                // suspended invocation) before they go, also on a panic; it is never leaked.
                unsafe { Coroutine::with_stack_unchecked(stack, body) }
            })
            .collect();
        let mut state: Vec<State<R>> = (0..workgroup_size).map(|_| State::Ready([0; 4])).collect();
        let mut round = 0u32;
        loop {
            // Alternate the order between rounds (see "Races" in the module doc).
            let backwards = round & 1 == 1;
            round = round.wrapping_add(1);
            for s in 0..num_subgroups {
                let s = if backwards { num_subgroups - 1 - s } else { s };
                let lanes = (s * width) as usize..((s + 1) * width) as usize;
                run_subgroup(&mut coroutines[lanes.clone()], &mut state[lanes], backwards, group, s);
            }
            // Every subgroup now waits on the barrier or has returned.
            let at_barrier = state.iter().filter(|st| matches!(st, State::Waiting(Request::Barrier))).count();
            if at_barrier == 0 {
                break;
            }
            if at_barrier < state.len() {
                let first_done = state.iter().position(|st| matches!(st, State::Done(_))).unwrap_or(0);
                panic!(
                    "workgroup {group}: {at_barrier} of {workgroup_size} invocations wait on the workgroup \
                     barrier while invocation {first_done} has returned (non-uniform control flow)"
                );
            }
            state.iter_mut().for_each(|st| *st = State::Ready([0; 4]));
        }
        drop(coroutines);
        state
            .into_iter()
            .map(|st| match st {
                State::Done(r) => r,
                _ => unreachable!("every invocation returned"),
            })
            .collect()
    }
}

/// Step 1–2 for one subgroup: runs its lanes from operation to operation until all of them wait
/// on the workgroup barrier or have returned.
fn run_subgroup<R>(
    coroutines: &mut [Coroutine<Reply, Request, R, &mut DefaultStack>],
    state: &mut [State<R>],
    backwards: bool,
    group: u32,
    subgroup: u32,
) {
    let width = state.len();
    loop {
        for i in 0..width {
            let lane = if backwards { width - 1 - i } else { i };
            if let State::Ready(reply) = state[lane] {
                state[lane] = match coroutines[lane].resume(reply) {
                    CoroutineResult::Yield(request) => State::Waiting(request),
                    CoroutineResult::Return(r) => State::Done(r),
                };
            }
        }
        let request = |st: &State<R>| match st {
            State::Waiting(r) => Some(*r),
            _ => None,
        };
        let kind = |st: &State<R>| request(st).map(|r| std::mem::discriminant(&r));
        if let Some(other) = (1..width).find(|&l| kind(&state[l]) != kind(&state[0])) {
            let describe = |st: &State<R>| match request(st) {
                Some(r) => format!("waits on {}", r.name()),
                None => "has returned".to_string(),
            };
            panic!(
                "workgroup {group}, subgroup {subgroup}: lane 0 {} but lane {other} {} \
                 (non-uniform control flow around a collective operation)",
                describe(&state[0]),
                describe(&state[other])
            );
        }
        match request(&state[0]) {
            Some(Request::Shuffle { .. }) => {
                let mut posted = [(0u32, 0u32); MAX_WIDTH as usize];
                for (p, st) in posted.iter_mut().zip(state.iter()) {
                    if let State::Waiting(Request::Shuffle { value, src }) = *st {
                        *p = (value, src);
                    }
                }
                for (st, &(_, src)) in state.iter_mut().zip(&posted) {
                    *st = State::Ready([posted[src as usize].0, 0, 0, 0]);
                }
            }
            Some(Request::Ballot(_)) => {
                let mut mask = [0u32; 4];
                for (l, st) in state.iter().enumerate() {
                    if let State::Waiting(Request::Ballot(true)) = st {
                        mask[l / 32] |= 1 << (l % 32);
                    }
                }
                state.iter_mut().for_each(|st| *st = State::Ready(mask));
            }
            Some(Request::SubgroupBarrier) => state.iter_mut().for_each(|st| *st = State::Ready([0; 4])),
            Some(Request::Barrier) | None => return,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn emu(width: u32, workgroup_size: u32, shared_words: usize) -> Emulation {
        Emulation { width, workgroup_size, shared_words }
    }

    /// Shuffles, ballots and the built-ins at every width the emulation supports, with several
    /// subgroups per workgroup and several workgroups.
    #[test]
    fn shuffle_and_ballot_follow_their_definitions() {
        for width in [1, 2, 4, 8, 16, 32, 64, 128] {
            let wg = 2 * width.max(4);
            let out = run_workgroups(emu(width, wg, 0), 3, |g, c, _| {
                let me = g * 1000 + c.local_index();
                let from_next = c.shuffle(me, (c.lane() + 1) % c.subgroup_size());
                let xor = c.shuffle_xor(me, 1);
                let odd = c.ballot(c.lane() % 2 == 1);
                (c.lane(), c.subgroup_id(), c.num_subgroups(), from_next, xor, odd)
            });
            assert_eq!(out.len(), 3 * wg as usize);
            for (i, &(lane, sg, nsg, from_next, xor, odd)) in out.iter().enumerate() {
                let (g, l) = (i as u32 / wg, i as u32 % wg);
                assert_eq!((lane, sg, nsg), (l % width, l / width, wg / width), "width {width}");
                assert_eq!(from_next, g * 1000 + sg * width + (lane + 1) % width, "width {width}");
                assert_eq!(xor, g * 1000 + sg * width + (lane ^ 1) % width, "width {width}");
                let mut expected = [0u32; 4];
                for k in (1..width).step_by(2) {
                    expected[(k / 32) as usize] |= 1 << (k % 32);
                }
                assert_eq!(odd, expected, "width {width}");
            }
        }
    }

    /// Workgroup memory written before a barrier is seen by every invocation after it.
    #[test]
    fn barrier_publishes_workgroup_memory() {
        let out = run_workgroups(emu(8, 64, 64), 5, |g, c, s| {
            s.store(c.local_index(), g * 100 + c.local_index());
            c.workgroup_barrier();
            let (prev, next) = ((c.local_index() + 63) % 64, (c.local_index() + 1) % 64);
            (s.load(prev), s.load(next))
        });
        for (i, &(prev, next)) in out.iter().enumerate() {
            let (g, l) = (i as u32 / 64, i as u32 % 64);
            assert_eq!((prev, next), (g * 100 + (l + 63) % 64, g * 100 + (l + 1) % 64));
        }
    }

    /// Without the barrier, some invocation reads a neighbour's slot before the neighbour wrote
    /// it — in one direction or the other, whatever the order the emulation runs them in — so a
    /// kernel missing a barrier fails its test.
    #[test]
    fn a_missing_barrier_is_observable() {
        for width in [4, 8, 64] {
            let out = run_workgroups(emu(width, 64, 64), 1, |_, c, s| {
                s.store(c.local_index(), c.local_index() + 1);
                let (prev, next) = ((c.local_index() + 63) % 64, (c.local_index() + 1) % 64);
                (s.load(prev), s.load(next))
            });
            let stale = out.iter().filter(|&&(p, n)| p == 0 || n == 0).count();
            assert!(stale > 0, "width {width}: every read saw its neighbour's store without a barrier");
        }
    }

    #[test]
    #[should_panic(expected = "lane 0 waits on a shuffle but lane 1 has returned")]
    fn lanes_skipping_a_shuffle_are_reported() {
        run_workgroups(emu(4, 4, 0), 1, |_, c, _| if c.lane() == 0 { c.shuffle(1, 0) } else { 0 });
    }

    #[test]
    #[should_panic(expected = "waits on a ballot but lane 2 waits on a shuffle")]
    fn lanes_at_different_operations_are_reported() {
        run_workgroups(emu(4, 4, 0), 1, |_, c, _| if c.lane() < 2 { c.ballot(true)[0] } else { c.shuffle(1, 0) });
    }

    #[test]
    #[should_panic(expected = "non-uniform control flow")]
    fn a_subgroup_skipping_the_barrier_is_reported() {
        run_workgroups(emu(4, 16, 0), 2, |_, c, _| {
            if c.subgroup_id() != 1 {
                c.workgroup_barrier();
            }
        });
    }

    /// A panic inside an invocation reaches the caller with its own message, from any worker
    /// thread, and the suspended invocations are unwound.
    #[test]
    #[should_panic(expected = "invocation 37 of workgroup 41")]
    fn a_panicking_invocation_fails_the_dispatch_with_its_message() {
        run_workgroups(emu(8, 64, 0), 64, |g, c, _| {
            c.workgroup_barrier();
            if g == 41 && c.local_index() == 37 {
                panic!("invocation 37 of workgroup 41");
            }
            c.shuffle(g, 0)
        });
    }
}
