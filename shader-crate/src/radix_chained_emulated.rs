//! The chained-scan passes on the CPU, with workgroups run in orders the emulation chooses.
//!
//! Each pass's workgroups run on `resident` threads ([`run_workgroups_resident`]): a thread
//! launches the next workgroup of a launch order (ascending, descending, or a seeded shuffle)
//! when its previous one returned. The status words live on a [`Board`]; a look-back that finds
//! a word not ready blocks its thread until some workgroup publishes. When every running
//! workgroup is blocked and none can be launched (all threads busy, or nothing left to launch),
//! nothing can ever publish again: the board reports the deadlock as a panic naming the
//! schedule, instead of hanging. A sort that completes under every schedule tried shows that
//! the tile claim keeps each wait on a workgroup that is already running.
use super::*;
use crate::coop::cpu::{run_workgroups_resident, Emulation, Residency};
use crate::radix::emulated::{global_histogram_emulated, Out};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Condvar, Mutex};

/// The order workgroups are launched in, and how many run at once.
#[derive(Clone, Copy, Debug)]
pub struct Schedule {
    /// Threads, each running one workgroup at a time.
    pub resident: u32,
    pub order: Order,
}

#[derive(Clone, Copy, Debug)]
pub enum Order {
    Ascending,
    Descending,
    /// A permutation drawn from this seed.
    Shuffled(u32),
}

impl Schedule {
    /// Workgroup ids `0..groups` in launch order.
    pub fn launch_order(&self, groups: u32) -> Vec<u32> {
        let mut order: Vec<u32> = (0..groups).collect();
        match self.order {
            Order::Ascending => {}
            Order::Descending => order.reverse(),
            Order::Shuffled(seed) => {
                let mut x = seed | 1;
                for i in (1..order.len()).rev() {
                    x ^= x << 13;
                    x ^= x >> 17;
                    x ^= x << 5;
                    order.swap(i, x as usize % (i + 1));
                }
            }
        }
        order
    }
}

#[derive(Default)]
struct Occupancy {
    running: u32,
    blocked: u32,
    launched: u32,
    failed: bool,
}

/// Device memory of the chained scan (status words and tile counters) shared by the emulated
/// workgroups of one dispatch, with what the deadlock check needs.
pub struct Board {
    words: Vec<AtomicU32>,
    occupancy: Mutex<Occupancy>,
    changed: Condvar,
    resident: u32,
    groups: u32,
    schedule: String,
}

impl Board {
    pub fn new(words: u32, groups: u32, schedule: &Schedule) -> Self {
        Self {
            words: (0..words).map(|_| AtomicU32::new(0)).collect(),
            occupancy: Mutex::new(Occupancy::default()),
            changed: Condvar::new(),
            resident: schedule.resident.max(1),
            groups,
            schedule: format!("{schedule:?}"),
        }
    }

    fn occupancy(&self) -> std::sync::MutexGuard<'_, Occupancy> {
        self.occupancy.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Stores word `i` and wakes the blocked workgroups, if any: a waiter checks the word and
    /// counts itself blocked under the lock taken here after the store, so it either saw the
    /// word or is counted. (Waking nobody saves a futex call per publish: 256 per tile.)
    pub fn publish(&self, i: u32, v: u32) {
        self.words[i as usize].store(v, Ordering::SeqCst);
        if self.occupancy().blocked > 0 {
            self.changed.notify_all();
        }
    }

    /// Word `i` once `ready` holds for it; blocks while it does not, and panics when no
    /// workgroup is left that could publish it.
    pub fn wait_for(&self, i: u32, ready: impl Fn(u32) -> bool) -> u32 {
        let word = || self.words[i as usize].load(Ordering::SeqCst);
        let mut o = self.occupancy();
        loop {
            let v = word();
            if ready(v) {
                return v;
            }
            assert!(!o.failed, "another workgroup of the dispatch failed");
            o.blocked += 1;
            let nothing_to_launch = o.launched == self.groups || o.running == self.resident;
            if o.blocked == o.running && nothing_to_launch {
                o.failed = true;
                self.changed.notify_all();
                panic!(
                    "deadlock: all {} running workgroups wait and none can be launched ({}; word {i} = {v:#x})",
                    o.running, self.schedule
                );
            }
            o = self.changed.wait(o).unwrap_or_else(|e| e.into_inner());
            o.blocked -= 1;
        }
    }
}

impl Residency for Board {
    fn launch(&self, _group: u32) {
        let mut o = self.occupancy();
        o.running += 1;
        o.launched += 1;
    }
    fn retire(&self, _group: u32, panicked: bool) {
        let mut o = self.occupancy();
        o.running -= 1;
        o.failed |= panicked;
        self.changed.notify_all();
    }
}

/// A workgroup's view of the board as the kernel's [`Chain`].
struct BoardChain<'a>(&'a Board);

impl Chain for BoardChain<'_> {
    fn claim(&mut self, i: u32) -> u32 {
        self.0.words[i as usize].fetch_add(1, Ordering::SeqCst)
    }
    fn publish(&mut self, i: u32, v: u32) {
        self.0.publish(i, v);
    }
    fn look(&mut self, i: u32, pass: u32) -> u32 {
        self.0.wait_for(i, |w| is_ready(w, pass))
    }
}

