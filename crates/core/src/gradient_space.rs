//! Gradient space (p, q) and stereographic space (f, g), and the unit normals they describe.
//!
//! p = −∂z/∂x, q = −∂z/∂y, so n = (p, q, 1)/√(1+p²+q²). The stereographic coordinates project
//! the unit normal from the sphere's south pole (0, 0, −1) onto the plane z = 1:
//! f = 2n_x/(1+n_z), g = 2n_y/(1+n_z). Every normal of the visible hemisphere lands in the disc
//! f² + g² ≤ 4, the occluding limb on its rim: (1,0,0) ↦ (2,0) and (0,1,0) ↦ (0,2). p and q,
//! by contrast, are infinite there, which is why iterative solvers work in f–g.

use nalgebra::Vector3;

/// A unit normal.
pub type Normal = Vector3<f64>;

/// The radius of the stereographic disc holding every visible normal.
pub const FG_RADIUS: f64 = 2.0;

/// The unit normal of slopes (p, q): (p, q, 1)/√(1+p²+q²).
pub fn normal_from_pq(p: f64, q: f64) -> Normal {
    Vector3::new(p, q, 1.0) / (1.0 + p * p + q * q).sqrt()
}

/// The slopes (p, q) = (n_x/n_z, n_y/n_z) of a normal; `None` where n_z ≤ 0 (at or beyond the
/// occluding limb the slopes are infinite).
pub fn pq_from_normal(n: &Normal) -> Option<(f64, f64)> {
    (n.z > 0.0).then(|| (n.x / n.z, n.y / n.z))
}

/// The stereographic coordinates of a unit normal: (2n_x, 2n_y)/(1+n_z).
///
/// Finite for every normal but the one pointing straight away from the viewer (n_z = −1),
/// which maps to infinity; that normal is not visible, so it is clamped to the rim.
pub fn fg_from_normal(n: &Normal) -> (f64, f64) {
    let d = 1.0 + n.z;
    if d <= 1e-12 {
        let r = n.x.hypot(n.y);
        if r < 1e-300 {
            return (FG_RADIUS, 0.0);
        }
        // Beyond the limb: put it on the rim in its image-plane direction.
        return (FG_RADIUS * n.x / r, FG_RADIUS * n.y / r);
    }
    (2.0 * n.x / d, 2.0 * n.y / d)
}

/// The unit normal of stereographic coordinates (f, g): (4f, 4g, 4−f²−g²)/(4+f²+g²).
pub fn normal_from_fg(f: f64, g: f64) -> Normal {
    let r2 = f * f + g * g;
    Vector3::new(4.0 * f, 4.0 * g, 4.0 - r2) / (4.0 + r2)
}

/// (f, g) of slopes (p, q): 2(p, q)/(1+√(1+p²+q²)).
pub fn fg_from_pq(p: f64, q: f64) -> (f64, f64) {
    let d = 1.0 + (1.0 + p * p + q * q).sqrt();
    (2.0 * p / d, 2.0 * q / d)
}

/// The derivatives of [`fg_from_pq`], analytic: [∂f/∂p, ∂f/∂q, ∂g/∂p, ∂g/∂q].
///
/// ```
/// use shadelab_core::gradient_space::{fg_from_pq, fg_pq_jacobian};
/// let (p, q, h) = (0.7, -1.3, 1e-6);
/// let [fp, fq, gp, gq] = fg_pq_jacobian(p, q);
/// let (f1, g1) = fg_from_pq(p + h, q);
/// let (f0, g0) = fg_from_pq(p - h, q);
/// assert!((fp - (f1 - f0) / (2.0 * h)).abs() < 1e-8 && (gp - (g1 - g0) / (2.0 * h)).abs() < 1e-8);
/// let (f1, g1) = fg_from_pq(p, q + h);
/// let (f0, g0) = fg_from_pq(p, q - h);
/// assert!((fq - (f1 - f0) / (2.0 * h)).abs() < 1e-8 && (gq - (g1 - g0) / (2.0 * h)).abs() < 1e-8);
/// ```
pub fn fg_pq_jacobian(p: f64, q: f64) -> [f64; 4] {
    // f = 2p/d, g = 2q/d with d = 1 + s, s = √(1+p²+q²): ∂d/∂p = p/s.
    let s = (1.0 + p * p + q * q).sqrt();
    let d = 1.0 + s;
    let d2s = d * d * s;
    let fq = -2.0 * p * q / d2s;
    [
        2.0 / d - 2.0 * p * p / d2s,
        fq,
        fq,
        2.0 / d - 2.0 * q * q / d2s,
    ]
}

/// (p, q) of stereographic coordinates; `None` on or outside the rim f² + g² ≥ 4.
pub fn pq_from_fg(f: f64, g: f64) -> Option<(f64, f64)> {
    let r2 = f * f + g * g;
    (r2 < 4.0).then(|| {
        let k = 4.0 / (4.0 - r2);
        (k * f, k * g)
    })
}

