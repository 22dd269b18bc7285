//! Welding: which corners share a position, as a small integer per corner.

use glam::DVec3;

/// Corners welded by their exact position.
pub(crate) struct Welded {
    /// The position of each corner, numbered in order of first appearance.
    pub id: Vec<u32>,
    /// The first corner at each position.
    pub first: Vec<u32>,
}

/// A grid-space position's key (−0 and +0 alike).
pub(crate) fn grid_key(v: DVec3) -> [u64; 3] {
    [v.x, v.y, v.z].map(|c| (c + 0.0).to_bits())
}

/// A soup position's key (−0 and +0 alike).
pub(crate) fn soup_key(p: [f32; 3]) -> [u32; 3] {
    p.map(|c| (c + 0.0).to_bits())
}

/// A position key whose bits a multiplicative hash spreads over its top bits.
pub(crate) trait Key: Copy + Eq + Default {
    /// The key's hash: its top bits pick the slot.
    fn hash(&self) -> u64;
}

impl Key for [u32; 3] {
    fn hash(&self) -> u64 {
        let xy = u64::from(self[0]) | (u64::from(self[1]) << 32);
        (xy.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ u64::from(self[2])).wrapping_mul(0xbf58_476d_1ce4_e5b9)
    }
}

impl Key for [u64; 3] {
    fn hash(&self) -> u64 {
        let xy = self[0] ^ self[1].rotate_left(32);
        (xy.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ self[2]).wrapping_mul(0xbf58_476d_1ce4_e5b9)
    }
}

/// The mark of an empty slot in a table of position numbers: not a repeated byte, so a new table is filled
/// by wide stores rather than a byte-wise `memset` (whose every byte counts as an instruction under
/// valgrind, in whose counts the analysis is measured).
const EMPTY: u32 = u32::MAX >> 1;

/// The number of slot bits of an open-addressing table for `count` keys (at most two-thirds full).
fn table_bits(count: usize) -> u32 {
    (count + count / 2).next_power_of_two().max(2).ilog2()
}

/// Whether the `count` keys `keys` are all different: first by their hashes alone (keys with different
/// hashes differ), then, only when two hashes agree, by the keys themselves ([`representatives`]).
pub(crate) fn all_different<K: Key>(count: usize, keys: impl Iterator<Item = K> + Clone) -> bool {
    hashes_all_different(count, keys.clone().map(|key| key.hash()))
        || representatives(count, keys).iter().enumerate().all(|(k, &first)| first as usize == k)
}

/// Whether the `count` hashes `hashes` are surely all different (false when two are equal, and also when
/// two differ only in the last bit and one of them is the table's empty mark): an open-addressing table of
/// the hashes. (One pass over the keys: for keys gathered from several lists, as a grid's positions of a soup's
/// corners are, that costs more than the table's misses, where [`representatives`] takes two.)
fn hashes_all_different(count: usize, hashes: impl Iterator<Item = u64>) -> bool {
    // Not a repeated byte, as `EMPTY`.
    const UNUSED: u64 = 0x5555_5555_5555_5554;
    let bits = table_bits(count);
    let mut slots = vec![UNUSED; 1 << bits];
    let mask = slots.len() - 1;
    for hash in hashes {
        let hash = if hash == UNUSED { hash ^ 1 } else { hash };
        let mut slot = (hash >> (64 - bits)) as usize;
        loop {
            match slots[slot] {
                UNUSED => {
                    slots[slot] = hash;
                    break;
                }
                other if other == hash => return false,
                _ => slot = (slot + 1) & mask,
            }
        }
    }
    true
}

/// Keys per part of [`representatives`] (about): the part's table, 4 bytes a slot, and its keys stay in the core's
/// L2 cache.
const KEYS_PER_PART: usize = 1 << 12;

/// The most parts of [`representatives`] (bits).
const MOST_PART_BITS: u32 = 16;

