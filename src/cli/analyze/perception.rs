//! The flags `analyze prior-sweep` and `analyze observer` share: the picture and how to
//! interpret it, turned into the library's [`shadelab::pipeline::perception::Config`].

use super::{CliError, Global, RenderSize, Source};
use crate::cli::flags::{usage, AnalysisFlags, SolverFlags};
use shadelab::pipeline::perception::{Config, Header};

/// The picture and how to interpret it.
#[derive(Debug, clap::Args)]
pub struct PictureArgs {
    #[command(flatten)]
    pub source: Source,
    #[command(flatten)]
    size: RenderSize,
    #[command(flatten)]
    pub analysis: AnalysisFlags,
    #[command(flatten)]
    pub solver: SolverFlags,
    /// The reconstruction method, as `solve --method` names them (default multigrid,
    /// Ikeuchi–Horn; docs/perception.md says why the analyses keep it).
    #[arg(long, value_name = "METHOD")]
    pub method: Option<String>,
}

/// The first line of a perception summary: the assumed slant, albedo and ambient, and the true
/// light when the stimulus or the image's sidecar gives it.
pub fn true_light_line(header: &Header) -> String {
    let p = &header.parameters;
    let mut line = format!(
        "assumed: slant {:.1}°, albedo {:.4}, ambient {:.4}",
        p.slant_deg, p.albedo, p.ambient
    );
    if let Some(t) = &header.true_light {
        line += &format!(
            "; true light: tilt {:.1}° slant {:.1}°",
            t.tilt_deg, t.slant_deg
        );
    }
    line + "\n"
}

impl PictureArgs {
    /// The library's configuration, from the flags (not yet checked as a whole).
    pub fn config(&self, global: &Global) -> Result<Config, CliError> {
        let mut config = Config::new(self.source.to_library(global)?);
        config.size = self.size.get()?;
        config.domain = self.analysis.domain()?;
        config.boundary = self.analysis.boundary()?;
        config.slant_deg = self.analysis.slant;
        config.albedo = self.analysis.albedo;
        config.ambient = self.analysis.ambient;
        self.solver.apply(&mut config.solver)?;
        if let Some(method) = &self.method {
            config.solver.method = method.parse().map_err(|e| usage("--method", e))?;
        }
        Ok(config)
    }
}
