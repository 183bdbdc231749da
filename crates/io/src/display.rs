//! A display in physical units: how its codes become cd/m², and the codes that show a linear
//! stimulus at given luminances.
//!
//! A [`Display`] is a response (code → cd/m²) at a bit depth: either PsychoPy's fitted gamma
//! model (its monitor calibration: L = a + (b + kV)^γ and its special cases, read from a PsychoPy
//! monitor file where one is given) or a photometer's table of code → cd/m², interpolated
//! monotonically (Fritsch & Carlson 1980). [`Display::show`] turns a stimulus (linear 0..1) into
//! the display's codes through the inverse response, mapping 0..1 onto the luminances a
//! [`Luminance`] asks for, and returns what the display will show in cd/m², code by code, so that
//! a sidecar can record each target's luminance. An 8-bit display can show finer steps by
//! bit-stealing (Tyler 1997: the R, G and B codes of a gray differ by one where that comes closer)
//! or by error diffusion (Floyd & Steinberg 1976).
//!
//! ```
//! use shadelab::display::{Display, GammaModel, Luminance, Quantise, Response};
//! use shadelab::Grid;
//!
//! // A display of gamma 2.2, 0.5 to 120 cd/m², 8 bits (PsychoPy's equation 1).
//! let model = GammaModel { equation: 1, black: 0.5, white: 120.0, gamma: 2.2, b: 0.0 };
//! let display = Display::new("lab", 8, Response::Gamma(model), Quantise::Plain).unwrap();
//! assert_eq!(display.code_luminance(255), 120.0);
//! // A stimulus 0..1 shown from 10 to 90 cd/m².
//! let stimulus = Grid::from_vec(3, 1, vec![0.0, 0.5, 1.0]).unwrap();
//! let shown = display.show(&stimulus, Luminance::Span { black: 10.0, white: 90.0 }).unwrap();
//! let l = shown.luminance.data();
//! // Each within half of its step between codes of the wanted 10, 50 and 90 cd/m².
//! assert!((l[0] - 10.0).abs() < 0.5 && (l[1] - 50.0).abs() < 0.5 && (l[2] - 90.0).abs() < 0.5);
//! ```

use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Labels};
use serde::Serialize;
use serde_json::{json, Value};

/// The Rec. 709 luminance weights of R, G and B: what each channel adds to a gray's luminance
/// when a display's channels are not measured separately.
pub const REC709_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// PsychoPy's gamma model of a display (`psychopy.monitors.gammaFun`), V the code scaled to
/// 0..1: equation 1, L = black + (white − black)·V^γ; equation 2, L = (a + b′V)^γ with
/// a = black^(1/γ), b′ = white^(1/γ) − a; equation 4 (Pelli & Zhang 1991), L = a + (b + kV)^γ
/// with a = black − b^γ and k = (white − a)^(1/γ) − b. Each runs from `black` at code 0 to
/// `white` at the top code.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GammaModel {
    /// PsychoPy's `linearizeMethod`: 1, 2 or 4.
    pub equation: u8,
    /// Luminance at code 0, cd/m² (PsychoPy's `minLum`).
    pub black: f64,
    /// Luminance at the top code, cd/m² (`maxLum`).
    pub white: f64,
    /// The exponent γ.
    pub gamma: f64,
    /// Equation 4's offset b (PsychoPy's gamma grid, column 4); ignored by equations 1 and 2.
    pub b: f64,
}

impl GammaModel {
    /// Luminance in cd/m² of the code scaled to 0..1.
    pub fn luminance(&self, v: f64) -> f64 {
        let (lo, hi, g) = (self.black, self.white, self.gamma);
        match self.equation {
            1 => lo + (hi - lo) * v.powf(g),
            2 => {
                let a = lo.powf(1.0 / g);
                let b = hi.powf(1.0 / g) - a;
                (a + b * v).powf(g)
            }
            _ => {
                let a = lo - self.b.powf(g);
                let k = (hi - a).powf(1.0 / g) - self.b;
                a + (self.b + k * v).powf(g)
            }
        }
    }

