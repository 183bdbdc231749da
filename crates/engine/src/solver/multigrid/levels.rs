//! The level hierarchy: the padded grids, their layout from the finest level down, the band
//! beside the edges, and the half-size problem of nested iteration.

use super::*;

/// One level of the hierarchy: a grid padded by one cell on every side, so that every cell of the
/// image has four neighbours to read (padding holds 0 and is never in the domain).
#[derive(Debug, Clone)]
pub(super) struct Level {
    /// Unpadded width.
    pub(super) w: usize,
    /// Unpadded height.
    pub(super) h: usize,
    /// Padded width w + 2.
    pub(super) wp: usize,
    /// Padded height h + 2.
    pub(super) hp: usize,
    /// Cells per row of one colour: ⌈wp / 2⌉.
    pub(super) hw: usize,
    /// Flags and neighbour count of each padded cell, row-major.
    pub(super) kind: Vec<u8>,
    /// Values split by colour (r + c) mod 2: cell (r, c) lives at index r·hw + c/2 of its colour,
    /// so one colour can be written in parallel while the other is read. The finest level holds
    /// (f, g), coarse levels the correction.
    pub(super) val: [Vec<Pair>; 2],
    /// Coarse levels: the restricted residual, padded row-major.
    pub(super) rhs: Vec<Pair>,
    /// Coarse levels: the restricted reaction matrix A, padded row-major.
    pub(super) reaction: Vec<Sym>,
    /// Coarse levels below the first: whether `reaction` already holds the restriction of the
    /// level above's in this cycle. The reaction matrices of the finest level change only
    /// between cycles (with the fine values), so those of level 2 and coarser are the same on
    /// every visit of one cycle and are restricted on the first.
    pub(super) reaction_current: bool,
    /// Unknown cells on this level in the current problem.
    pub(super) unknowns: usize,
    /// Whether this is a coarse level (not the image's own).
    pub(super) coarse: bool,
    /// For each colour and padded row, the half-open range of j (index in the colour's row)
    /// that holds every unknown of that colour in the row (empty: (0, 0)): the sweeps skip the
    /// rest of the row.
    pub(super) spans: [Vec<(u32, u32)>; 2],
}

impl Level {
    pub(super) fn new(w: usize, h: usize, coarse: bool) -> Level {
        let (wp, hp) = (w + 2, h + 2);
        let hw = wp.div_ceil(2);
        let cells = if coarse { wp * hp } else { 0 };
        Level {
            w,
            h,
            wp,
            hp,
            hw,
            kind: vec![0; wp * hp],
            val: [vec![[0.0; 2]; hp * hw], vec![[0.0; 2]; hp * hw]],
            rhs: vec![[0.0; 2]; cells],
            reaction: vec![[0.0; 3]; cells],
            reaction_current: false,
            unknowns: 0,
            coarse,
            spans: [vec![(0, 0); hp], vec![(0, 0); hp]],
        }
    }

    /// Finds the spans of unknowns of every colour and row from `kind`.
    pub(super) fn find_spans(&mut self) {
        let wp = self.wp;
        for r in 0..self.hp {
            for colour in 0..2 {
                let start = (r + colour) & 1;
                let row = &self.kind[r * wp..(r + 1) * wp];
                let mut unknown_j = (0..self.hw)
                    .filter(|&j| 2 * j + start < wp && row[2 * j + start] & UNKNOWN != 0);
                let first = unknown_j.next();
                self.spans[colour][r] = match (first, unknown_j.next_back().or(first)) {
                    (Some(a), Some(b)) => (a as u32, b as u32 + 1),
                    _ => (0, 0),
                };
            }
        }
    }

    /// The span of colour `colour` in padded row `r`, as a range of j.
    #[inline]
    pub(super) fn span(&self, colour: usize, r: usize) -> (usize, usize) {
        let (a, b) = self.spans[colour][r];
        (a as usize, b as usize)
    }

    /// The value at padded (r, c).
    #[inline]
    pub(super) fn value(&self, r: usize, c: usize) -> Pair {
        self.val[(r + c) & 1][r * self.hw + (c >> 1)]
    }

    /// Sets the value at padded (r, c).
    #[inline]
    pub(super) fn set_value(&mut self, r: usize, c: usize, v: Pair) {
        let hw = self.hw;
        self.val[(r + c) & 1][r * hw + (c >> 1)] = v;
    }

