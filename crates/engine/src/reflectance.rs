//! Reflectance maps: the brightness R of each surface orientation under one distant light.
//!
//! Every model gives R as a function of the unit normal together with its gradient ∂R/∂n; the
//! trait turns that, by the chain rule through the analytic Jacobians of
//! [`crate::gradient_space`], into R(f, g) with ∂R/∂f, ∂R/∂g and R(p, q) with ∂R/∂p, ∂R/∂q. The
//! viewer is at v = (0, 0, 1) (orthographic projection).

use crate::error::{Error, Result};
use crate::gradient_space::{
    normal_fg_jacobian, normal_from_fg, normal_from_pq, normal_pq_jacobian, Normal,
};
use crate::light::Light;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// R and its two partial derivatives at one point of a 2-D orientation space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The brightness R.
    pub value: f64,
    /// ∂R with respect to the first coordinate (f or p).
    pub d1: f64,
    /// ∂R with respect to the second coordinate (g or q).
    pub d2: f64,
}

impl Sample {
    /// R = 0 with a zero gradient: a blank to fill.
    pub const ZERO: Sample = Sample {
        value: 0.0,
        d1: 0.0,
        d2: 0.0,
    };
}

/// The second derivatives of R in a 2-D orientation space: (∂²R/∂f², ∂²R/∂f∂g, ∂²R/∂g²).
pub type Hessian = [f64; 3];

/// The step of the central differences of the gradient that give the default
/// [`ReflectanceMap::fg_hessian`].
pub const HESSIAN_STEP: f64 = 1e-4;

/// A reflectance map: brightness as a function of surface orientation, for a fixed light.
pub trait ReflectanceMap: Send + Sync + std::fmt::Debug {
    /// The light the map is computed for.
    fn light(&self) -> Light;

    /// R(n) and its gradient ∂R/∂n (the components of n taken as independent variables) at a
    /// unit normal `n`.
    fn radiance_and_gradient(&self, n: &Normal) -> (f64, Vector3<f64>);

    /// The brightness of a surface that the light does not reach (cast or attached shadow).
    fn ambient(&self) -> f64 {
        0.0
    }

    /// R(n) at a unit normal.
    fn radiance(&self, n: &Normal) -> f64 {
        self.radiance_and_gradient(n).0
    }

    /// R(f, g) with ∂R/∂f and ∂R/∂g.
    fn fg(&self, f: f64, g: f64) -> Sample {
        let n = normal_from_fg(f, g);
        let (value, grad) = self.radiance_and_gradient(&n);
        let (dn_df, dn_dg) = normal_fg_jacobian(f, g);
        Sample {
            value,
            d1: grad.dot(&dn_df),
            d2: grad.dot(&dn_dg),
        }
    }

    /// [`ReflectanceMap::fg`] at every point (`f[i]`, `g[i]`), written to `out[i]`, for as many
    /// points as the shortest of the three slices holds: the same values as `fg`, bit for bit.
    /// The shape-from-shading sweeps evaluate a row of pixels at a time through this; the
    /// default calls `fg` per point, and a model can override it with a loop that the
    /// compiler vectorises, without a call per point.
    ///
    /// ```
    /// use shadelab::Light;
    /// use shadelab::{Lambertian, ReflectanceMap, ReflectanceSample};
    ///
    /// let map = Lambertian::unit(Light::from_tilt_slant(30.0, 40.0).unwrap());
    /// let (f, g) = ([0.0, 0.5, -1.2], [0.0, -0.3, 0.4]);
    /// let mut out = [ReflectanceSample::ZERO; 3];
    /// map.fg_batch(&f, &g, &mut out);
    /// for i in 0..3 {
    ///     assert_eq!(out[i], map.fg(f[i], g[i]));
    /// }
    /// ```
    fn fg_batch(&self, f: &[f64], g: &[f64], out: &mut [Sample]) {
        for ((o, &f), &g) in out.iter_mut().zip(f).zip(g) {
            *o = self.fg(f, g);
        }
    }

