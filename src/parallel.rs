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