    /// The sum of the four neighbours of padded cell (r, c).
    #[inline]
    pub(super) fn neighbours(&self, r: usize, c: usize) -> Pair {
        neighbour_sum(&self.val[(r + c + 1) & 1], self.hw, r, c, c >> 1)
    }

    pub(super) fn parallel(&self) -> bool {
        let min = if self.coarse {
            PARALLEL_MIN_CELLS
        } else {
            FINE_PARALLEL_MIN_CELLS
        };
        self.unknowns >= min
    }
}

/// The children of coarse padded cell (r, c) on the finer level `fine`, in padded coordinates.
#[inline]
pub(super) fn children(fine: &Level, r: usize, c: usize) -> impl Iterator<Item = (usize, usize)> {
    let (r0, c0) = (2 * r - 1, 2 * c - 1);
    let (rmax, cmax) = (fine.h, fine.w);
    [(r0, c0), (r0, c0 + 1), (r0 + 1, c0), (r0 + 1, c0 + 1)]
        .into_iter()
        .filter(move |&(fr, fc)| fr <= rmax && fc <= cmax)
}

/// Lays out `coarse` from `fine`: fixed where any child is fixed, unknown where any child is
/// unknown, with neighbour counts; a coarse unknown without domain neighbours is held fixed.
pub(super) fn coarsen(fine: &Level, coarse: &mut Level) {
    coarse.kind.fill(0);
    let cwp = coarse.wp;
    for r in 1..=coarse.h {
        for c in 1..=coarse.w {
            let mut kind = 0;
            for (fr, fc) in children(fine, r, c) {
                let fk = fine.kind[fr * fine.wp + fc];
                if fk & FIXED != 0 {
                    kind = FIXED;
                } else if fk & UNKNOWN != 0 && kind == 0 {
                    kind = UNKNOWN;
                }
            }
            coarse.kind[r * cwp + c] = kind;
        }
    }
    let mut unknowns = 0;
    for r in 1..=coarse.h {
        for c in 1..=coarse.w {
            let at = r * cwp + c;
            if coarse.kind[at] & UNKNOWN == 0 {
                continue;
            }
            let k = [at - 1, at + 1, at - cwp, at + cwp]
                .iter()
                .filter(|&&q| coarse.kind[q] & IN_DOMAIN != 0)
                .count() as u8;
            if k == 0 {
                coarse.kind[at] = FIXED;
            } else {
                coarse.kind[at] |= k;
                unknowns += 1;
            }
        }
    }
    coarse.unknowns = unknowns;
    coarse.find_spans();
}

/// The problem on the half-size grid: each coarse pixel averages its children's brightness
/// (those in the domain); it is fixed, to the mean of its fixed children, where any child is
/// fixed, an unknown where any other child is, and outside otherwise.
pub(in crate::solver) fn half_size_problem(
    image: &Image,
    bc: &BoundaryConditions,
) -> (Image, BoundaryConditions) {
    let (w, h) = (image.width(), image.height());
    let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
    let mut coarse_image = Grid::new(cw, ch, 0.0);
    let mut roles = Grid::new(cw, ch, Role::Outside);
    let mut fixed = Vec::new();
    for pr in 0..ch {
        for pc in 0..cw {
            let (mut sum, mut n) = (0.0, 0usize);
            let (mut fsum, mut nfixed) = ([0.0, 0.0], 0usize);
            for r in 2 * pr..(2 * pr + 2).min(h) {
                for c in 2 * pc..(2 * pc + 2).min(w) {
                    let role = *bc.roles.get(c, r);
                    if role == Role::Outside {
                        continue;
                    }
                    sum += image.get(c, r);
                    n += 1;
                    if let (Role::Fixed, Some(v)) = (role, bc.fixed_value(c, r)) {
                        fsum = [fsum[0] + v[0], fsum[1] + v[1]];
                        nfixed += 1;
                    }
                }
            }
            if n == 0 {
                continue;
            }
            *coarse_image.get_mut(pc, pr) = sum / n as f64;
            if nfixed > 0 {
                *roles.get_mut(pc, pr) = Role::Fixed;
                let k = nfixed as f64;
                fixed.push((pr * cw + pc, [fsum[0] / k, fsum[1] / k]));
            } else {
                *roles.get_mut(pc, pr) = Role::Unknown;
            }
        }
    }
    (coarse_image, BoundaryConditions::from_parts(roles, fixed))
}