    fn check(&self) -> std::result::Result<(), String> {
        let finite = [self.black, self.white, self.gamma, self.b]
            .iter()
            .all(|v| v.is_finite());
        if !finite {
            return Err("the gamma model's numbers must be finite".into());
        }
        if !matches!(self.equation, 1 | 2 | 4) {
            return Err(format!(
                "equation {} is not one of PsychoPy's 1, 2 or 4",
                self.equation
            ));
        }
        if !(self.black >= 0.0 && self.white > self.black) {
            return Err(format!(
                "black {} and white {} cd/m² must satisfy 0 <= black < white",
                self.black, self.white
            ));
        }
        if !(0.1..=10.0).contains(&self.gamma) {
            return Err(format!("gamma {} must be 0.1 to 10", self.gamma));
        }
        if self.b < 0.0 {
            return Err(format!("b {} must not be negative", self.b));
        }
        Ok(())
    }
}

/// How a display's codes become luminance.
#[derive(Debug, Clone, PartialEq)]
pub enum Response {
    /// PsychoPy's fitted gamma model.
    Gamma(GammaModel),
    /// A photometer's measurements: (code, cd/m²) pairs, codes rising from 0 to the top code,
    /// luminance rising; codes between are interpolated monotonically.
    Table(Vec<(u32, f64)>),
}

/// How luminances between two codes are shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantise {
    /// The nearest code, pixel by pixel: error at most half the step between two codes.
    Plain,
    /// Bit-stealing (Tyler 1997), 8-bit only: R, G and B may each be one code above the gray,
    /// so that 7 levels lie between two grays; the file is RGB.
    BitStealing,
    /// Error diffusion (Floyd & Steinberg 1976): each pixel's error is passed on to its
    /// neighbours, so that the mean over a small region is right.
    Dither,
}

impl Quantise {
    /// Its name in display files and sidecars.
    pub fn name(self) -> &'static str {
        match self {
            Quantise::Plain => "plain",
            Quantise::BitStealing => "bit-stealing",
            Quantise::Dither => "dither",
        }
    }
}

/// Which luminances a stimulus's linear 0..1 is shown at; parsed from `LO,HI` (cd/m² of 0 and
/// 1) or `background=B,michelson=C`.
///
/// ```
/// use shadelab::display::Luminance;
/// let span: Luminance = "10,90".parse().unwrap();
/// assert_eq!(span, Luminance::Span { black: 10.0, white: 90.0 });
/// let m: Luminance = "background=50,michelson=0.8".parse().unwrap();
/// let (lo, hi) = m.span();
/// assert!((lo - 10.0).abs() < 1e-12 && (hi - 90.0).abs() < 1e-12);
/// assert!("background=50,michelson=1.5".parse::<Luminance>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Luminance {
    /// 0 at `black` and 1 at `white`, cd/m², linearly between.
    Span {
        /// cd/m² of the stimulus's 0.
        black: f64,
        /// cd/m² of the stimulus's 1.
        white: f64,
    },
    /// A Michelson contrast about a background: v ↦ background·(1 + contrast·(2v − 1)), so that
    /// 0.5 is the background and 0..1 spans the contrast.
    Michelson {
        /// cd/m² of the stimulus's 0.5.
        background: f64,
        /// (Lmax − Lmin)/(Lmax + Lmin) of the stimulus's 0..1, in (0, 1].
        contrast: f64,
    },
}

impl Luminance {
    /// The cd/m² of the stimulus's 0 and 1.
    pub fn span(self) -> (f64, f64) {
        match self {
            Luminance::Span { black, white } => (black, white),
            Luminance::Michelson {
                background,
                contrast,
            } => (background * (1.0 - contrast), background * (1.0 + contrast)),
        }
    }

    /// The background luminance, where one is given.
    pub fn background(self) -> Option<f64> {
        match self {
            Luminance::Michelson { background, .. } => Some(background),
            Luminance::Span { .. } => None,
        }
    }

