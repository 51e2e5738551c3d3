//! A monotone radix heap of `(distance, node)` pairs: the narrow band's
//! priority queue.
//!
//! Fast marching pops nodes in non-decreasing distance, so a *radix heap*
//! (Ahuja, Mehlhorn, Orlin & Tarjan 1990) fits better than a binary heap:
//! pushes are O(1), pops amortized O(number of key bits), and the buckets are
//! flat vectors with no per-node allocation. Keys are the bit patterns of
//! non-negative `f32` distances, which order like the floats themselves.
//!
//! Lazy deletion: a node whose tentative distance drops is pushed again; the
//! caller skips stale entries (nodes already accepted) when they surface.

/// Number of buckets: one for keys equal to the last popped key, one per
/// highest differing bit of a `u32`.
const BUCKETS: usize = 33;

/// Monotone min-priority queue keyed by non-negative `f32`.
#[derive(Debug)]
pub(crate) struct RadixHeap {
    /// Key of the last popped entry; every stored key is at least this.
    last: u32,
    /// `buckets[b]` holds keys whose highest bit differing from `last` is `b − 1`
    /// (`b = 0`: equal to `last`).
    buckets: [Vec<(u32, u32)>; BUCKETS],
    len: usize,
}

impl RadixHeap {
    /// An empty heap.
    pub(crate) fn new() -> Self {
        Self { last: 0, buckets: std::array::from_fn(|_| Vec::new()), len: 0 }
    }

    /// Bucket of `key` relative to the last popped key.
    #[inline]
    fn bucket(&self, key: u32) -> usize {
        (u32::BITS - (key ^ self.last).leading_zeros()) as usize
    }

    /// Inserts `node` with priority `distance` (≥ 0). A distance below the
    /// last popped one is raised to it, so the heap stays monotone: the entry
    /// then comes out next, which is what a front that already passed it needs.
    #[inline]
    pub(crate) fn push(&mut self, distance: f32, node: u32) {
        let key = distance.max(0.0).to_bits().max(self.last);
        let b = self.bucket(key);
        self.buckets[b].push((key, node));
        self.len += 1;
    }

    /// Removes an entry of smallest distance, returning its node.
    pub(crate) fn pop(&mut self) -> Option<u32> {
        if self.len == 0 {
            return None;
        }
        if self.buckets[0].is_empty() {
            let b = self.buckets.iter().position(|v| !v.is_empty())?;
            let mut moving = std::mem::take(&mut self.buckets[b]);
            self.last = moving.iter().map(|e| e.0).min().unwrap_or(self.last);
            for &(key, node) in &moving {
                let nb = self.bucket(key);
                self.buckets[nb].push((key, node));
            }
            moving.clear();
            // Keep the drained vector's capacity for later refills.
            self.buckets[b] = moving;
        }
        self.len -= 1;
        self.buckets[0].pop().map(|e| e.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Interleaved monotone pushes and pops give the same distance
        /// sequence as a sorted reference.
        #[test]
        fn pops_in_order(batches in prop::collection::vec(prop::collection::vec(0.0f32..100.0, 0..20), 1..20)) {
            let mut heap = RadixHeap::new();
            let mut reference: Vec<f32> = Vec::new();
            let mut dist = Vec::new();
            let mut floor = 0.0f32;
            for batch in batches {
                for d in batch {
                    heap.push(floor + d, dist.len() as u32);
                    reference.push(floor + d);
                    dist.push(floor + d);
                }
                reference.sort_by(|a, b| b.total_cmp(a));
                for _ in 0..3 {
                    let (Some(want), Some(got)) = (reference.pop(), heap.pop()) else { break };
                    prop_assert_eq!(dist[got as usize], want);
                    floor = want;
                }
            }
            reference.sort_by(|a, b| b.total_cmp(a));
            while let Some(got) = heap.pop() {
                prop_assert_eq!(Some(dist[got as usize]), reference.pop());
            }
            prop_assert!(reference.is_empty());
        }
    }

    #[test]
    fn late_keys_are_raised_to_the_front() {
        let mut heap = RadixHeap::new();
        heap.push(5.0, 0);
        heap.push(7.0, 1);
        assert_eq!(heap.pop(), Some(0));
        heap.push(1.0, 2); // behind the front: comes out next
        assert_eq!(heap.pop(), Some(2));
        assert_eq!(heap.pop(), Some(1));
        assert_eq!(heap.pop(), None);
    }
}
