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
/// use shadelab::internal::parallel::{capped_threads, thread_cap};
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

#[cfg(test)]
mod tests {
    use crate::grid::Image;
    use crate::pipeline::lightness::{run as lightness, LightnessConfig};
    use crate::reconstruct::{Problem, ReconstructOptions, Reconstructor};
    use crate::render::{render, RenderOptions};
    use crate::surface::gaussian;
    use crate::{Boundary, Grid, Lambertian, Light, NoProgress, PictureSource};
    use md5::{Digest, Md5};

    /// The digests both builds must give, recorded by `SHADELAB_BLESS=1`.
    const RECORDED: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/parallel-digests.txt"
    );

    fn digest(images: &[&Image]) -> String {
        let mut md5 = Md5::new();
        for image in images {
            image
                .data()
                .iter()
                .for_each(|v| md5.update(v.to_le_bytes()));
        }
        format!("{:x}", md5.finalize())
    }

    /// A solve large enough for the solver's parallel sweeps and levels (40,000 unknowns), its
    /// depth, and the ODOG model (parallel FFTs) give the same bytes with and without the
    /// `parallel` feature: CI runs this test in both builds against one recorded digest.
    #[test]
    fn the_same_bytes_with_and_without_worker_threads() {
        let surface = gaussian(200, 200, 20.0, 20.0, 0.0, 0.0).unwrap();
        let map = Lambertian {
            light: Light::from_tilt_slant(20.0, 40.0).unwrap(),
            albedo: 1.0,
            ambient: 0.0,
        };
        let image = render(&surface, &map, &RenderOptions::default()).image;
        let everywhere = Grid::new(200, 200, true);
        let problem = Problem {
            image: &image,
            mask: &everywhere,
            boundary: &Boundary::Flat,
            reflectance: &map,
        };
        let mut planner = Reconstructor::new(200, 200, ReconstructOptions::default()).unwrap();
        let r = planner.reconstruct(&problem, &NoProgress).unwrap();
        assert!(r.shape.solution.unknowns >= 32_768);
        let source = PictureSource {
            stimulus: Some("checker-shadow".into()),
            ppd: Some(10.0),
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
            ..Default::default()
        };
        let config = LightnessConfig::new(source, vec!["odog".parse().unwrap()]).unwrap();
        let odog = lightness(&config, &NoProgress).unwrap();
        let s = &r.shape.solution;
        let found = format!(
            "solve {}\nodog {}\n",
            digest(&[&s.f, &s.g, &r.depth.depth]),
            digest(&[&odog.images[0].1])
        );
        if std::env::var_os("SHADELAB_BLESS").is_some() {
            std::fs::write(RECORDED, &found).unwrap();
        }
        let recorded = std::fs::read_to_string(RECORDED).unwrap();
        assert_eq!(found, recorded, "threads: {}", super::threads());
    }
}
