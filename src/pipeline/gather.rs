//! What a parallel pass selects from a slice, gathered into one vector of
//! exactly its number.
//!
//! rayon's `collect` of a filtered iterator cannot know how many items will
//! come: it collects each job's piece on its own, then copies the pieces
//! into one vector, so at its peak it holds the items twice. On a cloud
//! without a pixel grid those items (a key and an index per point, say)
//! are as large as the cloud or larger, and that copy was the measured
//! path's peak. Here each chunk of the slice first counts what it selects;
//! one vector of the total is allocated, split into a part per chunk, and
//! each chunk writes its items straight into its own part, in the slice's
//! order. The selection is read twice instead of once.

use rayon::prelude::*;

/// The elements of a parallel chunk.
const ELEMENTS_PER_CHUNK: usize = 1 << 14;

/// `item(i, e)` for every element `e` (at `i`) of `elements` that
/// `selected(i, e)` picks, in the slice's order; `None` if any item is.
pub(crate) fn try_gather<E: Sync, T: Copy + Default + Send>(
    elements: &[E],
    selected: impl Fn(usize, &E) -> bool + Sync,
    item: impl Fn(usize, &E) -> Option<T> + Sync,
) -> Option<Vec<T>> {
    let count = |k: usize, chunk: &[E]| indexed(k, chunk).filter(|&(i, e)| selected(i, e)).count();
    fill_counted(elements, count, |k, chunk, part| {
        let items = indexed(k, chunk).filter(|&(i, e)| selected(i, e)).map(|(i, e)| item(i, e));
        for (slot, value) in part.iter_mut().zip(items) {
            *slot = value?;
        }
        Some(())
    })
}

/// `item(i, e)` for every element `e` (at `i`) of `elements` that
/// `selected(i, e)` picks, in the slice's order.
pub(crate) fn gather<E: Sync, T: Copy + Default + Send>(
    elements: &[E],
    selected: impl Fn(usize, &E) -> bool + Sync,
    item: impl Fn(usize, &E) -> T + Sync,
) -> Vec<T> {
    try_gather(elements, selected, |i, e| Some(item(i, e))).unwrap_or_default()
}

/// Every `Some` of `item(i, e)` over `elements`, in the slice's order: for
/// a selection that computes what its item is made of. `item` runs twice
/// per element, once to count and once to fill.
pub(crate) fn gather_filter_map<E: Sync, T: Copy + Default + Send>(
    elements: &[E],
    item: impl Fn(usize, &E) -> Option<T> + Sync,
) -> Vec<T> {
    let count = |k: usize, chunk: &[E]| indexed(k, chunk).filter(|&(i, e)| item(i, e).is_some()).count();
    let filled = fill_counted(elements, count, |k, chunk, part| {
        for (slot, value) in part.iter_mut().zip(indexed(k, chunk).filter_map(|(i, e)| item(i, e))) {
            *slot = value;
        }
        Some(())
    });
    filled.unwrap_or_default()
}

/// The elements of chunk `k` with their indices in the whole slice.
fn indexed<E>(k: usize, chunk: &[E]) -> impl Iterator<Item = (usize, &E)> {
    (k * ELEMENTS_PER_CHUNK..).zip(chunk)
}

/// One vector of the sum of `count(k, chunk)` over the slice's chunks,
/// each chunk's part filled by `fill(k, chunk, part)`, on rayon; `None` if
/// any fill is.
fn fill_counted<E: Sync, T: Copy + Default + Send>(
    elements: &[E],
    count: impl Fn(usize, &[E]) -> usize + Sync,
    fill: impl Fn(usize, &[E], &mut [T]) -> Option<()> + Sync,
) -> Option<Vec<T>> {
    let counts: Vec<usize> =
        elements.par_chunks(ELEMENTS_PER_CHUNK).enumerate().map(|(k, chunk)| count(k, chunk)).collect();
    let mut gathered = vec![T::default(); counts.iter().sum()];
    let complete = split_into_parts(&mut gathered, counts)
        .into_par_iter()
        .zip(elements.par_chunks(ELEMENTS_PER_CHUNK))
        .enumerate()
        .all(|(k, (part, chunk))| fill(k, chunk, part).is_some());
    complete.then_some(gathered)
}

/// `all` split into consecutive parts of the lengths `counts` gives, each
/// for one parallel job to fill; `counts` must sum to `all`'s length.
pub(crate) fn split_into_parts<T>(all: &mut [T], counts: impl IntoIterator<Item = usize>) -> Vec<&mut [T]> {
    let counts = counts.into_iter();
    let mut parts = Vec::with_capacity(counts.size_hint().0);
    let mut rest = all;
    for n in counts {
        let (part, tail) = rest.split_at_mut(n);
        parts.push(part);
        rest = tail;
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gathers_what_a_sequential_filter_map_gives_in_order() {
        for n in [0, 1, ELEMENTS_PER_CHUNK - 1, ELEMENTS_PER_CHUNK, 3 * ELEMENTS_PER_CHUNK + 17] {
            let elements: Vec<u32> = (0..n as u32).map(|i| i.wrapping_mul(2_654_435_761) >> 7).collect();
            let selected = |i: usize, e: &u32| !(i + *e as usize).is_multiple_of(3);
            let item = |i: usize, e: &u32| (*e as u64) << 32 | i as u64;
            let expected: Vec<u64> =
                elements.iter().enumerate().filter(|&(i, e)| selected(i, e)).map(|(i, e)| item(i, e)).collect();
            let got = gather(&elements, selected, item);
            assert_eq!(got, expected, "{n} elements");
            assert_eq!(got.capacity(), expected.len(), "allocated once, at its size");
            let mapped = gather_filter_map(&elements, |i, e| selected(i, e).then(|| item(i, e)));
            assert_eq!(mapped, expected, "{n} elements, filter-mapped");
            assert_eq!(mapped.capacity(), expected.len());
        }
    }

    #[test]
    fn one_missing_item_fails_the_whole_gather() {
        let elements: Vec<u32> = (0..3 * ELEMENTS_PER_CHUNK as u32).collect();
        let item = |_: usize, e: &u32| (*e != 40_000).then_some(*e);
        assert_eq!(try_gather(&elements, |_, _| true, item), None);
        let skipped = try_gather(&elements, |_, e| *e != 40_000, item).expect("the missing one is not selected");
        assert_eq!(skipped.len(), elements.len() - 1);
    }
}
