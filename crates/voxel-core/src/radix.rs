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
/// first: the first pass reads the parts.
pub(crate) fn sort_parts_by_key<T: Copy + Default>(parts: Vec<Vec<T>>, bits: u32, key: impl Fn(&T) -> u32) -> Vec<T> {
    let passes = bits.div_ceil(DIGIT_BITS);
    if passes == 0 {
        return parts.concat();
    }
    let mask = (1u32 << DIGIT_BITS) - 1;
    let key = &key;
    let digit = |pass: u32| move |item: &T| (key(item) >> (pass * DIGIT_BITS) & mask) as usize;
    let len = parts.iter().map(Vec::len).sum();
    let mut items = vec![T::default(); len];
    counting_pass(parts.iter().flatten(), &mut items, digit(0));
    drop(parts);
    if passes > 1 {
        let mut sorted = vec![T::default(); len];
        for pass in 1..passes {
            counting_pass(items.iter(), &mut sorted, digit(pass));
            std::mem::swap(&mut items, &mut sorted);
        }
    }
    items
}

/// One stable counting sort of `items` by `digit` (below 2^`DIGIT_BITS`) into `sorted`.
fn counting_pass<'a, T: Copy + 'a>(
    items: impl Iterator<Item = &'a T> + Clone,
    sorted: &mut [T],
    digit: impl Fn(&T) -> usize,
) {
    let mut starts = vec![0usize; 1 << DIGIT_BITS];
    for item in items.clone() {
        starts[digit(item)] += 1;
    }
    let mut total = 0;
    for start in &mut starts {
        (*start, total) = (total, total + *start);
    }
    for item in items {
        let d = digit(item);
        sorted[starts[d]] = *item;
        starts[d] += 1;
    }
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
