//! The physical page pool of a virtual map and its allocator: the pages a
//! frame needs are made resident (kept from earlier frames when cached,
//! else given a free slot or the least recently used one's), and when more
//! are needed than the pool holds, the finest needed level is replaced by
//! its parents until they fit — a coarser shadow, never a wrong one.

use super::levels::PageKey;
use std::collections::{BTreeSet, HashMap};

#[derive(Clone, Copy, Debug)]
struct Resident {
    slot: u32,
    last_used: u64,
}

/// Physical slots and the pages in them.
#[derive(Debug)]
pub struct PagePool {
    capacity: u32,
    resident: HashMap<PageKey, Resident>,
    free: Vec<u32>,
    frame: u64,
}

/// One frame's allocation.
#[derive(Debug, Default)]
pub struct Allocation {
    /// New pages and their slots: to render this frame.
    pub render: Vec<(PageKey, u32)>,
    /// Pages the view asked for.
    pub needed: usize,
    /// Needed pages already resident (not rendered again).
    pub kept: Vec<PageKey>,
    /// Needed pages replaced by a coarser one for want of slots.
    pub degraded: usize,
    /// Needed pages of the coarsest levels left out (the pool holds fewer
    /// pages than those levels need): their pixels are lit.
    pub dropped: usize,
}

impl PagePool {
    pub fn new(capacity: u32) -> PagePool {
        PagePool {
            capacity,
            resident: HashMap::new(),
            free: (0..capacity).rev().collect(),
            frame: 0,
        }
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub fn resident_count(&self) -> usize {
        self.resident.len()
    }

    /// Every resident page and its slot.
    pub fn resident(&self) -> impl Iterator<Item = (PageKey, u32)> + '_ {
        self.resident.iter().map(|(k, r)| (*k, r.slot))
    }

    /// Forgets the pages `stale` picks (their content is out of date).
    pub fn invalidate(&mut self, stale: impl Fn(&PageKey) -> bool) {
        let gone: Vec<PageKey> = self.resident.keys().filter(|k| stale(k)).copied().collect();
        for k in gone {
            let r = self.resident.remove(&k).expect("listed above");
            self.free.push(r.slot);
        }
    }