    /// R(f, g) with its gradient (as [`ReflectanceMap::fg`]) and its [`Hessian`]. The default
    /// takes central differences of the gradient with step [`HESSIAN_STEP`] (four more
    /// evaluations, the cross term the mean of both); models with a closed form override it.
    /// At a kink of the map (the terminator) the result is that of one side or a difference
    /// across the kink: callers use it as a model, not as the truth.
    fn fg_hessian(&self, f: f64, g: f64) -> (Sample, Hessian) {
        let centre = self.fg(f, g);
        let (fp, fm) = (self.fg(f + HESSIAN_STEP, g), self.fg(f - HESSIAN_STEP, g));
        let (gp, gm) = (self.fg(f, g + HESSIAN_STEP), self.fg(f, g - HESSIAN_STEP));
        let h = 0.5 / HESSIAN_STEP;
        let hessian = [
            (fp.d1 - fm.d1) * h,
            0.5 * ((fp.d2 - fm.d2) + (gp.d1 - gm.d1)) * h,
            (gp.d2 - gm.d2) * h,
        ];
        (centre, hessian)
    }

    /// [`ReflectanceMap::fg_hessian`] at every point (`f[i]`, `g[i]`), into `out[i]` and
    /// `hessian[i]`, for as many points as the shortest slice holds: the same values, bit for
    /// bit; what [`ReflectanceMap::fg_batch`] is to `fg`.
    fn fg_hessian_batch(&self, f: &[f64], g: &[f64], out: &mut [Sample], hessian: &mut [Hessian]) {
        for (((o, h), &f), &g) in out.iter_mut().zip(hessian.iter_mut()).zip(f).zip(g) {
            (*o, *h) = self.fg_hessian(f, g);
        }
    }

    /// R(p, q) with ∂R/∂p and ∂R/∂q.
    fn pq(&self, p: f64, q: f64) -> Sample {
        let n = normal_from_pq(p, q);
        let (value, grad) = self.radiance_and_gradient(&n);
        let (dn_dp, dn_dq) = normal_pq_jacobian(p, q);
        Sample {
            value,
            d1: grad.dot(&dn_dp),
            d2: grad.dot(&dn_dq),
        }
    }
}

/// Lambertian (matte) reflectance: R = ambient + albedo · max(0, n·s). In attached shadow
/// (n·s ≤ 0) R is the ambient level and carries no information about the orientation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lambertian {
    /// The light.
    pub light: Light,
    /// Surface albedo ρ.
    pub albedo: f64,
    /// Ambient level added everywhere.
    pub ambient: f64,
}

impl Lambertian {
    /// Albedo 1 and no ambient light: R = max(0, n·s), the reflectance that shape from
    /// shading assumes for an image divided by its albedo.
    ///
    /// ```
    /// use shadelab::Light;
    /// use shadelab::Lambertian;
    ///
    /// let map = Lambertian::unit(Light::from_vector(0.0, 0.0, 1.0).unwrap());
    /// assert_eq!((map.albedo, map.ambient), (1.0, 0.0));
    /// ```
    pub fn unit(light: Light) -> Lambertian {
        Lambertian {
            light,
            albedo: 1.0,
            ambient: 0.0,
        }
    }
}

impl ReflectanceMap for Lambertian {
    fn light(&self) -> Light {
        self.light
    }

    fn ambient(&self) -> f64 {
        self.ambient
    }

    fn radiance_and_gradient(&self, n: &Normal) -> (f64, Vector3<f64>) {
        let s = self.light.direction();
        let cos_i = n.dot(&s);
        if cos_i > 0.0 {
            (self.ambient + self.albedo * cos_i, s * self.albedo)
        } else {
            (self.ambient, Vector3::zeros())
        }
    }

    fn fg(&self, f: f64, g: f64) -> Sample {
        self.fg_closed_form(f, g).0
    }

    fn fg_batch(&self, f: &[f64], g: &[f64], out: &mut [Sample]) {
        for ((o, &f), &g) in out.iter_mut().zip(f).zip(g) {
            *o = self.fg_closed_form(f, g).0;
        }
    }

    fn fg_hessian(&self, f: f64, g: f64) -> (Sample, Hessian) {
        let (sample, cos, inv_d) = self.fg_closed_form(f, g);
        (sample, self.hessian_closed_form(f, g, &sample, cos, inv_d))
    }

    fn fg_hessian_batch(&self, f: &[f64], g: &[f64], out: &mut [Sample], hessian: &mut [Hessian]) {
        for (((o, h), &f), &g) in out.iter_mut().zip(hessian.iter_mut()).zip(f).zip(g) {
            let (sample, cos, inv_d) = self.fg_closed_form(f, g);
            *o = sample;
            *h = self.hessian_closed_form(f, g, &sample, cos, inv_d);
        }
    }
}

