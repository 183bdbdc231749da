use super::super::super::tests::picture;
use super::super::{pull_weights, AngleScale};
use super::model::HELD;
use super::*;
use crate::boundary::{boundary_conditions, Boundary, Role};
use crate::grid::Mask;
use crate::light::Light;
use crate::solver::Solver;
use crate::surface::sphere;

/// A 20² sphere's problem (occluding boundary, light from tilt 30°, slant 40°), and a point
/// that is not its minimum: the truth's (f, g) bent by a smooth field, and a depth of its
/// own.
struct Case {
    solver: Solver,
    pull: Vec<f64>,
    angles: Vec<f64>,
    map: crate::reflectance::Lambertian,
    point: Vec<f64>,
}

fn case() -> Case {
    case_with(20, &Boundary::Occluding, (30.0, 40.0))
}

/// A `size`² sphere (radius 0.425 of the size) lit from (tilt, slant), solved with
/// `boundary`, from a perturbed start.
fn case_with(size: usize, boundary: &Boundary, (tilt, slant): (f64, f64)) -> Case {
    let surface = sphere(size, size, 0.425 * size as f64).unwrap();
    let (image, map) = picture(&surface, Light::from_tilt_slant(tilt, slant).unwrap());
    let bc = boundary_conditions(&surface.mask, boundary).unwrap();
    let mut solver = Solver::new(size, size).unwrap();
    let n = solver.build(crate::solver::Posed::new(&image, &bc, &map), 1.0);
    let domain: Mask = bc.roles.map(|r| *r == Role::Unknown);
    let pull = pull_weights(&domain, &solver.pixels);
    let scale = AngleScale::of(&map);
    let angles = solver.nodes[..n]
        .iter()
        .map(|node| scale.angle(node.intensity))
        .collect();
    let mut point = vec![0.0; 3 * n];
    for (j, &p) in solver.pixels.iter().enumerate() {
        let (c, r) = ((p as usize % size) as f64, (p as usize / size) as f64);
        let normal = surface.normals.data()[p as usize];
        let (f, g) = crate::gradient_space::fg_from_normal(&normal);
        point[j] = f + 0.1 * (0.3 * c).sin();
        point[n + j] = g - 0.08 * (0.2 * r).cos();
        point[2 * n + j] = 0.05 * c * r - 0.3 * c;
    }
    Case {
        solver,
        pull,
        angles,
        map,
        point,
    }
}

impl Case {
    fn energy(&self) -> Energy<'_> {
        let s = &self.solver;
        let n = self.angles.len();
        Energy::new(
            &s.nodes[..n],
            &s.pixels,
            &s.slot,
            (s.width, s.height),
            (&s.cur_f, &s.cur_g),
            &self.angles,
            &self.pull,
            &self.map,
        )
    }
}

/// The gradient is E's: central differences of E along 60 coordinates of f, g and z agree
/// with it to 1e-6 relative.
#[test]
fn gradient_is_the_energys() {
    let case = case();
    let energy = case.energy();
    let x = case.point.clone();
    let mut grad = vec![0.0; x.len()];
    let mut work = vec![0.0; x.len()];
    energy.value_and_gradient(&x, &mut grad, &mut work);
    let mut scratch = vec![0.0; x.len()];
    let (mut y, h) = (x.clone(), 1e-6);
    for k in 0..60 {
        let i = (k * 7919) % x.len();
        y[i] = x[i] + h;
        let up = energy.value_and_gradient(&y, &mut scratch, &mut work);
        y[i] = x[i] - h;
        let down = energy.value_and_gradient(&y, &mut scratch, &mut work);
        y[i] = x[i];
        let numeric = (up - down) / (2.0 * h);
        assert!(
            (numeric - grad[i]).abs() <= 1e-6 * grad[i].abs().max(1.0),
            "coordinate {i}: {numeric} against {}",
            grad[i]
        );
    }
}