    /// Parses `LO,HI` (cd/m² of 0 and 1) or `background=B,michelson=C`.
    fn parse_text(text: &str) -> std::result::Result<Luminance, String> {
        let number = |s: &str| -> std::result::Result<f64, String> {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("'{s}' is not a number"))
        };
        let parts: Vec<&str> = text.split(',').collect();
        let mut keyed = std::collections::BTreeMap::new();
        for p in &parts {
            if let Some((k, v)) = p.split_once('=') {
                keyed.insert(k.trim().to_string(), number(v)?);
            }
        }
        let value = if keyed.is_empty() && parts.len() == 2 {
            Luminance::Span {
                black: number(parts[0])?,
                white: number(parts[1])?,
            }
        } else if keyed.len() == 2 && parts.len() == 2 {
            match (keyed.get("background"), keyed.get("michelson")) {
                (Some(&background), Some(&contrast)) => Luminance::Michelson {
                    background,
                    contrast,
                },
                _ => return Err(format!("'{text}': give LO,HI or background=B,michelson=C")),
            }
        } else {
            return Err(format!("'{text}': give LO,HI or background=B,michelson=C"));
        };
        value.check()?;
        Ok(value)
    }

    fn check(self) -> std::result::Result<(), String> {
        if let Luminance::Michelson {
            background,
            contrast,
        } = self
        {
            if background.is_nan() || background <= 0.0 {
                return Err(format!(
                    "the background {background} cd/m² must be positive"
                ));
            }
            if !(contrast > 0.0 && contrast <= 1.0) {
                return Err(format!(
                    "the Michelson contrast {contrast} must be in (0, 1]"
                ));
            }
        }
        let (lo, hi) = self.span();
        if !(lo >= 0.0 && hi > lo) {
            return Err(format!(
                "the stimulus's 0..1 must map to 0 <= LO < HI cd/m² (got {lo}..{hi})"
            ));
        }
        Ok(())
    }

    /// The mapping a sidecar recorded ([`to_json`](Self::to_json)'s object).
    pub fn from_record(value: &Value) -> Result<Luminance> {
        let num = |key: &str| value.get(key).and_then(Value::as_f64);
        let mapping = match (
            num("background_cd_m2"),
            num("michelson"),
            num("black_cd_m2"),
            num("white_cd_m2"),
        ) {
            (Some(background), Some(contrast), _, _) => Luminance::Michelson {
                background,
                contrast,
            },
            (None, None, Some(black), Some(white)) => Luminance::Span { black, white },
            _ => {
                return Err(Error::invalid(format!(
                    "the recorded luminance {value} is not what shadelab writes"
                )))
            }
        };
        mapping.check().map_err(Error::invalid)?;
        Ok(mapping)
    }

    /// As a sidecar records it.
    pub fn to_json(self) -> Value {
        let (lo, hi) = self.span();
        match self {
            Luminance::Span { .. } => json!({"black_cd_m2": lo, "white_cd_m2": hi}),
            Luminance::Michelson {
                background,
                contrast,
            } => json!({
                "background_cd_m2": background, "michelson": contrast,
                "black_cd_m2": lo, "white_cd_m2": hi,
            }),
        }
    }
}

impl std::str::FromStr for Luminance {
    type Err = Error;
    fn from_str(text: &str) -> Result<Luminance> {
        Luminance::parse_text(text).map_err(Error::invalid)
    }
}

/// A display: its response at its bit depth and how it quantises.
#[derive(Debug, Clone, PartialEq)]
pub struct Display {
    name: String,
    bits: u8,
    response: Response,
    quantise: Quantise,
    weights: [f64; 3],
    /// cd/m² of every code, rising.
    lut: Vec<f64>,
    calibration: Option<Calibration>,
}

/// Which calibration of a PsychoPy monitor file a display was read from, and why that one
/// (a sidecar records it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Calibration {
    /// Its name in the monitor file.
    pub name: String,
    /// Named by the display's `calibration`; else PsychoPy's own choice, the one
    /// `psychopy.monitors.Monitor(name)` loads: the last by name.
    pub named: bool,
    /// Every calibration in the file, in PsychoPy's order (by name).
    pub all: Vec<String>,
}

/// What a display shows of a stimulus: its codes and their luminance.
#[derive(Debug, Clone, PartialEq)]
pub struct Shown {
    /// The codes, row-major, one per pixel (gray) or three (RGB, bit-stealing), each
    /// 0..2^bits − 1.
    pub codes: Vec<u16>,
    /// Channels per pixel: 1 or 3.
    pub channels: usize,
    /// The luminance the display shows at each pixel, cd/m².
    pub luminance: Image,
    /// The luminance asked for at each pixel, cd/m².
    pub wanted: Image,
    /// The luminance mapping used.
    pub mapping: Luminance,
}