impl Multigrid {
    /// Lays out every level for `bc`: flags and neighbour counts, the fixed values and a start
    /// of (0, 0) at the unknowns of the finest level (which nested iteration may then replace).
    pub(super) fn setup(
        &mut self,
        image: &Image,
        bc: &BoundaryConditions,
        data: crate::solver::DataRange,
    ) {
        let (w, h) = (self.width, self.height);
        let fine = &mut self.levels[0];
        fine.kind.fill(0);
        for v in fine.val.iter_mut() {
            v.fill([0.0; 2]);
        }
        let roles = bc.roles.data();
        let mut fixed = bc.fixed_values().iter();
        let in_domain = |c: isize, r: isize| {
            c >= 0
                && r >= 0
                && (c as usize) < w
                && (r as usize) < h
                && roles[r as usize * w + c as usize] != Role::Outside
        };
        let mut unknowns = 0;
        for r in 0..h {
            for c in 0..w {
                let p = r * w + c;
                let at = (r + 1) * fine.wp + c + 1;
                match roles[p] {
                    Role::Outside => {}
                    Role::Fixed => {
                        fine.kind[at] = FIXED;
                        // Fixed pixels come in row-major order, as this loop visits them.
                        if let Some(&(_, value)) = fixed.next() {
                            fine.set_value(r + 1, c + 1, value);
                        }
                    }
                    Role::Unknown => {
                        let (ci, ri) = (c as isize, r as isize);
                        let k = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                            .iter()
                            .filter(|(dc, dr)| in_domain(ci + dc, ri + dr))
                            .count() as u8;
                        // An isolated pixel has nothing to be smooth with: Jacobi leaves it at
                        // (0, 0), and so does this solver, by keeping it out of the problem.
                        if k > 0 {
                            let lit = if data.carries(image.data()[p]) {
                                LIT
                            } else {
                                0
                            };
                            fine.kind[at] = UNKNOWN | lit | k;
                            unknowns += 1;
                        }
                    }
                }
            }
        }
        fine.unknowns = unknowns;
        fine.find_spans();
        self.used = 1;
        while self.used < self.levels.len().min(self.max_levels)
            && self.levels[self.used - 1].unknowns > COARSEST_UNKNOWNS
        {
            let l = self.used;
            let (upper, lower) = self.levels.split_at_mut(l);
            coarsen(&upper[l - 1], &mut lower[0]);
            if lower[0].unknowns == 0 {
                break;
            }
            self.used += 1;
        }
        // Corrections start at zero; `restrict` clears only the cells a sweep may have written
        // (see there), so the ones a previous problem's unknowns left are cleared here.
        for level in &mut self.levels[1..self.used] {
            for v in level.val.iter_mut() {
                v.fill([0.0; 2]);
            }
        }
    }

    /// Finds the finest level's band for local relaxation: the unknowns within `BAND_WIDTH`
    /// steps (through unknowns) of a cell that is not one (the domain's edge), or of the edge
    /// of the data term (an unknown that carries data beside one that does not: the edge of an
    /// attached shadow, the terminator, or of a clipped highlight). There the coarse levels'
    /// linear model is poorest: R and ∇R vanish on one side.
    pub(super) fn find_band(&mut self) {
        let level = &mut self.levels[0];
        let wp = level.wp;
        let mut band = [Vec::new(), Vec::new()];
        let mut frontier = Vec::new();
        for r in 1..level.hp - 1 {
            let (lo, hi) = unknown_columns(&level.spans, r);
            for c in lo..hi {
                let at = r * wp + c;
                if level.kind[at] & UNKNOWN == 0 {
                    continue;
                }
                let edge = [at - 1, at + 1, at - wp, at + wp].iter().any(|&n| {
                    level.kind[n] & UNKNOWN == 0 || (level.kind[n] ^ level.kind[at]) & LIT != 0
                });
                if edge {
                    level.kind[at] |= BAND;
                    frontier.push(at);
                }
            }
        }
        let mut next = Vec::new();
        for step in 0..BAND_WIDTH {
            for &at in &frontier {
                band[(at / wp + at % wp) & 1].push(at as u32);
                if step + 1 < BAND_WIDTH {
                    for n in [at - 1, at + 1, at - wp, at + wp] {
                        if level.kind[n] & (UNKNOWN | BAND) == UNKNOWN {
                            level.kind[n] |= BAND;
                            next.push(n);
                        }
                    }
                }
            }
            std::mem::swap(&mut frontier, &mut next);
            next.clear();
        }
        for list in &band {
            for &at in list {
                level.kind[at as usize] &= !BAND;
            }
        }
        self.band = band;
    }
}
