//! The number of distinct colours among a model's cells ([`count`]): a small set while they are few, a sort once
//! they are many, halves of a long list side by side.

use crate::radix;

/// The number of distinct colours among `colors`. A list of more than [`DISTINCT_SPLIT`] is split in halves whose
/// distinct colours are collected side by side, then counted together.
pub(crate) fn count(colors: &[([u8; 4], u32)]) -> usize {
    if colors.len() <= DISTINCT_SPLIT {
        return distinct_sorted(colors).len();
    }
    let (left, right) = colors.split_at(colors.len() / 2);
    let (left, right) = rayon::join(|| distinct_sorted(left), || distinct_sorted(right));
    union_count(&left, &right)
}

/// The distinct colours among `colors` (as little-endian `u32`), ascending.
fn distinct_sorted(colors: &[([u8; 4], u32)]) -> Vec<u32> {
    // Neighbouring cells often share a colour: a repeat of the colour before is passed over.
    let values = || {
        let mut last = None;
        colors.iter().map(|c| u32::from_le_bytes(c.0)).filter(move |&v| last.replace(v) != Some(v))
    };
    // Most models show a few colours (their materials, a palette of vertex colours, a texture's): a small set
    // collects them. Past `SMALL_SET` of them, or once the first `FEW_NEW` came among fewer than an eighth more values
    // (colours that hardly repeat: vertex colours varying across every face), the values are sorted.
    let mut seen = rustc_hash::FxHashSet::default();
    // The colours seen last, in slots picked by a multiplicative hash of the colour: most repeats are found there
    // before the set is asked (a textured model's cells repeat a few hundred colours in no order).
    let mut recent = [None; RECENT];
    for (count, v) in values().enumerate() {
        let slot = &mut recent[(v.wrapping_mul(0x9E37_79B9) >> (u32::BITS - RECENT.trailing_zeros())) as usize];
        if slot.replace(v) == Some(v) {
            continue;
        }
        if seen.insert(v) && (seen.len() > SMALL_SET || seen.len() == FEW_NEW && count < FEW_NEW + FEW_NEW / 8) {
            let mut all = Vec::with_capacity(colors.len());
            all.extend(values());
            let mut values = radix::sort_by_key(all, u32::BITS, |&v| v);
            values.dedup();
            return values;
        }
    }
    let mut values: Vec<u32> = seen.into_iter().collect();
    values.sort_unstable();
    values
}

/// The number of values in either of two ascending lists without repeats.
fn union_count(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut j, mut count) = (0, 0, 0);
    while i < a.len() && j < b.len() {
        let (x, y) = (a[i], b[j]);
        i += usize::from(x <= y);
        j += usize::from(y <= x);
        count += 1;
    }
    count + (a.len() - i) + (b.len() - j)
}

/// The most distinct values [`distinct_sorted`] collects in a set (a textured model shows a few thousand: CesiumMan at
/// R=128 1,488, whose count took 0.14 ms when the set stopped at 2¹⁰ and the values were sorted, 0.10 ms in the set).
const SMALL_SET: usize = 1 << 13;

/// The colours after which [`distinct_sorted`] judges whether they repeat: when they came among fewer than an eighth
/// more values, it sorts the values rather than filling its set. (The box of vertex colours, 96,776 cells of 92,495
/// colours, fresh runs of 11, the count alone: at R=128 1.97 → 1.29 ms, at R=256 7.04 → 6.15; a textured box whose
/// first cells are each of a new texel, 2,601 colours of 390,152 at R=256, 0.53 → 0.70.)
const FEW_NEW: usize = 1 << 10;

/// The slots of [`distinct_sorted`]'s recent colours (a power of two). (The milk truck at R=128, 46,129 colours of 132
/// kinds from a texture: counted in 0.12 ms rather than 0.15, warm.)
const RECENT: usize = 256;

/// Above this many colours, [`count`] counts the halves of the list side by side. (Fresh runs at R=128, medians of
/// 15 of the count alone, split from 2¹⁷ colours and from 2¹²: the milk truck's 46,129 colours 0.134 and 0.087 ms, the
/// duck's 60,530 0.080 and 0.046, CesiumMan's 14,698 0.142 and 0.127, the Fox's 14,054 0.027 and 0.023.)
const DISTINCT_SPLIT: usize = 1 << 12;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distinct_values_are_counted_whether_few_or_many() {
        // Runs of repeats and values seen again far apart, below and above the small set's size, in lists short
        // enough for one task and long enough to be split (the halves sharing colours, or one of a single colour).
        let check = |values: Vec<u32>, case: &str| {
            let colors: Vec<([u8; 4], u32)> = values.iter().map(|v| (v.to_le_bytes(), 0)).collect();
            let expected: std::collections::BTreeSet<u32> = values.into_iter().collect();
            if colors.len() <= DISTINCT_SPLIT {
                assert_eq!(distinct_sorted(&colors), expected.iter().copied().collect::<Vec<_>>(), "{case}");
            }
            assert_eq!(count(&colors), expected.len(), "{case}");
            expected.len()
        };
        let long = (2 * DISTINCT_SPLIT).max(1 << 18) as u32 + 1;
        for len in [1_000, long] {
            for kinds in [1, 7, SMALL_SET, SMALL_SET + 1, 50_000] {
                let values = (0..len).map(|k| (k / 3).wrapping_mul(2_654_435_761) % kinds as u32).collect();
                let count = check(values, &format!("{kinds} kinds of {len}"));
                assert!(len == 1_000 || (count > SMALL_SET) == (kinds > SMALL_SET), "{count} of {kinds} kinds");
            }
        }
        // Colours that hardly repeat at first (sorted once the first `FEW_NEW` are in), then repeat.
        let first_new = |kinds: u32| (0..kinds).chain(0..kinds).map(|k| k.wrapping_mul(2_654_435_761)).collect();
        assert_eq!(check(first_new(2_000), "2,000 new, then again"), 2_000);
        assert_eq!(check(first_new(5_000), "5,000 new, then again, in halves"), 5_000);
        // Opaque white is the largest value (every byte 255), and black the smallest.
        assert_eq!(check(vec![u32::MAX; 5], "white"), 1);
        assert_eq!(check(vec![3, u32::MAX, 0, u32::MAX, 3], "white, black and another"), 3);
        let halves = (0..long).map(|k| if k < long / 2 { 7 } else { k.wrapping_mul(2_654_435_761) % 50_000 });
        assert!(check(halves.collect(), "one colour, then many") > SMALL_SET);
        assert_eq!(count(&[]), 0);
        assert_eq!(union_count(&[1, 4, 9], &[0, 4, 5, 9, 12]), 6);
        assert_eq!(union_count(&[], &[3]), 1);
    }
}