/// What a display shows of one target.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TargetLuminance {
    /// Its label in the target mask.
    pub label: u16,
    /// Its name.
    pub name: String,
    /// The mean luminance shown over its pixels, cd/m².
    pub luminance_cd_m2: f64,
    /// (L − background) / background, where the mapping has a background.
    pub weber_vs_background: Option<f64>,
}

impl Shown {
    /// The luminance shown in each target that has pixels (mean over them, cd/m²), with its
    /// Weber contrast against the background where the mapping has one; `names[l - 1]` names
    /// label `l`.
    pub fn targets(&self, labels: &Labels, names: &[String]) -> Vec<TargetLuminance> {
        let mut sums = vec![(0.0, 0usize); names.len()];
        for (&l, &v) in labels.data().iter().zip(self.luminance.data()) {
            if l >= 1 && (l as usize) <= names.len() {
                let s = &mut sums[l as usize - 1];
                s.0 += v;
                s.1 += 1;
            }
        }
        (1u16..)
            .zip(names.iter().zip(sums))
            .filter(|(_, (_, (_, n)))| *n > 0)
            .map(|(label, (name, (sum, n)))| {
                let mean = sum / n as f64;
                TargetLuminance {
                    label,
                    name: name.clone(),
                    luminance_cd_m2: mean,
                    weber_vs_background: self.mapping.background().map(|b| (mean - b) / b),
                }
            })
            .collect()
    }

    /// The mapping and the error, as a sidecar records them: `luminance` and
    /// `luminance_error_cd_m2` (`max`, `rms`).
    pub fn to_json(&self) -> serde_json::Map<String, Value> {
        let (max, rms) = self.error();
        let mut record = serde_json::Map::new();
        record.insert("luminance".into(), self.mapping.to_json());
        record.insert(
            "luminance_error_cd_m2".into(),
            json!({"max": max, "rms": rms}),
        );
        record
    }

    /// The error of the luminance shown against the luminance wanted: (largest, root mean
    /// square), cd/m².
    pub fn error(&self) -> (f64, f64) {
        let (mut max, mut sum) = (0.0f64, 0.0);
        for (a, b) in self.luminance.data().iter().zip(self.wanted.data()) {
            let e = (a - b).abs();
            max = max.max(e);
            sum += e * e;
        }
        let n = self.wanted.data().len().max(1) as f64;
        (max, (sum / n).sqrt())
    }
}

impl Display {
    /// A display named `name` with `bits` per channel (8, 10 or 16), its response and its
    /// quantisation; checked (a response that does not rise from code 0 to the top code, or
    /// bit-stealing on a display that is not 8-bit, is refused).
    pub fn new(
        name: impl Into<String>,
        bits: u8,
        response: Response,
        quantise: Quantise,
    ) -> Result<Display> {
        let bad = |m: String| Error::invalid(format!("display: {m}"));
        if !matches!(bits, 8 | 10 | 16) {
            return Err(bad(format!("bit depth {bits} is not 8, 10 or 16")));
        }
        if quantise == Quantise::BitStealing && bits != 8 {
            return Err(bad(format!(
                "bit-stealing is for 8-bit displays (this one has {bits} bits)"
            )));
        }
        let top = (1u32 << bits) - 1;
        let lut: Vec<f64> = match &response {
            Response::Gamma(model) => {
                model.check().map_err(bad)?;
                (0..=top)
                    .map(|c| model.luminance(f64::from(c) / f64::from(top)))
                    .collect()
            }
            Response::Table(rows) => table_lut(rows, top).map_err(bad)?,
        };
        if let Some(i) = lut.windows(2).position(|w| w[1].is_nan() || w[1] <= w[0]) {
            return Err(bad(format!(
                "its luminance does not rise from code {i} to {} ({} then {} cd/m²)",
                i + 1,
                lut[i],
                lut[i + 1]
            )));
        }
        Ok(Display {
            name: name.into(),
            bits,
            response,
            quantise,
            weights: REC709_WEIGHTS,
            lut,
            calibration: None,
        })
    }

    /// Records which calibration of a PsychoPy monitor file the display is.
    pub fn with_calibration(mut self, calibration: Calibration) -> Display {
        self.calibration = Some(calibration);
        self
    }