impl Lambertian {
    /// R(f, g) and its gradient in closed form, with cos i = n·s and 1/(4 + f² + g²) for the
    /// Hessian. With n = (4f, 4g, 4 − f² − g²)/D, D = 4 + f² + g², cos i = N/D for
    /// N = 4(f·s_x + g·s_y) + (4 − f² − g²)·s_z, and ∂cos i/∂f = (4s_x − 2f·(s_z + cos i))/D
    /// (likewise in g): one division per point, where the chain rule through the normal's
    /// Jacobian takes several.
    #[inline(always)]
    fn fg_closed_form(&self, f: f64, g: f64) -> (Sample, f64, f64) {
        let s = self.light.direction();
        let r2 = f * f + g * g;
        let inv_d = 1.0 / (4.0 + r2);
        let cos = (4.0 * (f * s.x + g * s.y) + (4.0 - r2) * s.z) * inv_d;
        let sample = if cos > 0.0 {
            let t = s.z + cos;
            let scale = self.albedo * inv_d;
            Sample {
                value: self.ambient + self.albedo * cos,
                d1: scale * (4.0 * s.x - 2.0 * f * t),
                d2: scale * (4.0 * s.y - 2.0 * g * t),
            }
        } else {
            Sample {
                value: self.ambient,
                d1: 0.0,
                d2: 0.0,
            }
        };
        (sample, cos, inv_d)
    }

    /// The Hessian of R from [`Lambertian::fg_closed_form`]'s results: differentiating
    /// cos i·D = N twice, ∂²cos i/∂f² = (−2s_z − 4f·∂cos i/∂f − 2 cos i)/D,
    /// ∂²cos i/∂f∂g = −(2g·∂cos i/∂f + 2f·∂cos i/∂g)/D, and likewise in g; zero in shadow.
    #[inline(always)]
    fn hessian_closed_form(
        &self,
        f: f64,
        g: f64,
        sample: &Sample,
        cos: f64,
        inv_d: f64,
    ) -> Hessian {
        if cos <= 0.0 || self.albedo == 0.0 {
            return [0.0; 3];
        }
        let sz = self.light.direction().z;
        // ∂cos i/∂f and ∂cos i/∂g, times the albedo: the sample's gradient.
        let (cf, cg) = (sample.d1, sample.d2);
        let a = self.albedo;
        [
            (-2.0 * a * (sz + cos) - 4.0 * f * cf) * inv_d,
            -2.0 * (g * cf + f * cg) * inv_d,
            (-2.0 * a * (sz + cos) - 4.0 * g * cg) * inv_d,
        ]
    }
}

/// Blinn–Phong: the Lambertian term plus a specular lobe k_s·max(0, n·h)^shininess, with
/// h the unit half-vector between the light and the viewer, lit faces only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlinnPhong {
    /// The diffuse part.
    pub diffuse: Lambertian,
    /// Specular strength k_s.
    pub specular: f64,
    /// Specular exponent (larger is glossier).
    pub shininess: f64,
}

impl ReflectanceMap for BlinnPhong {
    fn light(&self) -> Light {
        self.diffuse.light
    }

    fn ambient(&self) -> f64 {
        self.diffuse.ambient
    }

    fn radiance_and_gradient(&self, n: &Normal) -> (f64, Vector3<f64>) {
        let (mut r, mut grad) = self.diffuse.radiance_and_gradient(n);
        let s = self.diffuse.light.direction();
        let h = (s + Vector3::z()).normalize();
        let cos_h = n.dot(&h);
        if n.dot(&s) > 0.0 && cos_h > 0.0 {
            r += self.specular * cos_h.powf(self.shininess);
            grad += h * (self.specular * self.shininess * cos_h.powf(self.shininess - 1.0));
        }
        (r, grad)
    }
}

/// Oren–Nayar rough diffuse reflectance (qualitative model), normalised so that roughness 0 is
/// Lambertian: R = ρ·cos θ_i·(A + B·max(0, cos(φ_i − φ_r))·sin α·tan β).
///
/// With v = (0, 0, 1), max(0, cos Δφ)·sin α·tan β = max(0, s_z − (n·s)·n_z) / max(n·s, n_z),
/// which is what is computed (and differentiated) here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrenNayar {
    /// The light.
    pub light: Light,
    /// Surface albedo ρ.
    pub albedo: f64,
    /// Roughness σ, the standard deviation of facet slopes, in radians.
    pub roughness: f64,
}

