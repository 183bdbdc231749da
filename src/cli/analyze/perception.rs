//! The flags `analyze prior-sweep` and `analyze observer` share: the picture and how to
//! interpret it, turned into the library's [`shadelab::pipeline::perception::Config`].

use super::{CliError, Global, Source};
use crate::cli::flags::{AnalysisFlags, SolverFlags};
use shadelab::pipeline::perception::Config;
use shadelab::visual_size::parse_pair;

/// The picture and how to interpret it.
#[derive(Debug, clap::Args)]
pub struct PictureArgs {
    #[command(flatten)]
    pub source: Source,
    /// Size of the rendered stimulus in pixels: N (square) or WxH (with --stimulus).
    #[arg(
        long,
        value_name = "N|WxH",
        requires = "stimulus",
        allow_hyphen_values = true
    )]
    pub size: Option<String>,
    #[command(flatten)]
    pub analysis: AnalysisFlags,
    #[command(flatten)]
    pub solver: SolverFlags,
}

impl PictureArgs {
    /// The library's configuration, from the flags (not yet checked as a whole).
    pub fn config(&self, global: &Global) -> Result<Config, CliError> {
        let mut config = Config::new(self.source.to_library(global)?);
        config.size = match &self.size {
            Some(text) => Some(parse_pair(text, "--size").map_err(CliError::from)?),
            None => None,
        };
        config.domain = self.analysis.domain()?;
        config.boundary = self.analysis.boundary()?;
        config.slant_deg = self.analysis.slant;
        config.albedo = self.analysis.albedo;
        config.ambient = self.analysis.ambient;
        self.solver.apply(&mut config.solver);
        Ok(config)
    }
}
