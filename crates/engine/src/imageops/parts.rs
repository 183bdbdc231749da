//! Connected parts: the 4-connected components of a mask, or the components of any graph.
//!
//! The search is a depth-first flood from each unvisited node in index order (row-major for a
//! grid), visiting a grid pixel's neighbours left, right, up, down. Each part keeps its members
//! in the order the search reached them, so that a sum over a part is the same, bit for bit,
//! wherever it is computed; [`Parts::subtract_means`] offers that order or index order.

use crate::grid::Mask;

/// The connected parts of a graph or mask, numbered 0.. in the order of their first node.
///
/// ```
/// use shadelab_engine::imageops::parts;
/// use shadelab::Grid;
/// // Two parts: the L on the left (4-connected) and the single pixel at the right; the
/// // diagonal neighbour of the L's foot is not connected to it.
/// let mask = Grid::from_vec(4, 3, vec![
///     true,  false, false, true,
///     true,  false, false, false,
///     true,  true,  false, false,
/// ]).unwrap();
/// let p = parts(&mask);
/// assert_eq!(p.count(), 2);
/// assert_eq!(p.part(0), &[0, 4, 8, 9]);
/// assert_eq!(p.part(1), &[3]);
/// assert_eq!(p.label(9), Some(0));
/// assert_eq!(p.label(1), None);
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Parts {
    /// Part of each node, `NONE` outside every part.
    label: Vec<u32>,
    /// Members of all parts, part after part, each in visiting order.
    members: Vec<usize>,
    /// Where each part starts in `members` (one more entry than parts).
    starts: Vec<usize>,
}

const NONE: u32 = u32::MAX;

/// The order in which [`Parts::subtract_means`] sums a part's values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SumOrder {
    /// The order the search reached the members.
    Visit,
    /// Ascending node index (row-major for a grid).
    Index,
}

impl Parts {
    /// The number of parts.
    pub fn count(&self) -> usize {
        self.starts.len() - 1
    }

    /// The nodes of part `k` in visiting order. Panics when `k` is not below [`Parts::count`].
    pub fn part(&self, k: usize) -> &[usize] {
        &self.members[self.starts[k]..self.starts[k + 1]]
    }

    /// The part of node `i`, or `None` when it belongs to none (a pixel outside the mask).
    pub fn label(&self, i: usize) -> Option<usize> {
        self.label
            .get(i)
            .copied()
            .filter(|&l| l != NONE)
            .map(|l| l as usize)
    }

    /// The parts one after another.
    pub fn iter(&self) -> impl Iterator<Item = &[usize]> + '_ {
        (0..self.count()).map(move |k| self.part(k))
    }

    /// Subtracts from `values` (one per node) the mean of each part, summed in `order`; nodes
    /// outside every part are left alone.
    ///
    /// ```
    /// use shadelab_engine::imageops::{parts, parts::SumOrder};
    /// use shadelab::Grid;
    /// let mask = Grid::from_vec(3, 1, vec![true, false, true]).unwrap();
    /// let mut v = vec![1.0, 7.0, 4.0];
    /// parts(&mask).subtract_means(&mut v, SumOrder::Visit);
    /// assert_eq!(v, vec![0.0, 7.0, 0.0]);
    /// ```
    pub fn subtract_means(&self, values: &mut [f64], order: SumOrder) {
        if order == SumOrder::Index {
            // One pass in index order adds each part's values in ascending index order: the
            // sums of sorting each part, without the sort.
            let mut sums = vec![0.0; self.count()];
            for (v, &l) in values.iter().zip(&self.label) {
                if l != NONE {
                    sums[l as usize] += v;
                }
            }
            let means: Vec<f64> = (0..self.count())
                .map(|k| sums[k] / self.part(k).len() as f64)
                .collect();
            for (v, &l) in values.iter_mut().zip(&self.label) {
                if l != NONE {
                    *v -= means[l as usize];
                }
            }
            return;
        }
        let mut sorted = Vec::new();
        for part in self.iter() {
            let members = match order {
                SumOrder::Visit => part,
                SumOrder::Index => {
                    sorted.clear();
                    sorted.extend_from_slice(part);
                    sorted.sort_unstable();
                    &sorted[..]
                }
            };
            let sum = members.iter().fold(0.0, |s, &i| s + values[i]);
            let mean = sum / members.len() as f64;
            for &i in members {
                values[i] -= mean;
            }
        }
    }
}

/// The 4-connected parts of the `true` pixels of `mask`; nodes are row-major pixel indices.
pub fn parts(mask: &Mask) -> Parts {
    let (w, h) = (mask.width(), mask.height());
    let m = mask.data();
    search(
        m.len(),
        |i| m[i],
        |i, visit| {
            let (c, r) = (i % w, i / w);
            if c > 0 {
                visit(i - 1);
            }
            if c + 1 < w {
                visit(i + 1);
            }
            if r > 0 {
                visit(i - w);
            }
            if r + 1 < h {
                visit(i + w);
            }
        },
    )
}

/// The connected parts of the graph on nodes `0..n` whose edges are `neighbours[k]` (indices
/// at or above `n` are ignored); every node belongs to a part.
///
/// ```
/// use shadelab_engine::imageops::graph_parts;
/// let neighbours = vec![vec![2], vec![], vec![0, 3], vec![2]];
/// let p = graph_parts(&neighbours);
/// assert_eq!(p.count(), 2);
/// assert_eq!(p.part(0), &[0, 2, 3]);
/// assert_eq!(p.part(1), &[1]);
/// ```
pub fn graph_parts<N: AsRef<[u32]>>(neighbours: &[N]) -> Parts {
    let n = neighbours.len();
    search(
        n,
        |_| true,
        |k, visit| {
            for &q in neighbours[k].as_ref() {
                if (q as usize) < n {
                    visit(q as usize);
                }
            }
        },
    )
}

/// The depth-first search behind [`parts`] and [`graph_parts`].
fn search(
    n: usize,
    include: impl Fn(usize) -> bool,
    neighbours: impl Fn(usize, &mut dyn FnMut(usize)),
) -> Parts {
    let mut label = vec![NONE; n];
    let mut members = Vec::new();
    let mut starts = vec![0];
    let mut stack = Vec::new();
    for start in 0..n {
        if !include(start) || label[start] != NONE {
            continue;
        }
        let part = (starts.len() - 1) as u32;
        label[start] = part;
        stack.push(start);
        while let Some(i) = stack.pop() {
            members.push(i);
            neighbours(i, &mut |q| {
                if include(q) && label[q] == NONE {
                    label[q] = part;
                    stack.push(q);
                }
            });
        }
        starts.push(members.len());
    }
    Parts {
        label,
        members,
        starts,
    }
}
