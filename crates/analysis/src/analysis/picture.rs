//! A picture to analyse: luminance, tokens, and what its maker says about the surface.

use super::convexity::{tokens_from_labels, Token};
use super::interpretation::Lighting;
use crate::error::{Error, Result};
use crate::grid::{Image, Labels, Mask};
use crate::stimulus::{Output, Request};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// Where the engine solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub enum Domain {
    /// The whole picture: a relief on a plane (the default; the stimuli lie on a panel).
    #[default]
    Image,
    /// Only the tokens' pixels (an object on a background that is not part of the surface,
    /// like the hollow mask's face).
    Tokens,
}

/// The names of the domains, as `--domain` spells them.
pub const DOMAIN_NAMES: &[&str] = &["image", "tokens"];

impl FromStr for Domain {
    type Err = Error;
    fn from_str(s: &str) -> Result<Domain> {
        match s {
            "image" => Ok(Domain::Image),
            "tokens" => Ok(Domain::Tokens),
            other => Err(Error::unknown("domain", other, DOMAIN_NAMES)),
        }
    }
}

impl fmt::Display for Domain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Domain::Image => "image",
            Domain::Tokens => "tokens",
        })
    }
}

/// A picture with its tokens.
#[derive(Debug, Clone)]
pub struct TokenPicture {
    /// Linear luminance.
    pub image: Image,
    /// The tokens (the whole picture when there is no target mask).
    pub tokens: Vec<Token>,
    /// The surface albedo its maker declares, if any.
    pub albedo: Option<f64>,
    /// The ambient level its maker declares, if any.
    pub ambient: Option<f64>,
}

impl TokenPicture {
    /// A picture from an image and, optionally, a label map with token names. Fails on a label
    /// map of another size, one with no tokens, or a non-finite luminance.
    pub fn from_image(image: Image, labels: Option<(&Labels, &[String])>) -> Result<TokenPicture> {
        if let Some(i) = image.data().iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(format!(
                "image value at column {}, row {} is not a finite number",
                i % image.width(),
                i / image.width()
            )));
        }
        let tokens = match labels {
            Some((labels, names)) => {
                labels.check_same_size("the target mask is", &image, "the image is")?;
                tokens_from_labels(labels, names)?
            }
            None => vec![Token::whole(image.width(), image.height())?],
        };
        Ok(TokenPicture {
            image,
            tokens,
            albedo: None,
            ambient: None,
        })
    }

    /// A rendered stimulus, its targets as tokens, with the albedo and ambient level it
    /// declares as parameters.
    pub fn from_stimulus(request: &Request, output: &Output) -> Result<TokenPicture> {
        let image = output.pixels.luminance();
        let targets = output
            .targets
            .as_ref()
            .map(|t| (&t.labels, t.names.as_slice()));
        let mut picture = TokenPicture::from_image(image, targets)?;
        picture.take_declared(&request.params);
        Ok(picture)
    }

    /// Takes the albedo and ambient level that a stimulus's parameters declare (none for a
    /// stimulus without those parameters).
    pub fn take_declared(&mut self, params: &crate::params::Params) {
        self.albedo = params.f64("albedo").ok();
        self.ambient = params.f64("ambient").ok();
    }

    /// The solve domain.
    pub fn domain(&self, domain: Domain) -> Mask {
        let (w, h) = (self.image.width(), self.image.height());
        match domain {
            Domain::Image => Mask::new(w, h, true),
            Domain::Tokens => {
                let mut m = Mask::new(w, h, false);
                for t in &self.tokens {
                    for &p in t.pixels() {
                        m.data_mut()[p] = true;
                    }
                }
                m
            }
        }
    }

    /// The lighting to assume at `slant_deg`: `albedo` and `ambient` when given, else what the
    /// picture declares, else ambient 0 and the albedo that makes the picture's background
    /// (the median luminance of the domain's pixels outside every token, or of the whole
    /// domain when the tokens fill it) a surface facing the viewer.
    pub fn lighting(
        &self,
        domain: &Mask,
        slant_deg: f64,
        albedo: Option<f64>,
        ambient: Option<f64>,
    ) -> Result<Lighting> {
        let ambient = ambient.or(self.ambient).unwrap_or(0.0);
        let albedo = match albedo.or(self.albedo) {
            Some(a) => a,
            None => {
                let background = self.background(domain);
                Lighting::albedo_for_flat(background, slant_deg, ambient)?
            }
        };
        let lighting = Lighting {
            slant_deg,
            albedo,
            ambient,
        };
        lighting.validate()?;
        Ok(lighting)
    }

    /// The median luminance of the domain's pixels outside every token (of the whole domain
    /// when the tokens cover it).
    pub fn background(&self, domain: &Mask) -> f64 {
        let mut in_token = vec![false; self.image.len()];
        for t in &self.tokens {
            for &p in t.pixels() {
                in_token[p] = true;
            }
        }
        let pick = |outside_only: bool| -> Vec<f64> {
            self.image
                .data()
                .iter()
                .enumerate()
                .filter(|&(p, _)| domain.data()[p] && (!outside_only || !in_token[p]))
                .map(|(_, &v)| v)
                .collect()
        };
        let mut values = pick(true);
        if values.is_empty() {
            values = pick(false);
        }
        values.sort_by(f64::total_cmp);
        values.get(values.len() / 2).copied().unwrap_or(0.0)
    }
}
