//! Streaming bricks through a pool of fixed size (docs/large-volumes.md, "Streaming"). Pure code: which bricks a
//! step uploads into which slots, which it evicts, and what each level-0 brick shows meanwhile.
//!
//! - The pool has `capacity` slots; the top level's one brick is uploaded first and never evicted, so every
//!   level-0 brick always has something to show: **never a hole**.
//! - A step takes the wanted cut (the screen rule within `capacity − 1` bricks, so that the wanted bricks and the
//!   top fit together) and uploads at most `max_uploads` wanted bricks that are missing, coarsest first (the widest
//!   regions improve first), then in index order (z, y, x).
//! - A slot for an upload: a free one, else the least recently used one that this step shows nowhere, else the
//!   least recently used one that only stands in for a missing brick (a coarser fallback). A wanted brick that is
//!   resident is never evicted, so the wanted cut is reached in at most ⌈missing / max_uploads⌉ steps.
//! - Meanwhile each level-0 brick shows the finest resident brick over it at its wanted level or coarser.

use super::levels::Cut;
use super::pool::{Pool, Resident};
use crate::pyramid::bricks::covering;
use std::collections::HashMap;

/// A brick of some level: (level, index in that level's grid).
pub type Key = (u32, [u32; 3]);

/// Which brick each slot holds and when it was last shown.
#[derive(Clone, Debug)]
pub struct Stream {
    /// The top level (its grid is one brick).
    pub top: u32,
    /// Per slot: the brick it holds and the step that last showed it.
    slots: Vec<Option<(Key, u64)>>,
    /// The slot of each resident brick.
    index: HashMap<Key, u32>,
    step: u64,
    /// Bricks uploaded and evicted so far.
    pub uploaded: u64,
    pub evicted: u64,
}

/// What one step did and how far the view is from its wanted cut.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Step {
    /// The slots to fill, each with the brick that now lives there.
    pub uploads: Vec<(u32, Resident)>,
    /// The level each level-0 brick shows after the uploads.
    pub shown: Cut,
    /// The cut wanted, and how many of its bricks are still missing after this step.
    pub wanted: Cut,
    pub missing: usize,
}

impl Stream {
    /// An empty pool of `capacity` slots (at least 1) for a pyramid whose top level is `top`.
    pub fn new(capacity: usize, top: u32) -> Stream {
        Stream {
            top,
            slots: vec![None; capacity.max(1)],
            index: HashMap::new(),
            step: 0,
            uploaded: 0,
            evicted: 0,
        }
    }

    pub fn capacity(&self) -> usize {
        self.slots.len()
    }

    /// The wanted cut's bound on bricks: the pool less the top's slot.
    pub fn cut_bound(&self) -> usize {
        (self.capacity() - 1).max(1)
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.step
    }

    pub fn is_resident(&self, key: Key) -> bool {
        self.index.contains_key(&key)
    }

    /// One step towards `wanted`: at most `max_uploads` uploads (the top's first), then the cut shown.
    pub fn step(&mut self, wanted: &Cut, max_uploads: usize) -> Step {
        self.step += 1;
        let now = self.step;
        let top: Key = (self.top, [0, 0, 0]);
        let want = wanted.shown();
        let mut missing: Vec<Key> = want.iter().copied().filter(|k| !self.is_resident(*k)).collect();
        if !self.is_resident(top) && !missing.contains(&top) {
            missing.push(top);
        }
        // Coarsest first, then z, y, x.
        missing.sort_by_key(|&(l, b)| (std::cmp::Reverse(l), b[2], b[1], b[0]));
        for k in &want {
            self.touch(*k, now);
        }
        // The fallbacks in use now: shown until their finer bricks arrive, evicted only after unused slots.
        let fallback = self.fallback_cut(wanted);
        self.touch_cut(&fallback, now);
        let mut uploads = Vec::new();
        for &key in missing.iter().take(max_uploads.max(1)) {
            let Some(slot) = self.victim(now, &want, top) else {
                break;
            };
            if let Some((old, _)) = self.slots[slot].take() {
                self.index.remove(&old);
                self.evicted += 1;
            }
            self.slots[slot] = Some((key, now));
            self.index.insert(key, slot as u32);
            self.uploaded += 1;
            uploads.push((
                slot as u32,
                Resident {
                    level: key.0,
                    brick: key.1,
                },
            ));
        }
        let shown = self.fallback_cut(wanted);
        self.touch_cut(&shown, now);
        let missing = want.iter().filter(|k| !self.is_resident(**k)).count();
        Step {
            uploads,
            shown,
            wanted: wanted.clone(),
            missing,
        }
    }

