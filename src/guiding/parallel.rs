//! Per-leaf work of the refit spread over the host's cores. Each leaf is touched by one
//! thread and results are combined in leaf order, so the tree is the same bit for bit
//! whatever the number of threads.

/// Below this many items one thread does it all (spawning costs more than it saves).
const MIN_ITEMS_PER_THREAD: usize = 64;

/// Threads to use: the host's parallelism, at most one per `MIN_ITEMS_PER_THREAD` items.
fn threads_for(items: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    cores.min(items / MIN_ITEMS_PER_THREAD).max(1)
}

/// `f(index, item)` for every item, in contiguous chunks on scoped threads; returns the
/// results in item order.
pub(crate) fn map_mut<T: Send, R: Send>(
    items: &mut [T],
    f: impl Fn(usize, &mut T) -> R + Sync,
) -> Vec<R> {
    let threads = threads_for(items.len());
    if threads <= 1 {
        return items.iter_mut().enumerate().map(|(i, t)| f(i, t)).collect();
    }
    let chunk = items.len().div_ceil(threads);
    let f = &f;
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks_mut(chunk)
            .enumerate()
            .map(|(c, part)| {
                scope.spawn(move || {
                    part.iter_mut()
                        .enumerate()
                        .map(|(i, t)| f(c * chunk + i, t))
                        .collect::<Vec<R>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a refit thread panicked"))
            .collect()
    })
}

/// Like [`map_mut`], with the items split among the threads by `cost` (one per item)
/// rather than by count: per-leaf work is skewed (a few leaves near the camera hold most
/// of a pass's records), and equal counts left most threads waiting on one.
pub(crate) fn map_mut_by_cost<T: Send, R: Send>(
    items: &mut [T],
    cost: &[u64],
    f: impl Fn(usize, &mut T) -> R + Sync,
) -> Vec<R> {
    assert_eq!(items.len(), cost.len(), "one cost per item");
    let threads = threads_for(items.len());
    if threads <= 1 {
        return items.iter_mut().enumerate().map(|(i, t)| f(i, t)).collect();
    }
    // Chunk ends where the running cost passes each thread's equal share.
    let total: u64 = cost.iter().sum::<u64>().max(1);
    let mut ends = Vec::with_capacity(threads);
    let mut running = 0u64;
    for (i, &c) in cost.iter().enumerate() {
        running += c;
        if running * threads as u64 >= total * (ends.len() as u64 + 1) && ends.len() + 1 < threads {
            ends.push(i + 1);
        }
    }
    ends.push(items.len());
    let f = &f;
    std::thread::scope(|scope| {
        let mut rest = items;
        let mut start = 0usize;
        let mut handles = Vec::with_capacity(ends.len());
        for &end in &ends {
            let (part, tail) = std::mem::take(&mut rest).split_at_mut(end - start);
            rest = tail;
            let first = start;
            handles.push(scope.spawn(move || {
                part.iter_mut()
                    .enumerate()
                    .map(|(i, t)| f(first + i, t))
                    .collect::<Vec<R>>()
            }));
            start = end;
        }
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a refit thread panicked"))
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_mut_visits_every_item_once_in_order() {
        for n in [0usize, 1, 63, 64, 200, 1000, 4097] {
            let mut items: Vec<u64> = (0..n as u64).collect();
            let out = map_mut(&mut items, |i, x| {
                *x += 1;
                i as u64 * 10
            });
            assert_eq!(items, (1..=n as u64).collect::<Vec<_>>());
            assert_eq!(out, (0..n as u64).map(|i| i * 10).collect::<Vec<_>>());
        }
    }

    #[test]
    fn map_mut_by_cost_visits_every_item_once_in_order() {
        for n in [0usize, 1, 63, 64, 200, 1000, 4097] {
            // Skewed costs: one heavy item, zeros, and uniform ones.
            for cost in [
                (0..n)
                    .map(|i| if i == n / 3 { 1_000_000 } else { 1 })
                    .collect::<Vec<u64>>(),
                vec![0; n],
                vec![5; n],
            ] {
                let mut items: Vec<u64> = (0..n as u64).collect();
                let out = map_mut_by_cost(&mut items, &cost, |i, x| {
                    *x += 1;
                    i as u64 * 10
                });
                assert_eq!(items, (1..=n as u64).collect::<Vec<_>>());
                assert_eq!(out, (0..n as u64).map(|i| i * 10).collect::<Vec<_>>());
            }
        }
    }
}