    /// The PsychoPy calibration the display was read from, if any.
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_ref()
    }

    /// Sets the luminance weights of R, G and B that bit-stealing adds (default
    /// [`REC709_WEIGHTS`]; a PsychoPy calibration's gun luminances where it has them).
    pub fn with_channel_weights(mut self, weights: [f64; 3]) -> Result<Display> {
        let sum: f64 = weights.iter().sum();
        if !weights.iter().all(|w| w.is_finite() && *w > 0.0) || (sum - 1.0).abs() > 1e-6 {
            return Err(Error::invalid(format!(
                "display: channel weights {weights:?} must be positive and add up to 1"
            )));
        }
        self.weights = weights;
        Ok(self)
    }

    /// The display's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Bits per channel: 8, 10 or 16.
    pub fn bits(&self) -> u8 {
        self.bits
    }

    /// How it quantises.
    pub fn quantise(&self) -> Quantise {
        self.quantise
    }

    /// The top code, 2^bits − 1.
    pub fn top_code(&self) -> u16 {
        (self.lut.len() - 1) as u16
    }

    /// The luminance of a gray code, cd/m².
    pub fn code_luminance(&self, code: u16) -> f64 {
        self.lut[usize::from(code).min(self.lut.len() - 1)]
    }

    /// The luminance of an RGB triple of codes: the channels' weighted gray luminances.
    pub fn rgb_luminance(&self, codes: [u16; 3]) -> f64 {
        (0..3)
            .map(|c| self.weights[c] * self.code_luminance(codes[c]))
            .sum()
    }

    /// Black and white: the luminance of code 0 and of the top code.
    pub fn black_white(&self) -> (f64, f64) {
        (self.lut[0], self.lut[self.lut.len() - 1])
    }

    /// The whole range of the display, as a [`Luminance`].
    pub fn full_range(&self) -> Luminance {
        let (black, white) = self.black_white();
        Luminance::Span { black, white }
    }

    /// The code whose luminance is nearest `l` (the lower on a tie).
    pub fn nearest_code(&self, l: f64) -> u16 {
        let i = self.lut.partition_point(|&v| v < l);
        let code = if i == 0 {
            0
        } else if i == self.lut.len() || l - self.lut[i - 1] <= self.lut[i] - l {
            i - 1
        } else {
            i
        };
        code as u16
    }

    /// Checks that `mapping` is well formed and within the display's black and white.
    pub fn check_mapping(&self, mapping: Luminance) -> Result<()> {
        mapping.check().map_err(Error::invalid)?;
        let (lo, hi) = mapping.span();
        let (black, white) = self.black_white();
        let slack = 1e-9 * white;
        if lo < black - slack || hi > white + slack {
            return Err(Error::invalid(format!(
                "the stimulus's luminance {lo}..{hi} cd/m² is outside what the display '{}' \
                 shows ({black}..{white} cd/m²)",
                self.name
            )));
        }
        Ok(())
    }

    /// The codes that show `stimulus` (linear 0..1) at the luminances `mapping` asks for, and
    /// what they show. The mapping must lie within the display's black and white.
    pub fn show(&self, stimulus: &Image, mapping: Luminance) -> Result<Shown> {
        self.check_mapping(mapping)?;
        let (lo, hi) = mapping.span();
        let wanted = stimulus.map(|&v| lo + v * (hi - lo));
        let (w, h) = (stimulus.width(), stimulus.height());
        let (codes, channels, luminance): (Vec<u16>, usize, Vec<f64>) = match self.quantise {
            Quantise::Plain => {
                let codes: Vec<u16> = wanted
                    .data()
                    .iter()
                    .map(|&l| self.nearest_code(l))
                    .collect();
                let lum = codes.iter().map(|&c| self.code_luminance(c)).collect();
                (codes, 1, lum)
            }
            Quantise::Dither => {
                let codes = self.diffuse(&wanted);
                let lum = codes.iter().map(|&c| self.code_luminance(c)).collect();
                (codes, 1, lum)
            }
            Quantise::BitStealing => {
                let triples: Vec<[u16; 3]> = wanted.data().iter().map(|&l| self.steal(l)).collect();
                let lum = triples.iter().map(|&t| self.rgb_luminance(t)).collect();
                (triples.concat(), 3, lum)
            }
        };
        Ok(Shown {
            codes,
            channels,
            luminance: Grid::from_vec(w, h, luminance)?,
            wanted,
            mapping,
        })
    }

    /// Floyd–Steinberg error diffusion in luminance, row by row, left to right.
    fn diffuse(&self, wanted: &Image) -> Vec<u16> {
        let (w, h) = (wanted.width(), wanted.height());
        let (black, white) = self.black_white();
        let mut row = vec![0.0; w + 2];
        let mut next = vec![0.0; w + 2];
        let mut codes = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                let target = (wanted.get(c, r) + row[c + 1]).clamp(black, white);
                let code = self.nearest_code(target);
                let e = target - self.code_luminance(code);
                codes.push(code);
                row[c + 2] += e * 7.0 / 16.0;
                next[c] += e * 3.0 / 16.0;
                next[c + 1] += e * 5.0 / 16.0;
                next[c + 2] += e / 16.0;
            }
            std::mem::swap(&mut row, &mut next);
            next.iter_mut().for_each(|v| *v = 0.0);
        }
        codes
    }

    /// The RGB triple nearest `l`: the gray at or below it with each channel one code up or
    /// not (8 candidates, the first nearest in a fixed order).
    fn steal(&self, l: f64) -> [u16; 3] {
        let top = self.top_code();
        let gray = (self.lut.partition_point(|&v| v <= l).max(1) - 1) as u16;
        let mut best = [gray; 3];
        let mut best_error = f64::INFINITY;
        for bits in 0..8u16 {
            let t = [0, 1, 2].map(|c| (gray + ((bits >> c) & 1)).min(top));
            let e = (self.rgb_luminance(t) - l).abs();
            if e < best_error {
                best = t;
                best_error = e;
            }
        }
        best
    }

    /// As a sidecar records it: name, bit depth, response, quantisation, black and white.
    pub fn to_json(&self) -> Value {
        let response = match &self.response {
            Response::Gamma(m) => json!({
                "model": "psychopy-gamma", "equation": m.equation, "black_cd_m2": m.black,
                "white_cd_m2": m.white, "gamma": m.gamma, "b": m.b,
            }),
            Response::Table(rows) => json!({
                "model": "table",
                "table": rows.iter().map(|(c, l)| json!([c, l])).collect::<Vec<_>>(),
            }),
        };
        let (black, white) = self.black_white();
        let mut record = json!({
            "name": self.name,
            "bit_depth": self.bits,
            "response": response,
            "quantise": self.quantise.name(),
            "channel_weights": self.weights,
            "black_cd_m2": black,
            "white_cd_m2": white,
        });
        if let Some(c) = &self.calibration {
            record["psychopy_calibration"] = json!({
                "name": c.name,
                "taken": if c.named {
                    "named"
                } else {
                    "PsychoPy's: the last by name, as Monitor(name) loads it"
                },
                "calibrations": c.all,
            });
        }
        record
    }

    /// The display a sidecar recorded ([`to_json`](Self::to_json)'s object).
    pub fn from_record(value: &Value) -> Result<Display> {
        let bad = || {
            Error::invalid(format!(
                "the recorded display {value} is not what shadelab writes"
            ))
        };
        let name = value.get("name").and_then(Value::as_str).ok_or_else(bad)?;
        let bits = value
            .get("bit_depth")
            .and_then(Value::as_u64)
            .ok_or_else(bad)? as u8;
        let quantise = match value.get("quantise").and_then(Value::as_str) {
            Some("plain") => Quantise::Plain,
            Some("bit-stealing") => Quantise::BitStealing,
            Some("dither") => Quantise::Dither,
            _ => return Err(bad()),
        };
        let r = value.get("response").ok_or_else(bad)?;
        let num = |key: &str| r.get(key).and_then(Value::as_f64).ok_or_else(bad);
        let response = match r.get("model").and_then(Value::as_str) {
            Some("psychopy-gamma") => Response::Gamma(GammaModel {
                equation: num("equation")? as u8,
                black: num("black_cd_m2")?,
                white: num("white_cd_m2")?,
                gamma: num("gamma")?,
                b: num("b")?,
            }),
            Some("table") => Response::Table(
                r.get("table")
                    .and_then(Value::as_array)
                    .ok_or_else(bad)?
                    .iter()
                    .map(|row| {
                        match (
                            row.get(0).and_then(Value::as_u64),
                            row.get(1).and_then(Value::as_f64),
                        ) {
                            (Some(c), Some(l)) => Ok((c as u32, l)),
                            _ => Err(bad()),
                        }
                    })
                    .collect::<Result<Vec<_>>>()?,
            ),
            _ => return Err(bad()),
        };
        let mut display = Display::new(name, bits, response, quantise)?;
        if let Some(c) = value.get("psychopy_calibration") {
            display = display.with_calibration(Calibration {
                name: c["name"].as_str().ok_or_else(bad)?.to_string(),
                named: c["taken"] == "named",
                all: c["calibrations"]
                    .as_array()
                    .ok_or_else(bad)?
                    .iter()
                    .map(|n| n.as_str().map(str::to_string).ok_or_else(bad))
                    .collect::<Result<_>>()?,
            });
        }
        match value
            .get("channel_weights")
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_f64).collect::<Vec<_>>())
        {
            Some(w) if w.len() == 3 => display.with_channel_weights([w[0], w[1], w[2]]),
            _ => Ok(display),
        }
    }
}

