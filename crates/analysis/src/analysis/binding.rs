//! One light for the whole scene, or one per token (Ramachandran 1988).
//!
//! In an array of oppositely shaded circles or strips, seeing one row as bumps makes the other
//! row dimples: vision assumes a single light. The engine shows why. Interpreted under one
//! global light, every token is judged against the same tilt, so tokens shaded in opposite
//! directions get opposite convexities. Interpreted with a light estimated from each token
//! alone, each token's light comes from its own bright side and every token reads the same
//! way (all convex): nothing binds them.
//!
//! Lights are estimated by [`crate::light_estimation::estimate_light`], tilt only: the slant is
//! held at the analysis's assumed slant, since the moment estimate of slant is biased for
//! shading painted on a plane (see that module).

use super::interpretation::{Interpreter, Lighting, Scene};
use crate::error::{Error, Result};
use crate::grid::Mask;
use crate::light_estimation::estimate_light;
use crate::parallel::prelude::*;
use crate::solver::SolveOptions;
use serde::Serialize;

/// Where the global light comes from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum GlobalLight {
    /// This tilt, degrees.
    Given(f64),
    /// Estimated from the whole domain.
    Estimated,
}

/// A light used for a reading, and how it was found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct UsedLight {
    /// The tilt used, degrees.
    pub tilt_deg: f64,
    /// For an estimated light, how consistently the picture brightens toward one side (0..1);
    /// near 0 the tilt is meaningless.
    pub tilt_confidence: Option<f64>,
}

/// The two readings of an array.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Binding {
    /// The global light.
    pub global_light: UsedLight,
    /// Each token's convexity under the global light.
    pub global: Vec<f64>,
    /// Each token's own light.
    pub token_lights: Vec<UsedLight>,
    /// Each token's convexity under its own light.
    pub per_token: Vec<f64>,
}

impl Binding {
    /// Whether the global reading gives tokens of both signs.
    pub fn global_has_both_signs(&self) -> bool {
        both_signs(&self.global)
    }

    /// Whether the per-token reading gives tokens of both signs.
    pub fn per_token_has_both_signs(&self) -> bool {
        both_signs(&self.per_token)
    }
}

fn both_signs(v: &[f64]) -> bool {
    v.iter().any(|&c| c > 0.0) && v.iter().any(|&c| c < 0.0)
}

/// Reads every token of `scene` under one global light and under a light of its own.
pub fn binding(
    scene: &Scene,
    lighting: &Lighting,
    global: GlobalLight,
    options: &SolveOptions,
) -> Result<Binding> {
    let global_light = match global {
        GlobalLight::Given(t) => UsedLight {
            tilt_deg: t,
            tilt_confidence: None,
        },
        GlobalLight::Estimated => {
            let e = estimate_light(scene.image, scene.domain)?;
            UsedLight {
                tilt_deg: e.tilt_deg,
                tilt_confidence: Some(e.tilt_confidence),
            }
        }
    };
    let (w, h) = (scene.image.width(), scene.image.height());
    let token_lights = scene
        .tokens
        .iter()
        .map(|t| {
            let mut mask = Mask::new(w, h, false);
            for &p in t.pixels() {
                mask.data_mut()[p] = true;
            }
            let e = estimate_light(scene.image, &mask)?;
            Ok(UsedLight {
                tilt_deg: e.tilt_deg,
                tilt_confidence: Some(e.tilt_confidence),
            })
        })
        .collect::<Result<Vec<_>>>()?;
    // One solve per distinct light: the global one, then each token's.
    let mut tilts = vec![global_light.tilt_deg];
    tilts.extend(token_lights.iter().map(|l| l.tilt_deg));
    let readings = tilts
        .par_iter()
        .map_init(
            || Interpreter::new(scene, options),
            |it, &t| match it {
                Ok(it) => it.interpret(scene, t, lighting),
                Err(e) => Err(Error::Compute(format!("cannot plan the solve: {e}"))),
            },
        )
        .collect::<Result<Vec<_>>>()?;
    let global_reading = readings[0].tokens.iter().map(|r| r.convexity).collect();
    let per_token = (0..scene.tokens.len())
        .map(|k| readings[k + 1].tokens[k].convexity)
        .collect();
    Ok(Binding {
        global_light,
        global: global_reading,
        token_lights,
        per_token,
    })
}