/// For each of the `count` keys `keys`, the first key equal to it (its position in `keys`). The keys are split
/// into parts by the top bits of their hashes (two passes over `keys`: counting, then copying each key with its
/// position into its part's stretch of one list), then each part is welded in a small table: where one table
/// for all the keys (32 MB for a million) misses the caches at almost every probe, a part's stays in L2 (the
/// height field's million vertices on a 2-core VM: its soup weld 70 → 51 ms).
pub(crate) fn representatives<K: Key>(count: usize, keys: impl Iterator<Item = K> + Clone) -> Vec<u32> {
    let part_bits = crate::radix::bits_for(count / KEYS_PER_PART).min(MOST_PART_BITS);
    let part = |key: &K| if part_bits == 0 { 0 } else { (key.hash() >> (64 - part_bits)) as usize };
    let mut start = vec![0u32; (1 << part_bits) + 1];
    for key in keys.clone() {
        start[part(&key) + 1] += 1;
    }
    for p in 1..start.len() {
        start[p] += start[p - 1];
    }
    let mut next = start.clone();
    let mut parted = vec![(K::default(), 0u32); count];
    for (k, key) in keys.enumerate() {
        let at = &mut next[part(&key)];
        parted[*at as usize] = (key, k as u32);
        *at += 1;
    }
    let largest = start.windows(2).map(|w| (w[1] - w[0]) as usize).max().unwrap_or(0);
    let bits = table_bits(largest);
    // A slot holds the position in `parted` of the first key seen with its hash's slot bits, or EMPTY.
    let mut slots = vec![EMPTY; 1 << bits];
    let mask = slots.len() - 1;
    let mut first = vec![0u32; count];
    for w in start.windows(2) {
        let entries = &parted[w[0] as usize..w[1] as usize];
        for (e, &(key, k)) in entries.iter().enumerate() {
            // The bits below the part's pick the slot.
            let mut slot = ((key.hash() << part_bits) >> (64 - bits)) as usize;
            first[k as usize] = loop {
                match slots[slot] {
                    EMPTY => {
                        slots[slot] = e as u32;
                        break k;
                    }
                    seen if entries[seen as usize].0 == key => break entries[seen as usize].1,
                    _ => slot = (slot + 1) & mask,
                }
            };
        }
        // Emptied for the next part: from each key's home slot to the first empty one. A key sits in the run of
        // filled slots that starts at its home, and emptying a run to its end leaves none of it filled behind.
        for &(key, _) in entries {
            let mut slot = ((key.hash() << part_bits) >> (64 - bits)) as usize;
            while slots[slot] != EMPTY {
                slots[slot] = EMPTY;
                slot = (slot + 1) & mask;
            }
        }
    }
    first
}

/// Welds corners (`corners`, in order) by their keys (`key`): one pass through an open-addressing table that
/// holds each position's key with its number (so a probe reads one slot), at most two-thirds full; equal keys
/// are found exactly (the hash only picks where to look first).
pub(crate) fn weld<T, K: Key>(corners: &[T], key: impl Fn(&T) -> K) -> Welded {
    // A closed mesh has about one position per six corners (two triangles per vertex); the table grows past
    // that. Room for more costs more than the growth: a table beyond the core's L2 cache slows every probe
    // (room for one position per two corners: 4 MiB of slots for the FlightHelmet, its analysis 7.1 ms
    // instead of 4.7).
    let mut table = Table::with_room(corners.len() / 6);
    let mut id = vec![0; corners.len()];
    for (c, (corner, id)) in corners.iter().zip(&mut id).enumerate() {
        let key = key(corner);
        *id = match table.find(key) {
            Ok(id) => id,
            Err(empty) => table.insert(empty, key, c as u32),
        };
    }
    Welded { id, first: table.first }
}

/// [`weld`] of corners read from indexed source vertices (corner `c` at `positions[index[c]]`, bit for bit):
/// welds the sources, one per vertex rather than one per corner ([`representatives`]), then numbers each corner's
/// position in order of first appearance as [`weld`] of the corners would, so the result is the same.
pub(crate) fn weld_indexed<T, K: Key>(positions: &[T], key: impl Fn(&T) -> K, index: &[u32]) -> Welded {
    let first_source = representatives(positions.len(), positions.iter().map(&key));
    let mut renumbered = vec![EMPTY; positions.len()];
    let mut welded = Welded { id: vec![0; index.len()], first: Vec::with_capacity(positions.len()) };
    for (c, (&source, id)) in index.iter().zip(&mut welded.id).enumerate() {
        let position = &mut renumbered[first_source[source as usize] as usize];
        if *position == EMPTY {
            *position = welded.first.len() as u32;
            welded.first.push(c as u32);
        }
        *id = *position;
    }
    welded
}

/// A slot of the welding table: a position's key and number, or [`EMPTY`] as the number.
#[derive(Clone, Copy)]
struct Slot<K> {
    key: K,
    id: u32,
}

/// The welding table: the positions seen so far, by key.
struct Table<K> {
    slots: Vec<Slot<K>>,
    /// The number of slot bits.
    bits: u32,
    /// The first corner at each position, by number.
    first: Vec<u32>,
}

impl<K: Key> Table<K> {
    /// An empty table with room for `positions` positions (it grows when it needs more).
    fn with_room(positions: usize) -> Self {
        let bits = table_bits(positions);
        let slots = vec![Slot { key: K::default(), id: EMPTY }; 1 << bits];
        Self { slots, bits, first: Vec::with_capacity(positions) }
    }

    /// The number of the position `key`, or the empty slot where it goes.
    fn find(&self, key: K) -> Result<u32, usize> {
        let mask = self.slots.len() - 1;
        let mut slot = (key.hash() >> (64 - self.bits)) as usize;
        loop {
            let here = self.slots[slot];
            if here.id == EMPTY {
                return Err(slot);
            }
            if here.key == key {
                return Ok(here.id);
            }
            slot = (slot + 1) & mask;
        }
    }

    /// Numbers the new position `key` (first seen at `corner`) in the empty slot `slot`, then keeps the table
    /// at most two-thirds full.
    #[cold]
    fn insert(&mut self, slot: usize, key: K, corner: u32) -> u32 {
        let id = self.first.len() as u32;
        self.slots[slot] = Slot { key, id };
        self.first.push(corner);
        if 3 * self.first.len() > 2 * self.slots.len() {
            self.grow();
        }
        id
    }

