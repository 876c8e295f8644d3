//! Independent fits in parallel, the costliest started first.
//!
//! A ranking's candidates (or the explorer's families) differ in cost by up to 10× (a 48-term family against
//! a one-parameter effect). Split in halves as `par_iter` splits them, the costliest can start last and run
//! alone at the end while the other core idles. Handed out one at a time, costliest first (longest
//! processing time first), the cores finish together. Each result is still the item's own, and the results
//! come back in the items' order, so nothing depends on the thread count or the schedule.

use rayon::prelude::*;

/// `f` of every item, computed in parallel in decreasing order of `weight` (ties: the items' order), returned
/// in the items' order.
pub fn map<T: Sync, R: Send>(items: &[T], weight: impl Fn(&T) -> usize, f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let mut order: Vec<usize> = (0..items.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(weight(&items[i])));
    let mut done: Vec<(usize, R)> = order.into_iter().par_bridge().map(|i| (i, f(&items[i]))).collect();
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, r)| r).collect()
}

#[cfg(test)]
mod tests {
    use super::map;

    #[test]
    fn results_come_back_in_the_items_order_whatever_the_schedule() {
        let items: Vec<usize> = (0..40).collect();
        let squares = map(&items, |&i| i % 7, |&i| i * i);
        assert_eq!(squares, items.iter().map(|i| i * i).collect::<Vec<_>>());
    }
}