    /// Writes the slots' bricks and the page table (each level-0 brick's slot in `shown`) into `pool`.
    pub fn write(&self, pool: &mut Pool, shown: &Cut) {
        for (slot, held) in self.slots.iter().enumerate() {
            pool.resident[slot] = held.map(|((level, brick), _)| Resident { level, brick });
        }
        for (i, &l) in shown.level.iter().enumerate() {
            let key = (l, covering(shown.brick_of(i), l));
            pool.directory[i] = self.index.get(&key).copied().unwrap_or(0);
        }
    }

    fn touch(&mut self, key: Key, now: u64) {
        if let Some(&slot) = self.index.get(&key) {
            if let Some((_, used)) = &mut self.slots[slot as usize] {
                *used = now;
            }
        }
    }

    fn touch_cut(&mut self, cut: &Cut, now: u64) {
        for (l, b) in cut.shown() {
            self.touch((l, b), now);
        }
    }

    /// Each level-0 brick's finest resident level at or above its wanted one (the top when nothing finer is).
    fn fallback_cut(&self, wanted: &Cut) -> Cut {
        let mut shown = wanted.clone();
        for (i, l) in shown.level.iter_mut().enumerate() {
            let b = wanted.brick_of(i);
            *l = (*l..self.top)
                .find(|&level| self.is_resident((level, covering(b, level))))
                .unwrap_or(self.top);
        }
        shown
    }