/// The sort with chained passes at subgroup width `width` (inputs of one tile or less too: the
/// host takes the single-workgroup path there, these tests do not).
pub fn sort_chained_emulated(width: u32, keys: &[u32], values: &[u32], key_bits: u32, schedule: Schedule) -> (Vec<u32>, Vec<u32>) {
    let n = keys.len() as u32;
    if n <= 1 || passes(key_bits) == 0 {
        return (keys.to_vec(), values.to_vec());
    }
    let tiles = n.div_ceil(RADIX_TILE);
    let hist = global_histogram_emulated(width, keys, key_bits);
    let emu = Emulation { width, workgroup_size: SORT_WORKGROUP, shared_words: RADIX_SHARED_WORDS };
    let board = Board::new(status_words(tiles), tiles, &schedule);
    let (mut k, mut v) = (keys.to_vec(), values.to_vec());
    for pass in 0..passes(key_bits) {
        // One board for every pass, as the GPU zeroes the status words once per sort.
        *board.occupancy() = Occupancy::default();
        let out = Out::new(n as usize);
        let bins = &hist[(pass * RADIX) as usize..];
        let (kk, vv) = (&k, &v);
        run_workgroups_resident(emu, &schedule.launch_order(tiles), schedule.resident, &board, |_, c, s| {
            chained_tile(c, s, &mut BoardChain(&board), n, tiles, (pass, key_bits), |d| bins[d as usize], |i| kk[i as usize], |i| vv[i as usize], |d, key, value| {
                out.write(d, key, value)
            });
        });
        (k, v) = out.finish();
    }
    (k, v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::coop::cpu::run_workgroups_resident;
    use crate::sort_inputs::shapes;

    fn schedules() -> Vec<Schedule> {
        let mut s = Vec::new();
        for resident in [1, 2, 5] {
            for order in [Order::Ascending, Order::Descending, Order::Shuffled(resident * 77)] {
                s.push(Schedule { resident, order });
            }
        }
        s
    }

    /// Stable, equal to the CPU's sort, at every width, under every schedule: one thread
    /// (workgroups strictly one after another, in any order), a few, descending and shuffled.
    #[test]
    fn chained_passes_sort_under_every_schedule() {
        let n = 5 * RADIX_TILE as usize + 9;
        for width in [4, 8, 16, 32, 64] {
            for schedule in schedules() {
                for (what, keys) in shapes(n, width).into_iter().filter(|(w, _)| matches!(*w, "few distinct" | "random")) {
                    let values: Vec<u32> = (0..n as u32).collect();
                    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
                    expected.sort_by_key(|e| e.0);
                    let (k, v) = sort_chained_emulated(width, &keys, &values, 32, schedule);
                    let got: Vec<(u32, u32)> = k.into_iter().zip(v).collect();
                    assert!(got == expected, "{what}, width {width}, {schedule:?}");
                }
            }
        }
    }

    /// 30-bit keys (4 passes sharing the board) and a partial single tile.
    #[test]
    fn chained_passes_sort_30_bit_keys_and_one_tile() {
        for n in [RADIX_TILE as usize - 5, 3 * RADIX_TILE as usize] {
            let keys: Vec<u32> = shapes(n, 3).pop().unwrap().1.iter().map(|k| k >> 2).collect();
            let values: Vec<u32> = (0..n as u32).collect();
            let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
            expected.sort_by_key(|e| e.0);
            let schedule = Schedule { resident: 2, order: Order::Descending };
            let (k, v) = sort_chained_emulated(8, &keys, &values, 30, schedule);
            assert_eq!(k.into_iter().zip(v).collect::<Vec<_>>(), expected, "n = {n}");
        }
    }

    /// The board reports a deadlock instead of hanging: with one resident thread and descending
    /// launches, a workgroup that waits on a higher workgroup *id* (not on a claimed tile) waits
    /// on one that cannot start.
    #[test]
    #[should_panic(expected = "deadlock: all 1 running workgroups wait")]
    fn waiting_on_an_unlaunched_workgroup_is_a_deadlock() {
        let schedule = Schedule { resident: 1, order: Order::Descending };
        let board = Board::new(4, 4, &schedule);
        let emu = Emulation { width: 4, workgroup_size: 4, shared_words: 0 };
        run_workgroups_resident(emu, &schedule.launch_order(4), 1, &board, |g, c, _| {
            if c.local_index() == 0 {
                if g > 0 {
                    board.wait_for(g - 1, |w| w != 0);
                }
                board.publish(g, 1);
            }
        });
    }

    /// The same waits on claimed tiles instead of ids complete under the same schedule.
    #[test]
    fn waiting_on_a_claimed_tile_completes() {
        let schedule = Schedule { resident: 1, order: Order::Descending };
        let board = Board::new(5, 4, &schedule);
        let emu = Emulation { width: 4, workgroup_size: 4, shared_words: 1 };
        run_workgroups_resident(emu, &schedule.launch_order(4), 1, &board, |_, c, s| {
            if c.local_index() == 0 {
                s.store(0, BoardChain(&board).claim(4));
            }
            c.workgroup_barrier();
            let tile = s.load(0);
            if c.local_index() == 0 {
                if tile > 0 {
                    board.wait_for(tile - 1, |w| w != 0);
                }
                board.publish(tile, 1);
            }
        });
    }
}