/// At a point where every residual is 0 the Gauss–Newton matrix is E's Hessian: its
/// product with a vector agrees with central differences of the gradient to 1e-5
/// relative, and it is symmetric.
#[test]
fn gauss_newton_matrix_is_the_hessian_where_the_residuals_vanish() {
    let mut case = case();
    let n = case.angles.len();
    // Orientations from the depth, and the brightness they give.
    let probe = case.energy();
    let mut x = case.point.clone();
    for j in 0..n {
        if case.pull[j] > 0.0 {
            let z = &case.point[2 * n..];
            let ((f, g), _) = probe.target(j, z);
            x[j] = f;
            x[n + j] = g;
        }
    }
    let scale = probe.scale;
    let angles: Vec<f64> = (0..n)
        .map(|j| scale.angle(case.map.fg(x[j], x[n + j]).value))
        .collect();
    drop(probe);
    case.angles = angles;
    let energy = case.energy();
    let gn = energy.linearise(&x, false);
    let mut work = vec![0.0; 2 * n];
    let v: Vec<f64> = (0..3 * n)
        .map(|i| ((i * 37) % 11) as f64 / 11.0 - 0.4)
        .collect();
    let u: Vec<f64> = (0..3 * n)
        .map(|i| ((i * 53) % 7) as f64 / 7.0 - 0.5)
        .collect();
    let (mut hv, mut hu) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    gn.apply(0.0, &v, &mut hv, &mut work);
    gn.apply(0.0, &u, &mut hu, &mut work);
    let (uhv, vhu) = (dot(&u, &hv), dot(&v, &hu));
    assert!(
        (uhv - vhu).abs() <= 1e-12 * uhv.abs().max(1.0),
        "{uhv} against {vhu}"
    );
    let h = 1e-6;
    let (mut up, mut down) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    let shifted =
        |sign: f64| -> Vec<f64> { x.iter().zip(&v).map(|(x, v)| x + sign * h * v).collect() };
    energy.value_and_gradient(&shifted(1.0), &mut up, &mut work);
    energy.value_and_gradient(&shifted(-1.0), &mut down, &mut work);
    let largest = hv.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for i in 0..3 * n {
        let numeric = (up[i] - down[i]) / (2.0 * h);
        assert!(
            (numeric - hv[i]).abs() <= 1e-5 * largest,
            "entry {i}: {numeric} against {}",
            hv[i]
        );
    }
}

/// The sparse matrix the preconditioner coarsens is the model's: its product with a vector
/// is `apply`'s, up to the diagonal floor.
#[test]
fn the_sparse_matrix_is_the_models() {
    let case = case();
    let energy = case.energy();
    let n = energy.len();
    let model = energy.linearise(&case.point, false);
    let v: Vec<f64> = (0..3 * n)
        .map(|i| ((i * 37) % 11) as f64 / 11.0 - 0.4)
        .collect();
    for nu in [0.0, 0.3] {
        let (mut want, mut got) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        let mut work = vec![0.0; 2 * n];
        model.apply(nu, &v, &mut want, &mut work);
        model.matrix(nu).mul_vec(&v, &mut got);
        for i in 0..3 * n {
            // The floor: 1e-6 on every diagonal entry, and z's damping from its floored
            // diagonal.
            let slack = 2.0 * DIAGONAL_FLOOR * (1.0 + nu) * v[i].abs() + 1e-12;
            assert!(
                (want[i] - got[i]).abs() <= slack,
                "ν = {nu}, entry {i}: {} against {}",
                got[i],
                want[i]
            );
        }
    }
}