    /// Doubles the table, keeping every position's number.
    #[cold]
    fn grow(&mut self) {
        let old = std::mem::replace(&mut self.slots, vec![Slot { key: K::default(), id: EMPTY }; 2 << self.bits]);
        self.bits += 1;
        let mask = self.slots.len() - 1;
        for here in old.into_iter().filter(|s| s.id != EMPTY) {
            let mut slot = (here.key.hash() >> (64 - self.bits)) as usize;
            while self.slots[slot].id != EMPTY {
                slot = (slot + 1) & mask;
            }
            self.slots[slot] = here;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_positions_and_signed_zeros_share_a_number_in_order_of_first_appearance() {
        let corners = [[0.0, 1.0, 2.0], [-0.0, 1.0, 2.0], [0.0, 1.0, 2.5], [0.0, 1.0, 2.0]];
        let welded = weld(&corners, |&p| soup_key(p));
        assert_eq!((welded.id, welded.first), (vec![0, 0, 1, 0], vec![0, 2]));
        // Many keys, few distinct: the table's probing finds every repeat.
        let many: Vec<DVec3> = (0..20_000).map(|i| DVec3::new((i % 97) as f64, (i % 89) as f64 * 0.5, 1.0)).collect();
        let welded = weld(&many, |&p| grid_key(p));
        assert_eq!(welded.first.len(), 97 * 89);
        assert!(welded.id.iter().enumerate().all(|(c, &id)| many[welded.first[id as usize] as usize] == many[c]));
        // More positions than the table first makes room for (a position per two corners): it grows.
        let line: Vec<DVec3> = (0..20_000).map(|i| DVec3::new(f64::from(i % 15_000), 0.5, 1.0)).collect();
        let grown = weld(&line, |&p| grid_key(p));
        assert_eq!(grown.first, (0..15_000).collect::<Vec<u32>>());
        assert!(grown.id.iter().enumerate().all(|(c, &id)| id == c as u32 % 15_000));
        // The same keys, once each, are all different; with one repeat, not.
        let firsts = welded.first.iter().map(|&c| grid_key(many[c as usize]));
        assert!(all_different(welded.first.len(), firsts.clone()));
        assert!(!all_different(welded.first.len() + 1, firsts.clone().chain([grid_key(many[5_000])])));
    }

    /// A key whose hash is its first part: different keys with equal hashes.
    #[derive(Clone, Copy, Default, PartialEq, Eq)]
    struct Colliding(u64, u64);

    impl Key for Colliding {
        fn hash(&self) -> u64 {
            self.0
        }
    }

    #[test]
    fn keys_with_equal_hashes_are_told_apart_by_the_keys() {
        let distinct = [Colliding(7, 1), Colliding(7, 2), Colliding(9, 1)];
        assert!(!hashes_all_different(3, distinct.iter().map(Key::hash)));
        assert!(all_different(3, distinct.iter().copied()));
        assert!(!all_different(4, distinct.iter().copied().chain([Colliding(7, 2)])));
        // The empty mark is a hash like any other (told from its neighbour by the keys).
        let near_mark = [Colliding(0x5555_5555_5555_5554, 0), Colliding(0x5555_5555_5555_5555, 0)];
        assert!(all_different(2, near_mark.iter().copied()));
        assert!(hashes_all_different(3, [1u64 << 63, 1 << 62, 3].into_iter()));
        // Many keys over many parts, each hash shared by four different keys (and every key repeated once).
        let keys: Vec<Colliding> = (0..40_000u64)
            .map(|k| k % 20_000)
            .map(|k| Colliding((k / 4).wrapping_mul(0x9e37_79b9_7f4a_7c15), k))
            .collect();
        let first = representatives(keys.len(), keys.iter().copied());
        assert!(
            first
                .iter()
                .enumerate()
                .all(|(k, &f)| keys[f as usize] == keys[k] && keys[..f as usize].iter().all(|o| *o != keys[k]))
        );
        assert_eq!(first.iter().enumerate().filter(|&(k, &f)| f as usize == k).count(), 20_000);
    }

    #[test]
    fn every_key_points_to_the_first_equal_key_across_parts() {
        // 300,000 positions on a lattice, each drawn about three times, in a scattered order: many parts.
        let mut random = crate::lcg::Lcg::new(11);
        let keys: Vec<[u32; 3]> =
            (0..300_000).map(|_| soup_key([0, 1, 2].map(|_| (random.unit(47.0) as f32).floor() * 0.25))).collect();
        let first = representatives(keys.len(), keys.iter().copied());
        let mut seen = std::collections::HashMap::new();
        for (k, key) in keys.iter().enumerate() {
            assert_eq!(first[k], *seen.entry(*key).or_insert(k as u32), "key {k}");
        }
        assert!((50_000..110_000).contains(&seen.len()), "{}", seen.len());
        assert!(!all_different(keys.len(), keys.iter().copied()));
        let distinct: Vec<[u32; 3]> = seen.keys().copied().collect();
        assert!(all_different(distinct.len(), distinct.iter().copied()));
    }
}
