//! A stable least-significant-digit radix sort by a small integer key: one to three passes over the list
//! where a comparison sort takes log n, for the shell's (cell, triangle) overlaps, the fill's column crossings
//! and the colour count.

/// Bits of the key sorted per pass.
const DIGIT_BITS: u32 = 11;

/// Bytes of the first segment of a [`Segments`] list, and of the largest.
const SEGMENT_BYTES: [usize; 2] = [512, 1 << 20];

/// A list that grows by segments, each twice the size of the one before (up to a limit), for the parallel
/// tasks that collect what is sorted afterwards: growing never moves what is already in (a `Vec` doubling
/// copies its items into fresh memory, so that the pages touched add up to about twice the list's), and the
/// segments are the parts [`sort_parts_by_key`] reads.
#[derive(Debug)]
pub(crate) struct Segments<T>(Vec<Vec<T>>);

impl<T> Default for Segments<T> {
    fn default() -> Self {
        Self(Vec::new())
    }
}

impl<T> Segments<T> {
    /// Appends `item`.
    #[inline(always)]
    pub fn push(&mut self, item: T) {
        match self.0.last_mut() {
            Some(last) if last.len() < last.capacity() => last.push(item),
            _ => self.grow(item),
        }
    }

    /// Appends `item` in a new segment (out of line: most pushes find room in the last one).
    #[cold]
    #[inline(never)]
    fn grow(&mut self, item: T) {
        let bytes =
            self.0.last().map_or(SEGMENT_BYTES[0], |last| (2 * last.len() * size_of::<T>()).min(SEGMENT_BYTES[1]));
        let mut segment = Vec::with_capacity(bytes.div_ceil(size_of::<T>()));
        segment.push(item);
        self.0.push(segment);
    }

    /// The segments of every list of `lists`, in order.
    pub fn concat(lists: Vec<Self>) -> Vec<Vec<T>> {
        lists.into_iter().flat_map(|list| list.0).collect()
    }
}

/// Sorts `items` by `key(item)`, which must be below 2^`bits`, keeping the order of items with equal keys.
pub(crate) fn sort_by_key<T: Copy + Default>(items: Vec<T>, bits: u32, key: impl Fn(&T) -> u32) -> Vec<T> {
    sort_parts_by_key(vec![items], bits, key)
}

/// [`sort_by_key`] of the concatenation of `parts` (the lists of parallel tasks), without concatenating them
/// first: the first pass reads the parts.
pub(crate) fn sort_parts_by_key<T: Copy + Default>(parts: Vec<Vec<T>>, bits: u32, key: impl Fn(&T) -> u32) -> Vec<T> {
    let len = parts.iter().map(Vec::len).sum();
    let digits = Digits::new(len * size_of::<T>(), bits);
    let last = digits.passes - 1;
    if last == 0 {
        let mut sorted = vec![T::default(); len];
        counting_pass(
            parts.iter().flatten(),
            digits.width,
            |item| digits.of(key(item), 0),
            |at, item| sorted[at] = item,
        );
        return sorted;
    }
    // The last pass writes to the spare list: no third list.
    let (items, mut sorted) = leading_passes(parts, &digits, &key, Vec::new());
    // Every position below `len` is written by the pass: only the length needs setting.
    sorted.resize(len, T::default());
    counting_pass(items.iter(), digits.width, |item| digits.of(key(item), last), |at, item| sorted[at] = item);
    sorted
}

/// [`sort_parts_by_key`] without the sorted list: its last pass hands each item to `place` with its position in
/// the sorted order (in no particular order of positions), for a caller that splits the items into lists of
/// their fields. A sort of several passes writes its first into `scratch` (whatever it holds), which a caller on
/// another thread can allocate where memory is at hand (a thread's first allocations touch fresh pages).
pub(crate) fn sort_parts_into<T: Copy + Default>(
    parts: Vec<Vec<T>>,
    bits: u32,
    key: impl Fn(&T) -> u32,
    place: impl FnMut(usize, T),
    scratch: Vec<T>,
) {
    let digits = Digits::new(parts.iter().map(Vec::len).sum::<usize>() * size_of::<T>(), bits);
    let last = digits.passes - 1;
    if last == 0 {
        return counting_pass(parts.iter().flatten(), digits.width, |item| digits.of(key(item), 0), place);
    }
    let (items, spare) = leading_passes(parts, &digits, &key, scratch);
    drop(spare);
    counting_pass(items.iter(), digits.width, |item| digits.of(key(item), last), place);
}