impl ReflectanceMap for OrenNayar {
    fn light(&self) -> Light {
        self.light
    }

    fn radiance_and_gradient(&self, n: &Normal) -> (f64, Vector3<f64>) {
        let s = self.light.direction();
        let v = Vector3::z();
        let s2 = self.roughness * self.roughness;
        let a = 1.0 - 0.5 * s2 / (s2 + 0.33);
        let b = 0.45 * s2 / (s2 + 0.09);
        let ci = n.dot(&s);
        if ci <= 0.0 {
            return (0.0, Vector3::zeros());
        }
        let cr = n.z;
        let c = s.z - ci * cr;
        let mut r = a * ci;
        let mut grad = s * a;
        if c > 0.0 && b > 0.0 {
            let dc = -(s * cr + v * ci);
            if ci >= cr {
                r += b * c;
                grad += dc * b;
            } else {
                r += b * ci * c / cr;
                grad += (s * (c / cr) + dc * (ci / cr) - v * (ci * c / (cr * cr))) * b;
            }
        }
        (self.albedo * r, grad * self.albedo)
    }
}

crate::params::param_choice! {
    /// A reflectance model, by the name `--brdf NAME` and the `brdf` key of a spec use.
    pub enum BrdfModel {
        /// [`Lambertian`]: matte.
        Lambertian = "lambertian",
        /// [`BlinnPhong`]: matte plus a specular lobe.
        BlinnPhong = "blinn-phong",
        /// [`OrenNayar`]: rough diffuse.
        OrenNayar = "oren-nayar",
    }
}

/// The reflectance models shadelab knows, by name, with their parameters: what `--brdf NAME`
/// and the `brdf` key of a spec select. Serialised as `{"model": "lambertian", "albedo": …}`
/// with every parameter, used by the model or not.
///
/// ```
/// use shadelab::{BrdfModel, BrdfSpec};
/// let spec = BrdfSpec::named("phong").unwrap();
/// assert_eq!(spec.model, BrdfModel::BlinnPhong);
/// let json = serde_json::to_value(&spec).unwrap();
/// assert_eq!(json["model"], "blinn-phong");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BrdfSpec {
    /// Which model.
    pub model: BrdfModel,
    /// Albedo ρ (0..1 for physical surfaces).
    pub albedo: f64,
    /// Ambient level (Lambertian and Blinn–Phong).
    pub ambient: f64,
    /// Specular strength k_s (Blinn–Phong).
    pub specular: f64,
    /// Specular exponent (Blinn–Phong).
    pub shininess: f64,
    /// Roughness σ in degrees (Oren–Nayar).
    pub roughness_deg: f64,
}

/// The names accepted by [`BrdfSpec::named`] (besides the aliases `phong` and `lambert`).
pub const BRDF_NAMES: &[&str] = BrdfModel::NAMES;

impl Default for BrdfSpec {
    fn default() -> Self {
        BrdfSpec {
            model: BrdfModel::Lambertian,
            albedo: 1.0,
            ambient: 0.0,
            specular: 0.4,
            shininess: 30.0,
            roughness_deg: 20.0,
        }
    }
}

impl BrdfSpec {
    /// The default parameters of the named model; fails for an unknown name.
    pub fn named(model: &str) -> Result<Self> {
        let model = match model {
            "phong" => "blinn-phong",
            "lambert" => "lambertian",
            m => m,
        };
        let model = model
            .parse::<BrdfModel>()
            .map_err(|_| Error::unknown("reflectance model", model, BRDF_NAMES))?;
        Ok(BrdfSpec {
            model,
            ..BrdfSpec::default()
        })
    }