/// The derivatives ∂n/∂f and ∂n/∂g of [`normal_from_fg`], analytic.
pub fn normal_fg_jacobian(f: f64, g: f64) -> (Vector3<f64>, Vector3<f64>) {
    // n = u / d with u = (4f, 4g, 4 − r²), d = 4 + r².
    let r2 = f * f + g * g;
    let d = 4.0 + r2;
    let u = Vector3::new(4.0 * f, 4.0 * g, 4.0 - r2);
    let du_df = Vector3::new(4.0, 0.0, -2.0 * f);
    let du_dg = Vector3::new(0.0, 4.0, -2.0 * g);
    let dn_df = du_df / d - u * (2.0 * f) / (d * d);
    let dn_dg = du_dg / d - u * (2.0 * g) / (d * d);
    (dn_df, dn_dg)
}

/// The derivatives ∂n/∂p and ∂n/∂q of [`normal_from_pq`], analytic.
pub fn normal_pq_jacobian(p: f64, q: f64) -> (Vector3<f64>, Vector3<f64>) {
    let s2 = 1.0 + p * p + q * q;
    let s = s2.sqrt();
    let s3 = s2 * s;
    let dn_dp = Vector3::new(1.0 / s - p * p / s3, -p * q / s3, -p / s3);
    let dn_dq = Vector3::new(-p * q / s3, 1.0 / s - q * q / s3, -q / s3);
    (dn_dp, dn_dq)
}

/// Angle between two normals in degrees (robust near 0 and 180).
pub fn angle_deg(a: &Normal, b: &Normal) -> f64 {
    a.cross(b).norm().atan2(a.dot(b)).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn limb_points() {
        let (f, g) = fg_from_normal(&Vector3::new(1.0, 0.0, 0.0));
        assert!((f - 2.0).abs() < 1e-15 && g.abs() < 1e-15);
        let (f, g) = fg_from_normal(&Vector3::new(0.0, 1.0, 0.0));
        assert!(f.abs() < 1e-15 && (g - 2.0).abs() < 1e-15);
        assert_eq!(fg_from_normal(&Vector3::new(0.0, 0.0, 1.0)), (0.0, 0.0));
        assert!(pq_from_normal(&Vector3::new(1.0, 0.0, 0.0)).is_none());
    }

    fn unit_visible() -> impl Strategy<Value = Normal> {
        (
            0.0..std::f64::consts::TAU,
            0.0..=std::f64::consts::FRAC_PI_2,
        )
            .prop_map(|(az, el)| {
                Vector3::new(el.sin() * az.cos(), el.sin() * az.sin(), el.cos().max(0.0))
            })
    }

    proptest! {
        #[test]
        fn fg_round_trip(n in unit_visible()) {
            let (f, g) = fg_from_normal(&n);
            prop_assert!(f * f + g * g <= 4.0 + 1e-12);
            prop_assert!((normal_from_fg(f, g) - n).norm() < 1e-12);
        }

        #[test]
        fn pq_round_trip(p in -50.0..50.0f64, q in -50.0..50.0f64) {
            let n = normal_from_pq(p, q);
            prop_assert!((n.norm() - 1.0).abs() < 1e-12);
            let (p2, q2) = pq_from_normal(&n).unwrap();
            prop_assert!((p2 - p).abs() < 1e-9 * (1.0 + p.abs()));
            prop_assert!((q2 - q).abs() < 1e-9 * (1.0 + q.abs()));
            let (f, g) = fg_from_pq(p, q);
            prop_assert!(f * f + g * g < 4.0);
            let (f2, g2) = fg_from_normal(&n);
            prop_assert!((f - f2).abs() < 1e-12 && (g - g2).abs() < 1e-12);
            let (p3, q3) = pq_from_fg(f, g).unwrap();
            prop_assert!((p3 - p).abs() < 1e-8 * (1.0 + p.abs() * p.abs()));
            prop_assert!((q3 - q).abs() < 1e-8 * (1.0 + q.abs() * q.abs()));
        }

        #[test]
        fn grazing_does_not_overflow(az in 0.0..std::f64::consts::TAU, eps in 0.0..1e-9f64) {
            let n = Vector3::new(az.cos(), az.sin(), eps).normalize();
            let (f, g) = fg_from_normal(&n);
            prop_assert!(f.is_finite() && g.is_finite());
            prop_assert!(f * f + g * g <= 4.0 + 1e-12);
        }

        #[test]
        fn jacobians_match_finite_differences(f in -1.9..1.9f64, g in -1.9..1.9f64) {
            let h = 1e-6;
            let (jf, jg) = normal_fg_jacobian(f, g);
            let nf = (normal_from_fg(f + h, g) - normal_from_fg(f - h, g)) / (2.0 * h);
            let ng = (normal_from_fg(f, g + h) - normal_from_fg(f, g - h)) / (2.0 * h);
            prop_assert!((jf - nf).norm() < 1e-7 && (jg - ng).norm() < 1e-7);
            let (p, q) = (f * 2.0, g * 2.0);
            let (jp, jq) = normal_pq_jacobian(p, q);
            let np = (normal_from_pq(p + h, q) - normal_from_pq(p - h, q)) / (2.0 * h);
            let nq = (normal_from_pq(p, q + h) - normal_from_pq(p, q - h)) / (2.0 * h);
            prop_assert!((jp - np).norm() < 1e-7 && (jq - nq).norm() < 1e-7);
        }
    }
}