    /// Makes `needed` resident, coarsening through `parent` while it does
    /// not fit (the finest level first: the least `rank`, a level's
    /// distance from the finest of its view); returns what to render and
    /// the counts.
    pub fn allocate(
        &mut self,
        mut needed: BTreeSet<PageKey>,
        parent: impl Fn(PageKey) -> Option<PageKey>,
        rank: impl Fn(u32) -> u32,
    ) -> Allocation {
        self.frame += 1;
        let mut a = Allocation {
            needed: needed.len(),
            ..Default::default()
        };
        while needed.len() > self.capacity as usize {
            // Replace the finest level present that has a coarser one by its parents.
            let finest = needed
                .iter()
                .filter(|k| parent(**k).is_some())
                .map(|k| (rank(k.level), k.level))
                .min();
            let Some((_, finest)) = finest else {
                // The coarsest level alone is too many: keep what fits.
                let keep = self.capacity as usize;
                a.dropped += needed.len() - keep;
                needed = needed.into_iter().rev().take(keep).collect();
                break;
            };
            let fine: Vec<PageKey> = needed
                .iter()
                .filter(|k| k.level == finest)
                .copied()
                .collect();
            let parents: Vec<PageKey> = fine.iter().filter_map(|k| parent(*k)).collect();
            a.degraded += fine.len();
            for k in &fine {
                needed.remove(k);
            }
            needed.extend(parents);
        }
        // Slots: free first, then the least recently used page not needed now.
        let mut evictable: Vec<(u64, PageKey)> = self
            .resident
            .iter()
            .filter(|(k, _)| !needed.contains(k))
            .map(|(k, r)| (r.last_used, *k))
            .collect();
        evictable.sort_unstable_by(|a, b| b.cmp(a));
        for key in needed {
            if let Some(r) = self.resident.get_mut(&key) {
                r.last_used = self.frame;
                a.kept.push(key);
                continue;
            }
            let slot = match self.free.pop() {
                Some(s) => s,
                None => {
                    let (_, old) = evictable.pop().expect("needed pages fit the pool");
                    self.resident.remove(&old).expect("resident").slot
                }
            };
            self.resident.insert(
                key,
                Resident {
                    slot,
                    last_used: self.frame,
                },
            );
            a.render.push((key, slot));
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(level: u32, x: i32, y: i32) -> PageKey {
        PageKey { level, x, y }
    }

    fn rank(level: u32) -> u32 {
        level
    }

    fn parent(k: PageKey) -> Option<PageKey> {
        (k.level < 3).then(|| key(k.level + 1, k.x.div_euclid(2), k.y.div_euclid(2)))
    }

    #[test]
    fn cached_pages_are_not_rendered_again() {
        let mut pool = PagePool::new(16);
        let want: BTreeSet<_> = [key(0, 0, 0), key(0, 1, 0), key(1, 4, 4)].into();
        let first = pool.allocate(want.clone(), parent, rank);
        assert_eq!(first.render.len(), 3);
        let second = pool.allocate(want, parent, rank);
        assert_eq!((second.render.len(), second.kept.len()), (0, 3));
    }

    #[test]
    fn the_least_recently_used_page_makes_room() {
        let mut pool = PagePool::new(2);
        pool.allocate([key(0, 0, 0)].into(), parent, rank);
        pool.allocate([key(0, 1, 0)].into(), parent, rank);
        // Both resident; a third evicts the older (0, 0, 0), not (0, 1, 0).
        let a = pool.allocate([key(0, 1, 0), key(0, 2, 0)].into(), parent, rank);
        assert_eq!(a.render.len(), 1);
        assert_eq!(a.kept.len(), 1);
        let keys: BTreeSet<_> = pool.resident().map(|(k, _)| k).collect();
        assert_eq!(keys, [key(0, 1, 0), key(0, 2, 0)].into());
        let slots: BTreeSet<_> = pool.resident().map(|(_, s)| s).collect();
        assert_eq!(slots.len(), 2);
    }

    #[test]
    fn too_many_pages_degrade_to_their_parents() {
        let mut pool = PagePool::new(3);
        // 8 fine pages → 2 parents (x 0..3 → 0..1), plus one page of level 2.
        let want: BTreeSet<_> = (0..4)
            .flat_map(|x| [key(0, x, 0), key(0, x, 1)])
            .chain([key(2, 9, 9)])
            .collect();
        let a = pool.allocate(want, parent, rank);
        assert_eq!((a.needed, a.degraded, a.dropped), (9, 8, 0));
        let keys: BTreeSet<_> = pool.resident().map(|(k, _)| k).collect();
        assert_eq!(keys, [key(1, 0, 0), key(1, 1, 0), key(2, 9, 9)].into());
    }

    #[test]
    fn the_finest_level_of_any_view_gives_way_first() {
        // Two views of two levels each: view 0 levels 0, 1; view 1 levels 2, 3.
        let parent = |k: PageKey| {
            k.level
                .is_multiple_of(2)
                .then(|| key(k.level + 1, k.x.div_euclid(2), k.y.div_euclid(2)))
        };
        let mut pool = PagePool::new(3);
        let want: BTreeSet<_> = [key(1, 0, 0), key(2, 0, 0), key(2, 1, 0), key(2, 2, 0)].into();
        let a = pool.allocate(want, parent, |l| l % 2);
        // View 0 is at its coarsest; view 1's fine pages give way.
        assert_eq!((a.degraded, a.dropped), (3, 0));
        let keys: BTreeSet<_> = pool.resident().map(|(k, _)| k).collect();
        assert_eq!(keys, [key(1, 0, 0), key(3, 0, 0), key(3, 1, 0)].into());
    }

    #[test]
    fn a_pool_smaller_than_the_coarsest_level_drops_and_says_so() {
        let mut pool = PagePool::new(2);
        let want: BTreeSet<_> = (0..5).map(|x| key(3, x, 0)).collect();
        let a = pool.allocate(want, parent, rank);
        assert_eq!((a.render.len(), a.dropped), (2, 3));
    }

    #[test]
    fn invalidated_pages_free_their_slots_and_render_again() {
        let mut pool = PagePool::new(4);
        let want: BTreeSet<_> = [key(0, 0, 0), key(0, 1, 0)].into();
        pool.allocate(want.clone(), parent, rank);
        pool.invalidate(|k| k.x == 1);
        assert_eq!(pool.resident_count(), 1);
        let a = pool.allocate(want, parent, rank);
        assert_eq!(a.render, vec![(key(0, 1, 0), a.render[0].1)]);
    }
}