    /// Builds the reflectance map for `light`, checking every parameter.
    pub fn build(&self, light: Light) -> Result<Box<dyn ReflectanceMap>> {
        let check = |name: &str, v: f64, lo: f64, hi: f64| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(Error::invalid(format!(
                    "{name} = {v} is outside {lo}..{hi}"
                )))
            }
        };
        let albedo = check("albedo", self.albedo, 0.0, 100.0)?;
        let ambient = check("ambient", self.ambient, 0.0, 1.0)?;
        let diffuse = Lambertian {
            light,
            albedo,
            ambient,
        };
        Ok(match self.model {
            BrdfModel::Lambertian => Box::new(diffuse),
            BrdfModel::BlinnPhong => Box::new(BlinnPhong {
                diffuse,
                specular: check("specular", self.specular, 0.0, 100.0)?,
                shininess: check("shininess", self.shininess, 1.0, 10_000.0)?,
            }),
            BrdfModel::OrenNayar => Box::new(OrenNayar {
                light,
                albedo,
                roughness: check("roughness_deg", self.roughness_deg, 0.0, 90.0)?.to_radians(),
            }),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_space::normal_from_fg;
    use proptest::prelude::*;

    fn models(light: Light) -> Vec<Box<dyn ReflectanceMap>> {
        BRDF_NAMES
            .iter()
            .map(|m| {
                let mut spec = BrdfSpec::named(m).unwrap();
                spec.ambient = 0.05;
                spec.build(light).unwrap()
            })
            .collect()
    }

    /// Whether (f, g) is away from the kinks of the models (terminator, specular cut-off,
    /// Oren–Nayar's branch switches), where finite differences are meaningless.
    fn smooth_at(light: Light, f: f64, g: f64) -> bool {
        let n = normal_from_fg(f, g);
        let s = light.direction();
        let ci = n.dot(&s);
        let c = s.z - ci * n.z;
        ci.abs() > 1e-3 && (ci - n.z).abs() > 1e-3 && c.abs() > 1e-3
    }

    #[test]
    fn lambertian_is_clamped_cosine() {
        let light = Light::from_tilt_slant(30.0, 40.0).unwrap();
        let r = Lambertian {
            light,
            albedo: 1.0,
            ambient: 0.0,
        };
        for &(f, g) in &[(0.0, 0.0), (0.5, -0.3), (-1.9, 0.2), (1.0, 1.0)] {
            let n = normal_from_fg(f, g);
            let expect = n.dot(&light.direction()).max(0.0);
            assert!((r.fg(f, g).value - expect).abs() < 1e-12);
        }
    }

    #[test]
    fn oren_nayar_at_zero_roughness_is_lambertian() {
        let light = Light::from_tilt_slant(-60.0, 50.0).unwrap();
        let on = OrenNayar {
            light,
            albedo: 0.8,
            roughness: 0.0,
        };
        let l = Lambertian {
            light,
            albedo: 0.8,
            ambient: 0.0,
        };
        for &(p, q) in &[(0.0, 0.0), (0.7, -0.3), (-2.0, 1.5)] {
            assert!((on.pq(p, q).value - l.pq(p, q).value).abs() < 1e-12);
        }
    }

    #[test]
    fn unknown_model_is_an_error() {
        let e = BrdfSpec::named("chrome").unwrap_err().to_string();
        assert!(e.contains("chrome") && e.contains("lambertian"), "{e}");
        let bad = BrdfSpec {
            albedo: f64::NAN,
            ..BrdfSpec::default()
        };
        assert!(bad.build(Light::FRONT).is_err());
    }

    proptest! {
        #[test]
        fn fg_derivatives_match_finite_differences(
            f in -1.95..1.95f64, g in -1.95..1.95f64,
            tilt in -180.0..180.0f64, slant in 0.0..80.0f64,
        ) {
            let light = Light::from_tilt_slant(tilt, slant).unwrap();
            prop_assume!(f * f + g * g < 3.8);
            let h = 1e-6;
            prop_assume!(smooth_at(light, f, g) && smooth_at(light, f + h, g) && smooth_at(light, f - h, g)
                && smooth_at(light, f, g + h) && smooth_at(light, f, g - h));
            for m in models(light) {
                let s = m.fg(f, g);
                let df = (m.fg(f + h, g).value - m.fg(f - h, g).value) / (2.0 * h);
                let dg = (m.fg(f, g + h).value - m.fg(f, g - h).value) / (2.0 * h);
                prop_assert!((s.d1 - df).abs() < 1e-5 * (1.0 + df.abs()), "{:?} d/df {} vs {}", m, s.d1, df);
                prop_assert!((s.d2 - dg).abs() < 1e-5 * (1.0 + dg.abs()), "{:?} d/dg {} vs {}", m, s.d2, dg);
            }
        }

        /// Lambertian's closed form agrees with the chain rule through the normal that the
        /// other models use; the batches give `fg` and `fg_hessian` bit for bit; the Hessian
        /// matches differences of the gradient away from the kinks.
        #[test]
        fn closed_forms_batches_and_hessians_agree(
            f in -1.95..1.95f64, g in -1.95..1.95f64,
            tilt in -180.0..180.0f64, slant in 0.0..80.0f64,
        ) {
            let light = Light::from_tilt_slant(tilt, slant).unwrap();
            let lambert = Lambertian { light, albedo: 0.7, ambient: 0.05 };
            let n = normal_from_fg(f, g);
            let (value, grad) = lambert.radiance_and_gradient(&n);
            let (dn_df, dn_dg) = crate::gradient_space::normal_fg_jacobian(f, g);
            let closed = lambert.fg(f, g);
            prop_assert!((closed.value - value).abs() < 1e-12);
            prop_assert!((closed.d1 - grad.dot(&dn_df)).abs() < 1e-12);
            prop_assert!((closed.d2 - grad.dot(&dn_dg)).abs() < 1e-12);
            // Smooth over the default's stencil, and compared with half its step.
            let k = HESSIAN_STEP;
            let smooth = [(0.0, 0.0), (k, 0.0), (-k, 0.0), (0.0, k), (0.0, -k)]
                .iter()
                .all(|(df, dg)| smooth_at(light, f + df, g + dg));
            let h = 0.5 * HESSIAN_STEP;
            let (fs, gs) = ([f, f + 0.1, f - 0.2], [g, g - 0.1, g + 0.05]);
            for m in models(light) {
                let mut batch = [Sample::ZERO; 3];
                let mut hbatch = [Sample::ZERO; 3];
                let mut hessians = [[0.0; 3]; 3];
                m.fg_batch(&fs, &gs, &mut batch);
                m.fg_hessian_batch(&fs, &gs, &mut hbatch, &mut hessians);
                for i in 0..3 {
                    prop_assert_eq!(batch[i], m.fg(fs[i], gs[i]));
                    let (sample, hessian) = m.fg_hessian(fs[i], gs[i]);
                    prop_assert_eq!(hbatch[i], sample);
                    prop_assert_eq!(hessians[i], hessian);
                    prop_assert_eq!(sample, m.fg(fs[i], gs[i]));
                }
                if smooth {
                    let (_, hessian) = m.fg_hessian(f, g);
                    let (fp, fm) = (m.fg(f + h, g), m.fg(f - h, g));
                    let (gp, gm) = (m.fg(f, g + h), m.fg(f, g - h));
                    let expect = [
                        (fp.d1 - fm.d1) / (2.0 * h),
                        (fp.d2 - fm.d2) / (2.0 * h),
                        (gp.d2 - gm.d2) / (2.0 * h),
                    ];
                    for (got, want) in hessian.iter().zip(expect) {
                        prop_assert!((got - want).abs() < 1e-3 * (1.0 + want.abs()), "{:?}: {:?} vs {:?}", m, hessian, expect);
                    }
                }
            }
        }

        #[test]
        fn pq_derivatives_match_finite_differences(
            p in -3.0..3.0f64, q in -3.0..3.0f64,
            tilt in -180.0..180.0f64, slant in 0.0..80.0f64,
        ) {
            let light = Light::from_tilt_slant(tilt, slant).unwrap();
            let h = 1e-6;
            let (f, g) = crate::gradient_space::fg_from_pq(p, q);
            prop_assume!(smooth_at(light, f, g));
            for (dp, dq) in [(h, 0.0), (-h, 0.0), (0.0, h), (0.0, -h)] {
                let (f2, g2) = crate::gradient_space::fg_from_pq(p + dp, q + dq);
                prop_assume!(smooth_at(light, f2, g2));
            }
            for m in models(light) {
                let s = m.pq(p, q);
                let dpv = (m.pq(p + h, q).value - m.pq(p - h, q).value) / (2.0 * h);
                let dqv = (m.pq(p, q + h).value - m.pq(p, q - h).value) / (2.0 * h);
                prop_assert!((s.d1 - dpv).abs() < 1e-5 * (1.0 + dpv.abs()));
                prop_assert!((s.d2 - dqv).abs() < 1e-5 * (1.0 + dqv.abs()));
            }
        }
    }
}
