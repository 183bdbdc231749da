//! Shards: which of a study's points one machine runs.

use crate::error::{Error, Result};
use serde::Serialize;

/// Which part of a study to run: shard `index` of `count` (0 ≤ index < count).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Shard {
    /// This shard, from 0.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// The whole study.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (e.g. `$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`).
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = |why: &str| {
            Error::invalid(format!(
                "shard '{text}': {why} (give I/N with 0 ≤ I < N, e.g. 0/4)"
            ))
        };
        let (i, n) = text.trim().split_once('/').ok_or_else(|| bad("no '/'"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| bad("I is not a whole number"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if count == 0 {
            return Err(bad("N must be at least 1"));
        }
        if index >= count {
            return Err(bad(&format!("shard {index} does not exist among {count}")));
        }
        Ok(Shard { index, count })
    }

    /// Whether this shard runs point `index`.
    pub fn runs(&self, index: usize) -> bool {
        index % self.count == self.index
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition() {
        assert_eq!(Shard::parse("2/4").unwrap(), Shard { index: 2, count: 4 });
        for bad in ["3/2", "2/2", "0/0", "1", "a/b", "-1/3", "1/x"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.starts_with("shard '") && e.contains(bad), "{e}");
        }
        let shards: Vec<Shard> = (0..3).map(|i| Shard { index: i, count: 3 }).collect();
        for p in 0..10 {
            assert_eq!(shards.iter().filter(|s| s.runs(p)).count(), 1);
        }
    }
}
