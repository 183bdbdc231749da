//! The solve: nested iteration from the coarse solution, the cycles and their stopping rule.

use super::*;

impl Multigrid {
    /// Nested iteration: solves the same problem on the half-size grid (recursively, so from
    /// the coarsest grid up) and starts the finest unknowns from that solution, interpolated
    /// bilinearly (coarse neighbours that are not unknowns lend the parent's value). Where the
    /// shading has an attached shadow or the light is oblique, a start from (0, 0) leaves a front
    /// (the terminator's neighbourhood, where ∇R vanishes and the linear coarse corrections see
    /// nothing) that the fine smoothing moves about one pixel per cycle; on the coarse grid it
    /// moves 2, 4, 8… pixels per cycle. The fixed point is the fine
    /// problem's either way: only the start differs. λ is kept on the coarse grid (the
    /// continuum scaling 4λ would break the sweep's stability bound λ·R_f² < 2); a coarse
    /// solve that diverges is ignored.
    pub(super) fn start_from_coarse_solution(&mut self, posed: Posed<'_>, options: &SolveOptions) {
        let (image, bc, reflectance) = (posed.image, posed.bc, posed.reflectance);
        if self.levels[0].unknowns < NESTED_MIN_UNKNOWNS {
            return;
        }
        let (w, h) = (self.width, self.height);
        let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
        let (coarse_image, coarse_bc) = half_size_problem(image, bc);
        // Made for this start and dropped before the fine cycles: kept, it would add a third of
        // the hierarchy's memory at the end of the solve, where a large solve's memory peaks,
        // to save an allocation that costs far less than the solve.
        let mut coarse = Multigrid::new(cw, ch);
        coarse.schedule = self.schedule;
        let coarse_options = SolveOptions {
            tol: options.tol.max(NESTED_TOL),
            max_iter: NESTED_MAX_CYCLES,
            ..*options
        };
        let (cf, cg, stats) = coarse.solve(
            Posed::new(&coarse_image, &coarse_bc, reflectance),
            &coarse_options,
            &mut |_| {},
        );
        let coarse_roles = coarse_bc.roles;
        drop((coarse, coarse_image));
        if stats.diverged {
            return;
        }
        self.work += 0.25 * stats.work;
        let fine = &mut self.levels[0];
        let unknown = |pc: isize, pr: isize| {
            pc >= 0
                && pr >= 0
                && (pc as usize) < cw
                && (pr as usize) < ch
                && *coarse_roles.get(pc as usize, pr as usize) == Role::Unknown
        };
        for r in 0..h {
            for c in 0..w {
                if fine.kind[(r + 1) * fine.wp + c + 1] & UNKNOWN != 0 {
                    let (pc, pr) = (c / 2, r / 2);
                    let parent = [*cf.get(pc, pr), *cg.get(pc, pr)];
                    let (dc, dr) = (
                        if c % 2 == 0 { -1 } else { 1 },
                        if r % 2 == 0 { -1 } else { 1 },
                    );
                    let (ic, ir) = (pc as isize, pr as isize);
                    let at = |oc: isize, or: isize| {
                        if unknown(ic + oc, ir + or) {
                            let (x, y) = ((ic + oc) as usize, (ir + or) as usize);
                            [*cf.get(x, y), *cg.get(x, y)]
                        } else {
                            parent
                        }
                    };
                    let (a, b, d) = (at(dc, 0), at(0, dr), at(dc, dr));
                    let v = [
                        (9.0 * parent[0] + 3.0 * a[0] + 3.0 * b[0] + d[0]) / 16.0,
                        (9.0 * parent[1] + 3.0 * a[1] + 3.0 * b[1] + d[1]) / 16.0,
                    ];
                    fine.set_value(r + 1, c + 1, v);
                }
            }
        }
    }