    /// The slot an upload takes: a free one; else the least recently used brick not shown this step; else the least
    /// recently used one that is not wanted (a fallback). Never the top, never a wanted resident brick.
    fn victim(&self, now: u64, want: &[Key], top: Key) -> Option<usize> {
        if let Some(free) = self.slots.iter().position(Option::is_none) {
            return Some(free);
        }
        let candidates = self.slots.iter().enumerate().filter_map(|(slot, held)| {
            let (key, used) = (*held)?;
            (key != top && want.binary_search(&key).is_err()).then_some((used >= now, used, slot))
        });
        candidates.min().map(|(_, _, slot)| slot)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys_of(cut: &Cut) -> Vec<Key> {
        cut.shown()
    }

    /// A 4 x 4 x 4 grid of level-0 bricks, top level 2.
    fn wanted(level: u32) -> Cut {
        Cut::uniform([4, 4, 4], level)
    }

    #[test]
    fn the_top_comes_first_and_the_cut_is_reached_within_bounded_steps() {
        let mut s = Stream::new(80, 2);
        let first = s.step(&wanted(1), 4);
        // The top first, then three level-1 bricks; everything else shows the top.
        assert_eq!(
            first.uploads[0].1,
            Resident {
                level: 2,
                brick: [0, 0, 0]
            }
        );
        assert_eq!(first.uploads.len(), 4);
        assert_eq!((first.wanted.shown().len(), first.missing), (8, 5));
        assert_eq!(first.shown.level.iter().filter(|&&l| l == 1).count(), 3 * 8);
        assert!(first.shown.level.iter().all(|&l| l == 1 || l == 2));
        let mut steps = 1;
        while s.step(&wanted(1), 4).missing > 0 {
            steps += 1;
        }
        assert_eq!(steps + 1, 3, "8 bricks and the top in uploads of 4: three steps");
        let done = s.step(&wanted(1), 4);
        assert!(done.uploads.is_empty());
        assert_eq!(done.shown, wanted(1));
    }

    #[test]
    fn least_recently_used_bricks_go_first_and_wanted_ones_never() {
        // Room for the top and 15 bricks: level 1 everywhere (8), then level 0 in one level-1 brick's region.
        let mut s = Stream::new(16, 2);
        while s.step(&wanted(1), 16).missing > 0 {}
        assert_eq!(s.evicted, 0);
        let mut corner = wanted(1);
        for (i, l) in corner.level.iter_mut().enumerate() {
            if wanted(0).brick_of(i).iter().all(|&v| v < 2) {
                *l = 0;
            }
        }
        // 8 level-0 bricks: 7 free slots, then the one unwanted brick (the level-1 brick they replace).
        let step = s.step(&corner, 16);
        assert_eq!(step.uploads.len(), 8);
        assert_eq!(step.missing, 0);
        assert_eq!(s.evicted, 1);
        for key in keys_of(&corner) {
            assert!(s.is_resident(key), "{key:?}");
        }
        assert!(!s.is_resident((1, [0, 0, 0])), "the only unwanted brick was evicted");
        assert!(s.is_resident((2, [0, 0, 0])));
        // Back to level 1: the least recently shown level-0 bricks make room, and nothing wanted goes.
        let step = s.step(&wanted(1), 16);
        assert_eq!((step.uploads.len(), step.missing), (1, 0));
        assert_eq!(step.shown, wanted(1));
    }

    #[test]
    fn fallbacks_are_the_finest_resident_coarser_bricks() {
        let mut s = Stream::new(100, 2);
        while s.step(&wanted(1), 100).missing > 0 {}
        // Level 0 wanted everywhere, one upload: brick 0 at level 0, the rest shows level 1 (never the top).
        let step = s.step(&wanted(0), 1);
        assert_eq!(
            step.uploads,
            vec![(
                9,
                Resident {
                    level: 0,
                    brick: [0, 0, 0]
                }
            )]
        );
        assert_eq!(step.shown.level[0], 0);
        assert!(step.shown.level[1..].iter().all(|&l| l == 1));
    }

    #[test]
    fn a_full_pool_evicts_fallbacks_last_and_still_converges() {
        // 9 slots: the top and 8. Level 1 resident, then level 0 in one level-1 brick's region beside the other
        // seven level-1 bricks (15 bricks) is over the bound; a cut within it (those 8 level-0 bricks under the
        // top) converges.
        let mut s = Stream::new(9, 2);
        while s.step(&wanted(1), 9).missing > 0 {}
        let mut fine = wanted(1);
        for (i, l) in fine.level.iter_mut().enumerate() {
            if wanted(0).brick_of(i).iter().all(|&v| v < 2) {
                *l = 0;
            }
        }
        assert_eq!(fine.shown().len(), 8 + 7);
        // Over the bound: the wanted bricks themselves are never evicted for each other, so some stay missing
        // and show a coarser level, never a hole.
        // The unwanted level-1 brick makes room for one; then no slot may go (all others are wanted or the top).
        let step = s.step(&fine, 2);
        assert_eq!(step.uploads.len(), 1);
        for (l, b) in fine.shown().into_iter().filter(|&(l, _)| l == 1) {
            assert!(s.is_resident((l, b)), "wanted brick {b:?} was evicted for another");
        }
        for _ in 0..5 {
            let step = s.step(&fine, 2);
            assert!(step.missing > 0);
            assert!(step.shown.level.iter().all(|&l| l <= 2));
        }
        let mut within = wanted(2);
        for (i, l) in within.level.iter_mut().enumerate() {
            if wanted(0).brick_of(i).iter().all(|&v| v < 2) {
                *l = 0;
            }
        }
        assert_eq!(within.shown().len(), 8 + 1);
        let mut steps = 0;
        while s.step(&within, 2).missing > 0 {
            steps += 1;
            assert!(steps < 10);
        }
        assert_eq!(s.step(&within, 2).shown, within);
    }

    #[test]
    fn write_fills_the_pools_slots_and_page_table() {
        let mut pool = Pool::with_capacity([64, 64, 64], [16; 3], 2048, 10, 2).unwrap();
        assert!(pool.capacity() >= 10);
        let mut s = Stream::new(pool.capacity(), 2);
        let step = s.step(&wanted(1), 3);
        s.write(&mut pool, &step.shown);
        for (i, &slot) in pool.directory.iter().enumerate() {
            let l = step.shown.level[i];
            let r = pool.resident[slot as usize].expect("resident");
            assert_eq!((r.level, r.brick), (l, step.shown.brick_of(i).map(|b| b >> l)));
        }
    }
}