/// A pixel's block keeps the data term's Hessian where the pixel's smoothness and pull
/// hold it (no eigenvalue below [`HELD`] of their diagonal); elsewhere only the eigenvalue
/// below that floor changes, to the floor, along the same eigenvector.
#[test]
fn a_block_keeps_the_curvature_its_diagonal_holds() {
    // The eigenvalues (small, large) of [a, b, c] and the small one's unit eigenvector.
    let eigen = |[a, b, c]: [f64; 3]| {
        let (mean, radius) = (0.5 * (a + c), (0.25 * (a - c) * (a - c) + b * b).sqrt());
        let angle = 0.5 * (2.0 * b).atan2(a - c) + std::f64::consts::FRAC_PI_2;
        (mean - radius, mean + radius, (angle.cos(), angle.sin()))
    };
    let cases = [
        // Positive definite already.
        ([1.0, 0.3, 2.0], 4.5),
        // A ridge pixel of DiLiGenT pot2 (λ = 1): negative curvature −1.51, held by 4.5.
        ([-1.3036, -0.9289, 2.6370], 4.5),
        // Negative curvature beyond what the diagonal holds.
        ([-4.0, 1.0, 0.5], 4.5),
        ([-3.0, 2.5, -1.0], 2.0),
        // Both eigenvalues below the floor.
        ([-10.0, 0.0, -10.0], 2.0),
    ];
    for (data, diagonal) in cases {
        let block = held(data, diagonal);
        let whole = |m: [f64; 3]| [diagonal + m[0], m[1], diagonal + m[2]];
        let (low, high, soft) = eigen(whole(data));
        let (kept_low, kept_high, _) = eigen(whole(block));
        let floor = HELD * diagonal;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
        if low >= floor {
            assert!(
                data.iter().zip(&block).all(|(&a, &b)| close(a, b)),
                "{data:?} became {block:?}"
            );
            continue;
        }
        assert!(
            close(kept_low, floor),
            "{data:?}: {kept_low} against {floor}"
        );
        assert!(close(kept_high, high.max(floor)), "{data:?}: {kept_high}");
        // The change is (floor − low)·vvᵀ for the soft eigenvector v where the stiff
        // eigenvalue is above the floor.
        if high > floor {
            let rise = floor - low;
            let (x, y) = soft;
            let want = [rise * x * x, rise * x * y, rise * y * y];
            for i in 0..3 {
                assert!(close(block[i] - data[i], want[i]), "{data:?}: entry {i}");
            }
        }
    }
}

/// Every step lowers E, and the steps reach a minimum: once they stop changing (f, g) by
/// 1e-10, the gradient is below 1e-6 of where it started.
#[test]
fn steps_lower_the_energy_to_a_minimum() {
    let case = case();
    let energy = case.energy();
    let mut minimiser = Minimiser::new(&energy, case.point.clone());
    let norm = |v: &[f64]| dot(v, v).sqrt();
    let start = norm(&minimiser.grad);
    let mut last = minimiser.energy();
    let mut steps = 0;
    loop {
        let change = minimiser.step(&energy);
        steps += 1;
        assert!(minimiser.energy() < last || change == 0.0, "step {steps}");
        last = minimiser.energy();
        if change < 1e-10 || steps == 500 {
            break;
        }
    }
    let end = norm(&minimiser.grad);
    assert!(end < 1e-6 * start, "{end} of {start} after {steps} steps");
}

/// Steps from the case's start until a step changes nothing by 1e-9 (or 2000 steps), with
/// the acceleration over `depth` steps; returns the steps, E and |∇E| at the end.
fn minimise(case: &Case, depth: usize) -> (usize, f64, f64) {
    let energy = case.energy();
    let mut minimiser = Minimiser::with_acceleration(&energy, case.point.clone(), depth);
    let mut last = minimiser.energy();
    let mut steps = 0;
    loop {
        let change = minimiser.step(&energy);
        steps += 1;
        // E never rises, but for rounding where the relaxation re-sums it.
        let e = minimiser.energy();
        assert!(
            e <= last * (1.0 + 1e-14),
            "depth {depth}, step {steps}: {last} → {e}"
        );
        last = minimiser.energy();
        if change < 1e-9 || steps == 2000 {
            break;
        }
    }
    (steps, last, dot(&minimiser.grad, &minimiser.grad).sqrt())
}

/// The acceleration keeps E falling at every step and ends at the plain steps' minimum,
/// in fewer steps where they creep: on the sphere under an oblique light with the occluding
/// boundary, and under a light 5° from the view with the free boundary (a shallow valley of
/// E, as on ball photograph 052, where the plain steps shrink slowly).
#[test]
fn acceleration_reaches_the_same_minimum_in_fewer_steps() {
    for (size, boundary, light) in [
        (20, Boundary::Occluding, (30.0, 40.0)),
        (48, Boundary::Free, (30.0, 5.0)),
        (48, Boundary::Free, (30.0, 2.0)),
        (48, Boundary::Occluding, (30.0, 60.0)),
    ] {
        let case = case_with(size, &boundary, light);
        let plain = minimise(&case, 0);
        let fast = minimise(&case, LM_ANDERSON_DEPTH);
        eprintln!("{boundary:?}: plain {plain:?}, accelerated {fast:?}");
        assert!(plain.2 < 1e-6 && fast.2 < 1e-6, "{plain:?} {fast:?}");
        assert!(
            (plain.1 - fast.1).abs() < 1e-9 * plain.1,
            "{plain:?} {fast:?}"
        );
        assert!(fast.0 <= plain.0, "{plain:?} {fast:?}");
    }
}