    /// Solves the problem given by `image`, `bc` and `reflectance` with `options` (checked by
    /// the caller); `progress` is called after every cycle.
    pub(crate) fn solve(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        progress: &mut dyn FnMut(&Progress),
    ) -> (Image, Image, MultigridStats) {
        let (image, bc, reflectance) = (posed.image, posed.bc, posed.reflectance);
        let lambda = options.lambda;
        let ctx = Context::new(image, reflectance, lambda);
        self.work = 0.0;
        self.setup(
            image,
            bc,
            crate::solver::DataRange::new(reflectance, options.saturation),
        );
        self.find_band();
        if self.nested {
            self.start_from_coarse_solution(posed, options);
        }
        let mut stats = MultigridStats {
            cycles: 0,
            residual: 0.0,
            converged: self.levels[0].unknowns == 0,
            diverged: false,
            levels: self.used,
            work: 0.0,
        };
        let mut best = f64::INFINITY;
        let mut damping: f64 = 1.0;
        let mut restores = self.restores;
        // Globalisation hook (see globalize.rs): the cycles stop once they stall.
        let mut watch = crate::solver::globalize::StallWatch::new(lambda);
        // The last two residuals, for `predicts_convergence`.
        let mut history = [f64::INFINITY; 2];
        while !stats.converged {
            for _ in 0..self.schedule.pre_sweeps {
                self.smooth(0, &ctx);
            }
            let residual = if self.used > 1 && predicts_convergence(history, options.tol) {
                // Expected to be the last cycle: the test alone first, the restriction (the
                // map's Hessian, the reaction matrices) only if it fails. The same residual
                // either way (the same red targets, and a maximum is exact).
                let test = self.red_residual(&ctx);
                if test < options.tol {
                    test
                } else {
                    self.restrict(0, &ctx)
                }
            } else {
                self.restrict(0, &ctx)
            };
            history = [history[1], residual];
            stats.residual = residual;
            stats.cycles += 1;
            progress(&Progress {
                iteration: stats.cycles,
                max_iter: options.max_iter,
                last_update: residual,
                energy: None,
                level: 0,
                seconds_left: None,
            });
            if residual.is_nan() || residual > DIVERGENCE_UPDATE {
                stats.diverged = true;
                break;
            }
            if residual < options.tol {
                stats.converged = true;
                break;
            }
            if stats.cycles >= options.max_iter || crate::cancel::requested() {
                break;
            }
            // Globalisation hook (see globalize.rs): a stalled solve is finished there.
            if watch.stalled(residual) {
                break;
            }
            // A residual that grows means the linear coarse model overshoots (it leaves out the
            // (I − R)·∇²R part of the operator, which matters where the assumed light cannot
            // match the picture): the coarse correction is halved at each rise. A rise can
            // also be a passing one (the first fine cycle after the nested start, a band
            // sweep's kick), so the first time the residual then falls below half the best
            // before it, the correction is doubled back (`RESTORES` times in a solve).
            if residual > RISE * best {
                damping *= 0.5;
            } else if residual * RISE < best && damping < 1.0 && restores > 0 {
                damping = (damping * 2.0).min(1.0);
                restores -= 1;
            }
            best = best.min(residual);
            if self.used > 1 && damping > MIN_DAMPING {
                self.cycle(1, &ctx);
                self.prolongate(0, damping);
            }
            for _ in 0..self.schedule.post_sweeps {
                self.smooth(0, &ctx);
            }
            for _ in 0..self.band_sweeps {
                self.smooth_band(&ctx);
            }
        }
        stats.work = self.work;
        let (f, g) = self.fine_values();
        (f, g, stats)
    }

    /// One cycle of `self.schedule` (a W-cycle: each coarser level visited twice) for the
    /// correction on level `l` ≥ 1, from zero; the coarsest level is relaxed until it settles.
    pub(super) fn cycle(&mut self, l: usize, ctx: &Context) {
        if l + 1 == self.used {
            let mut first = 0.0;
            for sweep in 0..COARSEST_SWEEPS {
                let change = self.smooth_tracked(l, ctx);
                if sweep == 0 {
                    first = change;
                }
                if change.is_nan() || change <= COARSEST_REDUCTION * first {
                    break;
                }
            }
            return;
        }
        // Every visit starts the next level's correction from zero: `restrict` sets it.
        for _ in 0..self.schedule.coarse_visits {
            for _ in 0..self.schedule.pre_sweeps {
                self.smooth(l, ctx);
            }
            self.restrict(l, ctx);
            self.cycle(l + 1, ctx);
            self.prolongate(l, 1.0);
            for _ in 0..self.schedule.post_sweeps {
                self.smooth(l, ctx);
            }
        }
    }

    /// The finest level's f and g as image grids (0 outside the domain).
    pub(super) fn fine_values(&self) -> (Image, Image) {
        let (w, h) = (self.width, self.height);
        let fine = &self.levels[0];
        let (mut f, mut g) = (Grid::new(w, h, 0.0), Grid::new(w, h, 0.0));
        // One pass, each padded row's two colours cut once: cell c of the row is cell c/2 of
        // colour (r + c) mod 2.
        let rows = f
            .data_mut()
            .chunks_mut(w.max(1))
            .zip(g.data_mut().chunks_mut(w.max(1)));
        for (r, (f_row, g_row)) in (1..=h).zip(rows) {
            let colours = [
                &fine.val[r & 1][r * fine.hw..(r + 1) * fine.hw],
                &fine.val[(r + 1) & 1][r * fine.hw..(r + 1) * fine.hw],
            ];
            for (i, (f, g)) in f_row.iter_mut().zip(g_row.iter_mut()).enumerate() {
                let c = i + 1;
                let v = colours[c & 1][c >> 1];
                (*f, *g) = (v[0], v[1]);
            }
        }
        (f, g)
    }
}

/// Whether the cycle after residuals `history` (the one before last, the last) is expected to
/// reach `tol`: the last residual times the last reduction factor is below it.
pub(super) fn predicts_convergence(history: [f64; 2], tol: f64) -> bool {
    let [before, last] = history;
    before.is_finite() && before > 0.0 && last * (last / before) < tol
}
