//! A stable least-significant-digit radix sort by a small integer key: two or three passes over the list
//! where a comparison sort takes log n, for the shell's (cell, triangle) overlaps, the fill's column crossings
//! and the colour count.

/// Bits of the key sorted per pass.
const DIGIT_BITS: u32 = 11;

/// Sorts `items` by `key(item)`, which must be below 2^`bits`, keeping the order of items with equal keys.
pub(crate) fn sort_by_key<T: Copy + Default>(items: Vec<T>, bits: u32, key: impl Fn(&T) -> u32) -> Vec<T> {
    sort_parts_by_key(vec![items], bits, key)
}

/// [`sort_by_key`] of the concatenation of `parts` (the lists of parallel tasks), without concatenating them
/// first: the first pass reads the parts. The counts of every pass's digits are taken in one read.
pub(crate) fn sort_parts_by_key<T: Copy + Default>(parts: Vec<Vec<T>>, bits: u32, key: impl Fn(&T) -> u32) -> Vec<T> {
    let passes = bits.div_ceil(DIGIT_BITS) as usize;
    if passes == 0 {
        return parts.concat();
    }
    let mask = (1u32 << DIGIT_BITS) - 1;
    let mut starts = vec![[0usize; 1 << DIGIT_BITS]; passes];
    for item in parts.iter().flatten() {
        let k = key(item);
        for (pass, counts) in starts.iter_mut().enumerate() {
            counts[(k >> (pass as u32 * DIGIT_BITS) & mask) as usize] += 1;
        }
    }
    for counts in &mut starts {
        let mut total = 0;
        for start in counts.iter_mut() {
            (*start, total) = (total, total + *start);
        }
    }
    let len = parts.iter().map(Vec::len).sum();
    let scatter = |items: &mut dyn Iterator<Item = &T>, sorted: &mut [T], starts: &mut [usize], pass: usize| {
        for item in items {
            let d = (key(item) >> (pass as u32 * DIGIT_BITS) & mask) as usize;
            sorted[starts[d]] = *item;
            starts[d] += 1;
        }
    };
    let mut items = vec![T::default(); len];
    scatter(&mut parts.iter().flatten(), &mut items, &mut starts[0], 0);
    drop(parts);
    if passes > 1 {
        let mut sorted = vec![T::default(); len];
        for (pass, starts) in starts.iter_mut().enumerate().skip(1) {
            scatter(&mut items.iter(), &mut sorted, starts, pass);
            std::mem::swap(&mut items, &mut sorted);
        }
    }
    items
}

/// The bits a key below `count` needs.
pub(crate) fn bits_for(count: usize) -> u32 {
    usize::BITS - count.saturating_sub(1).leading_zeros()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorts_by_the_key_and_keeps_the_order_of_equal_keys() {
        let keys = [5_000_000u32, 3, 70_000, 3, 5_000_000, 0, 2047, 2048, u32::MAX];
        let items: Vec<(u32, usize)> = keys.iter().copied().zip(0..).collect();
        let mut expected = items.clone();
        expected.sort_by_key(|i| i.0);
        assert_eq!(sort_by_key(items.clone(), 32, |i| i.0), expected);
        let parts = vec![items[..4].to_vec(), vec![], items[4..].to_vec()];
        assert_eq!(sort_parts_by_key(parts, 32, |i| i.0), expected);
        let small: Vec<(u32, usize)> = items.iter().map(|&(k, i)| (k % 2048, i)).collect();
        let mut expected = small.clone();
        expected.sort_by_key(|i| i.0);
        assert_eq!(sort_by_key(small, 11, |i| i.0), expected);
        assert_eq!((bits_for(1), bits_for(2), bits_for(2048), bits_for(2049)), (0, 1, 11, 12));
    }
}