/// Pixels of the case: some with a data term and a pull, and every one without either
/// (the sphere's shadow, the pixels the depth cannot tilt; there is at least one).
fn kinds_of_pixel(energy: &Energy) -> Vec<usize> {
    let n = energy.len();
    let mut chosen = Vec::new();
    for want in [(true, true), (true, false), (false, true), (false, false)] {
        let pick =
            (0..n).filter(|&j| (energy.nodes[j].data_weight != 0.0, energy.pull[j] > 0.0) == want);
        chosen.extend(
            pick.step_by(if want == (true, true) { 7 } else { 1 })
                .take(6),
        );
    }
    assert!(chosen.len() > 6, "{chosen:?}");
    chosen
}

/// A pixel's part of E is E along its orientation: moving the pixel changes E by what its
/// part changes by (to 1e-10), its gradient is E's at the pixel, and its Hessian agrees
/// with central differences of that gradient to 1e-5.
#[test]
fn a_pixels_part_is_e_along_its_orientation() {
    let case = case();
    let energy = case.energy();
    let n = energy.len();
    let x = case.point.clone();
    let z = &x[2 * n..];
    let (mut grad, mut work) = (vec![0.0; 3 * n], vec![0.0; 2 * n]);
    let e = energy.value_and_gradient(&x, &mut grad, &mut work);
    let mut scratch = vec![0.0; 3 * n];
    for j in kinds_of_pixel(&energy) {
        let target = (energy.pull[j] > 0.0).then(|| energy.target(j, z).0);
        let at = (x[j], x[n + j]);
        let (part, gradient, hessian) = energy.local(&x, j, target, at);
        let close = |a: f64, b: f64, tol: f64| (a - b).abs() <= tol * a.abs().max(1.0);
        assert!(close(gradient[0], grad[j], 1e-10), "pixel {j}: ∂f");
        assert!(close(gradient[1], grad[n + j], 1e-10), "pixel {j}: ∂g");
        let mut y = x.clone();
        y[j] += 0.03;
        y[n + j] -= 0.02;
        let moved = energy.local(&x, j, target, (y[j], y[n + j])).0;
        let e_moved = energy.value_and_gradient(&y, &mut scratch, &mut work);
        assert!(close(e_moved - e, moved - part, 1e-10), "pixel {j}: E");
        let h = 1e-6;
        let d = |df: f64, dg: f64| energy.local(&x, j, target, (at.0 + df, at.1 + dg)).1;
        let (fp, fm, gp, gm) = (d(h, 0.0), d(-h, 0.0), d(0.0, h), d(0.0, -h));
        let numeric = [
            (fp[0] - fm[0]) / (2.0 * h),
            (fp[1] - fm[1]) / (2.0 * h),
            (gp[1] - gm[1]) / (2.0 * h),
        ];
        for i in 0..3 {
            assert!(
                close(hessian[i], numeric[i], 1e-5),
                "pixel {j}: entry {i}, {} against {}",
                hessian[i],
                numeric[i]
            );
        }
    }
}

/// Relaxing a pixel never raises E and leaves it at a least of E along its orientation:
/// E's gradient at the pixel is below 1e-6 of where it was, and no other unknown moves.
#[test]
fn relaxing_a_pixel_finds_the_least_along_its_orientation() {
    let case = case();
    let energy = case.energy();
    let n = energy.len();
    let (mut grad, mut work) = (vec![0.0; 3 * n], vec![0.0; 2 * n]);
    for j in kinds_of_pixel(&energy) {
        let x = case.point.clone();
        let e = energy.value_and_gradient(&x, &mut grad, &mut work);
        let before = grad[j].hypot(grad[n + j]);
        let mut y = x.clone();
        energy.relax(&mut y, j);
        let relaxed = energy.value_and_gradient(&y, &mut grad, &mut work);
        assert!(relaxed <= e, "pixel {j}: E {e} → {relaxed}");
        let after = grad[j].hypot(grad[n + j]);
        assert!(
            after <= 1e-6 * before.max(1.0),
            "pixel {j}: gradient {before} → {after}"
        );
        let others = (0..3 * n).filter(|&i| i != j && i != n + j);
        assert!(others.into_iter().all(|i| x[i] == y[i]), "pixel {j}");
    }
}
