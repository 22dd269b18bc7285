//! Welding: which corners share a position, as a small integer per corner.

use glam::DVec3;

/// Corners welded by their exact position.
pub(crate) struct Welded {
    /// The position of each corner, numbered in order of first appearance.
    pub id: Vec<u32>,
    /// The first corner at each position.
    pub first: Vec<u32>,
}

/// A position as bits: a grid-space corner's, or a soup corner's (its f32 bits widened).
pub(crate) type PositionKey = [u64; 3];

/// A grid-space position's key (−0 and +0 alike).
pub(crate) fn grid_key(v: DVec3) -> PositionKey {
    [v.x, v.y, v.z].map(|c| (c + 0.0).to_bits())
}

/// A soup position's key (−0 and +0 alike).
pub(crate) fn soup_key(p: [f32; 3]) -> PositionKey {
    p.map(|c| u64::from((c + 0.0).to_bits()))
}

/// A 64-bit mix (splitmix64's finalizer).
fn mix(mut x: u64) -> u64 {
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Welds the `count` corners whose positions `key` gives: one pass through an open-addressing table twice
/// their number, each slot holding a position's number; equal keys are found exactly (the hash only picks
/// where to look first).
pub(crate) fn weld(count: usize, key: impl Fn(usize) -> PositionKey) -> Welded {
    let bits = (2 * count).next_power_of_two().max(2).ilog2();
    let mut slots = vec![u32::MAX; 1 << bits];
    let mask = slots.len() - 1;
    let mut welded = Welded { id: Vec::with_capacity(count), first: Vec::new() };
    for c in 0..count {
        let k = key(c);
        let mut slot = (mix(mix(k[0] ^ k[1].rotate_left(32)) ^ k[2]) >> (64 - bits)) as usize;
        let id = loop {
            match slots[slot] {
                u32::MAX => {
                    let id = welded.first.len() as u32;
                    slots[slot] = id;
                    welded.first.push(c as u32);
                    break id;
                }
                id if key(welded.first[id as usize] as usize) == k => break id,
                _ => slot = (slot + 1) & mask,
            }
        };
        welded.id.push(id);
    }
    welded
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_positions_and_signed_zeros_share_a_number_in_order_of_first_appearance() {
        let corners = [[0.0, 1.0, 2.0], [-0.0, 1.0, 2.0], [0.0, 1.0, 2.5], [0.0, 1.0, 2.0]];
        let welded = weld(corners.len(), |c| soup_key(corners[c]));
        assert_eq!((welded.id, welded.first), (vec![0, 0, 1, 0], vec![0, 2]));
        // Many keys, few distinct: the table's probing finds every repeat.
        let many: Vec<DVec3> = (0..20_000).map(|i| DVec3::new((i % 97) as f64, (i % 89) as f64 * 0.5, 1.0)).collect();
        let welded = weld(many.len(), |c| grid_key(many[c]));
        assert_eq!(welded.first.len(), 97 * 89);
        assert!(welded.id.iter().enumerate().all(|(c, &id)| many[welded.first[id as usize] as usize] == many[c]));
    }
}