/// The digits of a sort, chosen for the memory a fresh process touches (a page fault per 4 KiB): a key whose
/// counts take no more room than the list (the fill's columns) is one digit, so one pass writes the sorted
/// order straight from the parts; otherwise digits of [`DIGIT_BITS`].
struct Digits {
    width: u32,
    passes: u32,
}

impl Digits {
    /// The digits of `bits`-bit keys of a list of `bytes`.
    fn new(bytes: usize, bits: u32) -> Self {
        let counts_bytes = (size_of::<usize>() as u64) << bits;
        let width = if counts_bytes <= bytes as u64 { bits } else { DIGIT_BITS };
        Self { width, passes: bits.div_ceil(width.max(1)).max(1) }
    }

    /// Digit `pass` of `key`.
    #[inline]
    fn of(&self, key: u32, pass: u32) -> usize {
        (u64::from(key) >> (pass * self.width) & ((1u64 << self.width) - 1)) as usize
    }
}

/// Every pass of a sort in several but the last, the first into `items` (whatever it holds): the items in that
/// order, and a spare list for the last pass (the largest part's memory, or the first pass's when a third pass
/// reused that).
fn leading_passes<T: Copy + Default>(
    parts: Vec<Vec<T>>,
    digits: &Digits,
    key: &impl Fn(&T) -> u32,
    mut items: Vec<T>,
) -> (Vec<T>, Vec<T>) {
    let len = parts.iter().map(Vec::len).sum();
    items.clear();
    items.resize(len, T::default());
    counting_pass(parts.iter().flatten(), digits.width, |item| digits.of(key(item), 0), |at, item| items[at] = item);
    let mut spare = parts.into_iter().max_by_key(Vec::capacity).unwrap_or_default();
    for pass in 1..digits.passes - 1 {
        spare.resize(len, T::default());
        counting_pass(items.iter(), digits.width, |item| digits.of(key(item), pass), |at, item| spare[at] = item);
        std::mem::swap(&mut items, &mut spare);
    }
    (items, spare)
}

/// One stable counting sort of `items` by `digit` (below 2^`digit_bits`): each item goes to `place` with its
/// position in the sorted order.
fn counting_pass<'a, T: Copy + 'a>(
    items: impl Iterator<Item = &'a T> + Clone,
    digit_bits: u32,
    digit: impl Fn(&T) -> usize,
    mut place: impl FnMut(usize, T),
) {
    let mut starts = vec![0usize; 1 << digit_bits];
    for item in items.clone() {
        starts[digit(item)] += 1;
    }
    let mut total = 0;
    for start in &mut starts {
        (*start, total) = (total, total + *start);
    }
    for item in items {
        let d = digit(item);
        place(starts[d], *item);
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
        // Counts of 2^12 words take less room than 10,000 items: one pass with a 12-bit digit.
        let many: Vec<(u32, usize)> = (0..10_000).map(|i| ((i * 7919 % 4096) as u32, i)).collect();
        let mut expected = many.clone();
        expected.sort_by_key(|i| i.0);
        assert_eq!(sort_parts_by_key(vec![many[..3000].to_vec(), many[3000..].to_vec()], 12, |i| i.0), expected);
        assert_eq!(sort_by_key(vec![(0u32, 'a'), (0, 'b')], 0, |i| i.0), [(0, 'a'), (0, 'b')]);
        let mut segments = (Segments::default(), Segments::default());
        for (k, &item) in many.iter().enumerate() {
            if k < 7000 { segments.0.push(item) } else { segments.1.push(item) }
        }
        let parts = Segments::concat(vec![segments.0, segments.1]);
        assert_eq!(
            parts.iter().map(Vec::len).collect::<Vec<_>>(),
            [32, 64, 128, 256, 512, 1024, 2048, 2936, 32, 64, 128, 256, 512, 1024, 984]
        );
        assert_eq!(parts.concat(), many);
        assert_eq!((bits_for(1), bits_for(2), bits_for(2048), bits_for(2049)), (0, 1, 11, 12));
    }
}
