//! Worker threads (rayon) with the `parallel` feature; without it, the same loops on one thread.
//! Every parallel loop in shadelab splits its work in fixed chunks and combines the chunks'
//! results in order, so the bytes it produces do not depend on the number of threads, nor on
//! whether threads are used at all.

/// The number of worker threads loops may use (1 without the `parallel` feature).
pub fn threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}

/// The most worker threads worth starting: four per core of this machine, and at least 4.
/// More only spend time starting threads; outputs are the same bytes for any count.
pub fn thread_cap() -> usize {
    std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .saturating_mul(4)
        .max(4)
}

/// `asked` worker threads limited to [`thread_cap`]: the count to use, and whether it was cut.
///
/// ```
/// use shadelab_core::parallel::{capped_threads, thread_cap};
/// assert_eq!(capped_threads(2), (2, false));
/// assert_eq!(capped_threads(usize::MAX), (thread_cap(), true));
/// ```
pub fn capped_threads(asked: usize) -> (usize, bool) {
    let cap = thread_cap();
    (asked.min(cap), asked > cap)
}

/// What parallel loops import: rayon's prelude with the `parallel` feature; without it,
/// stand-ins that give slices the same `par_*` methods as plain sequential iterators.
pub mod prelude {
    #[cfg(feature = "parallel")]
    pub use rayon::prelude::*;

    #[cfg(not(feature = "parallel"))]
    pub use super::sequential::{IteratorStandIns, SliceStandIns};
}

/// Combines the items of a (parallel) iterator with an associative `op` whose identity is
/// `identity`: rayon's `reduce` with the `parallel` feature, a left fold without it. For ops
/// like `max`, whose result does not depend on the grouping, both give the same bits.
#[cfg(feature = "parallel")]
pub fn reduce<I, T, F>(items: I, identity: T, op: F) -> T
where
    I: rayon::iter::ParallelIterator<Item = T>,
    T: Send + Sync + Copy,
    F: Fn(T, T) -> T + Sync + Send,
{
    items.reduce(|| identity, op)
}

/// Combines the items of an iterator with `op` from `identity` (the one-thread build).
#[cfg(not(feature = "parallel"))]
pub fn reduce<I, T, F>(items: I, identity: T, op: F) -> T
where
    I: Iterator<Item = T>,
    F: Fn(T, T) -> T,
{
    items.fold(identity, op)
}

#[cfg(not(feature = "parallel"))]
mod sequential {
    /// `par_*` methods of slices as their sequential counterparts.
    pub trait SliceStandIns<T> {
        /// `iter()`.
        fn par_iter(&self) -> std::slice::Iter<'_, T>;
        /// `iter_mut()`.
        fn par_iter_mut(&mut self) -> std::slice::IterMut<'_, T>;
        /// `chunks(n)`.
        fn par_chunks(&self, n: usize) -> std::slice::Chunks<'_, T>;
        /// `chunks_mut(n)`.
        fn par_chunks_mut(&mut self, n: usize) -> std::slice::ChunksMut<'_, T>;
    }

    impl<T> SliceStandIns<T> for [T] {
        fn par_iter(&self) -> std::slice::Iter<'_, T> {
            self.iter()
        }
        fn par_iter_mut(&mut self) -> std::slice::IterMut<'_, T> {
            self.iter_mut()
        }
        fn par_chunks(&self, n: usize) -> std::slice::Chunks<'_, T> {
            self.chunks(n)
        }
        fn par_chunks_mut(&mut self, n: usize) -> std::slice::ChunksMut<'_, T> {
            self.chunks_mut(n)
        }
    }

    /// rayon's splitting hints, which mean nothing on one thread.
    pub trait IteratorStandIns: Iterator + Sized {
        /// Returns the iterator as it is.
        fn with_min_len(self, _len: usize) -> Self {
            self
        }

        /// `map` with one state made by `init` for the whole (one-thread) loop.
        fn map_init<S, R, I, F>(self, init: I, mut f: F) -> impl Iterator<Item = R>
        where
            I: Fn() -> S,
            F: FnMut(&mut S, Self::Item) -> R,
        {
            let mut state = init();
            self.map(move |item| f(&mut state, item))
        }

        /// `for_each` with one state made by `init` for the whole (one-thread) loop.
        fn for_each_init<S, I, F>(self, init: I, mut f: F)
        where
            I: Fn() -> S,
            F: FnMut(&mut S, Self::Item),
        {
            let mut state = init();
            self.for_each(|item| f(&mut state, item))
        }
    }

    impl<I: Iterator> IteratorStandIns for I {}
}