/// The luminance of every code 0..=top from measured rows: monotone cubic (Fritsch–Carlson)
/// through the rows, which must start at code 0, end at `top` and rise in both columns.
fn table_lut(rows: &[(u32, f64)], top: u32) -> std::result::Result<Vec<f64>, String> {
    if rows.len() < 2 || rows[0].0 != 0 || rows[rows.len() - 1].0 != top {
        return Err(format!(
            "a photometer table must run from code 0 to code {top} (the top code)"
        ));
    }
    for w in rows.windows(2) {
        if w[1].0 <= w[0].0 || w[1].1 <= w[0].1 || !w[1].1.is_finite() {
            return Err(format!(
                "the table must rise in code and in luminance (code {} at {} cd/m², then code \
                 {} at {})",
                w[0].0, w[0].1, w[1].0, w[1].1
            ));
        }
    }
    let x: Vec<f64> = rows.iter().map(|r| f64::from(r.0)).collect();
    let y: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let n = x.len();
    let h: Vec<f64> = (0..n - 1).map(|i| x[i + 1] - x[i]).collect();
    let d: Vec<f64> = (0..n - 1).map(|i| (y[i + 1] - y[i]) / h[i]).collect();
    // Slopes: Fritsch–Carlson's weighted harmonic mean inside (the secants are all positive),
    // the one-sided secant at the ends.
    let mut m = vec![0.0; n];
    m[0] = d[0];
    m[n - 1] = d[n - 2];
    for i in 1..n - 1 {
        let (w1, w2) = (2.0 * h[i] + h[i - 1], h[i] + 2.0 * h[i - 1]);
        m[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i]);
    }
    let mut lut = Vec::with_capacity(top as usize + 1);
    let mut seg = 0;
    for code in 0..=top {
        let c = f64::from(code);
        while seg + 1 < n - 1 && c > x[seg + 1] {
            seg += 1;
        }
        let t = (c - x[seg]) / h[seg];
        let (t2, t3) = (t * t, t * t * t);
        let v = (2.0 * t3 - 3.0 * t2 + 1.0) * y[seg]
            + (t3 - 2.0 * t2 + t) * h[seg] * m[seg]
            + (-2.0 * t3 + 3.0 * t2) * y[seg + 1]
            + (t3 - t2) * h[seg] * m[seg + 1];
        lut.push(v);
    }
    Ok(lut)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gamma_display(bits: u8, quantise: Quantise) -> Display {
        let model = GammaModel {
            equation: 1,
            black: 0.5,
            white: 120.0,
            gamma: 2.2,
            b: 0.0,
        };
        Display::new("test", bits, Response::Gamma(model), quantise).unwrap()
    }

    #[test]
    fn psychopy_equations_run_from_black_to_white() {
        for (equation, b) in [(1, 0.0), (2, 0.0), (4, 0.3)] {
            let m = GammaModel {
                equation,
                black: 0.4,
                white: 95.0,
                gamma: 2.3,
                b,
            };
            assert!(
                (m.luminance(0.0) - 0.4).abs() < 1e-12,
                "equation {equation}"
            );
            assert!(
                (m.luminance(1.0) - 95.0).abs() < 1e-9,
                "equation {equation}"
            );
        }
    }

    #[test]
    fn plain_codes_are_within_half_a_step_of_the_wanted_luminance() {
        for bits in [8, 10, 16] {
            let d = gamma_display(bits, Quantise::Plain);
            let ramp = Grid::from_fn(997, 1, |c, _| c as f64 / 996.0);
            let shown = d.show(&ramp, d.full_range()).unwrap();
            for ((&code, &l), &want) in shown
                .codes
                .iter()
                .zip(shown.luminance.data())
                .zip(shown.wanted.data())
            {
                // The steps on either side of the code chosen.
                let below = d.code_luminance(code.saturating_sub(1));
                let above = d.code_luminance(code.saturating_add(1).min(d.top_code()));
                let half = 0.5 * (l - below).max(above - l);
                assert!(
                    (l - want).abs() <= half + 1e-12,
                    "{bits} bits: {l} vs {want}"
                );
            }
        }
    }

    #[test]
    fn bit_stealing_and_dither_beat_plain_eight_bits() {
        let ramp = Grid::from_fn(512, 64, |c, _| 0.2 + 0.3 * c as f64 / 511.0);
        let range = Luminance::Span {
            black: 10.0,
            white: 90.0,
        };
        let plain = gamma_display(8, Quantise::Plain)
            .show(&ramp, range)
            .unwrap();
        let stolen = gamma_display(8, Quantise::BitStealing)
            .show(&ramp, range)
            .unwrap();
        assert_eq!(stolen.channels, 3);
        let (plain_max, plain_rms) = plain.error();
        let (stolen_max, stolen_rms) = stolen.error();
        assert!(stolen_max < plain_max / 2.0 && stolen_rms < plain_rms / 3.0);
        // Dithering: per pixel up to a step, but each 8×8 block's mean within a tenth of plain's
        // largest error.
        let dithered = gamma_display(8, Quantise::Dither)
            .show(&ramp, range)
            .unwrap();
        let block = |img: &Image, bc: usize, br: usize| {
            let mut s = 0.0;
            for r in 0..8 {
                for c in 0..8 {
                    s += img.get(bc * 8 + c, br * 8 + r);
                }
            }
            s / 64.0
        };
        let mut worst = 0.0f64;
        for br in 1..8 {
            for bc in 1..64 {
                let e = block(&dithered.luminance, bc, br) - block(&dithered.wanted, bc, br);
                worst = worst.max(e.abs());
            }
        }
        assert!(
            worst < plain_max / 4.0,
            "dither block error {worst} vs {plain_max}"
        );
    }

    #[test]
    fn a_table_is_interpolated_monotonically_through_its_rows() {
        let rows = vec![(0, 0.3), (64, 4.0), (128, 20.0), (192, 55.0), (255, 110.0)];
        let d = Display::new("t", 8, Response::Table(rows.clone()), Quantise::Plain).unwrap();
        for (c, l) in rows {
            assert!((d.code_luminance(c as u16) - l).abs() < 1e-9);
        }
        assert!(Display::new(
            "t",
            8,
            Response::Table(vec![(0, 1.0), (255, 0.5)]),
            Quantise::Plain
        )
        .unwrap_err()
        .to_string()
        .contains("rise"));
        assert!(Display::new(
            "t",
            8,
            Response::Table(vec![(0, 1.0), (200, 5.0)]),
            Quantise::Plain
        )
        .unwrap_err()
        .to_string()
        .contains("code 255"));
    }

    #[test]
    fn a_mapping_beyond_the_display_is_refused() {
        let d = gamma_display(8, Quantise::Plain);
        let img = Grid::new(2, 2, 0.5);
        let e = d
            .show(
                &img,
                Luminance::Span {
                    black: 0.1,
                    white: 90.0,
                },
            )
            .unwrap_err();
        assert!(e.to_string().contains("outside what the display"));
        assert!("background=50,michelson=1.5".parse::<Luminance>().is_err());
        assert!("10".parse::<Luminance>().is_err());
        assert!("90,10".parse::<Luminance>().is_err());
    }
}
