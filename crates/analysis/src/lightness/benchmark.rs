//! Scores of lightness-model predictions against human data, as the literature scores them.
//!
//! A model's *effect* on a stimulus with two targets is the mean model output over the target
//! people see as lighter minus the mean over the other (Robinson, Hammon & de Sa 2007 compare
//! models with observers by the difference of the mean model output on the two targets). The
//! model predicts the human *direction* when its effect is positive (the verdicts, with the
//! tolerance under which an effect is no prediction, are
//! `pipeline::benchmark::Verdict`'s). Across stimuli, the
//! Spearman rank correlation between the models' effects and the human effect sizes says
//! whether the model orders the illusions by strength as people do; it does not depend on
//! the model's units.

use crate::error::Result;
use crate::grid::{Image, Labels};

/// The mean of `output` over the pixels labelled `lighter` minus the mean over those labelled
/// `darker`; `None` when either label has no pixel.
///
/// ```
/// use shadelab::Grid;
/// use shadelab_analysis::lightness::benchmark::effect;
/// let labels = Grid::from_vec(4, 1, vec![1u16, 1, 0, 2]).unwrap();
/// let output = Grid::from_vec(4, 1, vec![0.5, 0.7, 9.0, 0.2]).unwrap();
/// assert!((effect(&output, &labels, 1, 2).unwrap().unwrap() - 0.4).abs() < 1e-12);
/// assert_eq!(effect(&output, &labels, 1, 3).unwrap(), None);
/// ```
pub fn effect(output: &Image, labels: &Labels, lighter: u16, darker: u16) -> Result<Option<f64>> {
    labels.check_same_size("the target mask is", output, "the model output is")?;
    let (mut a, mut na, mut b, mut nb) = (0.0, 0usize, 0.0, 0usize);
    for (&l, &v) in labels.data().iter().zip(output.data()) {
        if l == lighter {
            a += v;
            na += 1;
        } else if l == darker {
            b += v;
            nb += 1;
        }
    }
    Ok((na > 0 && nb > 0).then_some(a / na.max(1) as f64 - b / nb.max(1) as f64))
}

/// The ranks of `values` from 1, ties given the mean of the ranks they span.
///
/// ```
/// use shadelab_analysis::lightness::benchmark::ranks;
/// assert_eq!(ranks(&[3.0, 1.0, 3.0, 2.0]), vec![3.5, 1.0, 3.5, 2.0]);
/// ```
pub fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&i, &j| values[i].total_cmp(&values[j]));
    let mut out = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        let rank = (start + 1 + end) as f64 / 2.0;
        for &i in &order[start..end] {
            out[i] = rank;
        }
        start = end;
    }
    out
}

/// Spearman's rank correlation of paired `x` and `y`: Pearson's correlation of their ranks
/// (ties averaged). `None` with fewer than 3 pairs, unequal lengths, or when either side is
/// constant.
///
/// ```
/// use shadelab_analysis::lightness::benchmark::spearman;
/// assert_eq!(spearman(&[1.0, 2.0, 3.0], &[10.0, 20.0, 90.0]), Some(1.0));
/// assert_eq!(spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]), Some(-1.0));
/// assert_eq!(spearman(&[1.0, 1.0, 1.0], &[3.0, 2.0, 1.0]), None);
/// ```
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 3 || x.iter().chain(y).any(|v| !v.is_finite()) {
        return None;
    }
    let (rx, ry) = (ranks(x), ranks(y));
    let n = rx.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    (sxx > 0.0 && syy > 0.0).then_some(sxy / (sxx * syy).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spearman_matches_the_textbook_formula_without_ties() {
        // Without ties ρ = 1 − 6 Σd² / (n(n² − 1)).
        let x = [0.3, 1.2, -0.5, 2.2, 0.9, 1.1];
        let y = [5.0, 3.0, 1.0, 9.0, 4.0, 8.0];
        let (rx, ry) = (ranks(&x), ranks(&y));
        let d2: f64 = rx.iter().zip(&ry).map(|(a, b)| (a - b) * (a - b)).sum();
        let n = x.len() as f64;
        let textbook = 1.0 - 6.0 * d2 / (n * (n * n - 1.0));
        assert!((spearman(&x, &y).unwrap() - textbook).abs() < 1e-12);
        // Invariant under any increasing transform of either side.
        let y3: Vec<f64> = y.iter().map(|v: &f64| v.powi(3) - 7.0).collect();
        assert_eq!(spearman(&x, &y), spearman(&x, &y3));
        assert_eq!(spearman(&x[..2], &y[..2]), None);
    }
}
